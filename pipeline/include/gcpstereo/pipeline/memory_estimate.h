// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// A view's peak memory, estimated before the propagation system, the cost volumes and the max-flow
// graphs are allocated, from what they allocate (image size, labels, neighbours, tiles, threads),
// so that a run too large for the machine is refused instead of being killed by the kernel.
#pragma once

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace gcpstereo::pipeline {

struct PipelineConfig;

// What a view's peak depends on.
struct ViewMemoryInput {
  int width_px = 0, height_px = 0;                        // the reference at dataset.scale
  int labels = 0;                                         // labels.count (once known)
  int neighbors = 0;                                      // matched views besides the reference
  int tile_rows = 1, tile_cols = 1, tile_overlap_px = 0;  // optimizer.tiles, tile_overlap
  int threads = 1;  // tiles solved at once (runtime.threads; 0 = all cores)
  std::string propagation = "linear_system";  // propagation.method
  std::string solver = "cholmod";             // propagation.solver
  std::string refinement = "irls";            // optimizer.refinement
  bool window_filter = false;  // the cost's window aggregation (cost.window_px or sweep_ > 1)
  // The process's resident memory when the estimate is made (images, GCPs, libraries): replaces
  // the base and views terms when > 0 (a run knows it; a plan before the run does not).
  double resident_bytes = 0.0;
  bool has_gcps = true;  // no GCPs: no propagation
  bool optimize = true;  // false when the run stops after the propagation
  // optimizer.left_right_check: the neighbour's own solve (its D̂, then its tiles) runs alongside
  // the reference's D̂ and tiles.
  bool left_right_check = false;
};

// The estimate, in bytes, with its parts (report.json "memory_estimate").
struct MemoryEstimate {
  double base_bytes = 0.0;   // the process with its libraries loaded (or its resident memory)
  double views_bytes = 0.0;  // the reference's and neighbours' images (0 with resident memory)
  double propagation_bytes = 0.0;   // D̂'s solve (the sparse system and its factor)
  double optimization_bytes = 0.0;  // the tiles solved at once: cost volumes, graphs, buffers
  double partner_bytes = 0.0;  // the left-right check's second solve, alongside (as large again)
  int concurrent_tiles = 0;
  double tile_pixels = 0.0;  // the largest tile's, with its overlap
  // The propagation's and the optimisation's memory is released between them: the peak is the
  // larger of the two on top of the base and the views, plus the left-right check's partner.
  double total_bytes() const;
  nlohmann::json ToJson() const;
};

ViewMemoryInput ViewMemoryInputOf(const PipelineConfig& options, int width_px, int height_px,
                                  int labels, int neighbors);
MemoryEstimate EstimateViewMemory(const ViewMemoryInput& input);

// This process's resident memory now, from /proc/self/statm (0 when it cannot be read).
double ResidentMemoryBytes();

// Returns the heap memory that is free but still held by the allocator to the system (glibc's
// malloc_trim; nothing elsewhere). A scene run calls it before it measures the resident memory of
// its next view: freed cost volumes and graphs of the views before would otherwise count in that
// view's base and inflate its estimate (fountain-P11 scene: 4.5 GB estimated for a 2.8 GB peak).
void ReleaseFreedHeapMemory();

// /proc/meminfo's MemAvailable in bytes (0 when it cannot be read).
double AvailableMemoryBytes();

// The budget: runtime.max_memory_gb when set (> 0), else the machine's available memory (0 when
// neither is known: no check).
double MemoryBudgetBytes(double max_memory_gb);

// Throws gcpstereo::Error (one line naming optimizer.tiles, dataset.scale and labels.count) when
// `estimate` exceeds MemoryBudgetBytes(max_memory_gb).
void CheckMemoryBudget(const MemoryEstimate& estimate, double max_memory_gb);

}  // namespace gcpstereo::pipeline
