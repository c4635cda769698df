// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// Stereo GCPs (paper §4.1) for calibrated, non-rectified views (Strecha's fountain-P11, the
// synthetic scenes): each neighbour is rectified with the reference, the rectified pair goes
// through ExtractStereoGcps, the matches are triangulated back to reference pixels, and a GCP is
// kept only when another neighbour's pair confirms its depth ("a consistency check against
// neighbour views").

#include <string>
#include <vector>

#include "gcpstereo/core/labels.h"
#include "gcpstereo/core/progress.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/cost/plane_sweep.h"
#include "gcpstereo/gcp/gcp_sources.h"
#include "gcpstereo/gcp/stereo_gcps.h"

namespace gcpstereo::gcp {

// One rectified reference–neighbour pair.
struct CalibratedPairSummary {
  std::string neighbor;
  double baseline = 0.0;     // |C_ref − C_nb|, data set unit
  double focal_px = 0.0;     // f of the rectified pair
  bool mirrored = false;     // neighbour left of the reference: images flipped horizontally
  int min_disparity_px = 0;  // searched range in the rectified pair
  int max_disparity_px = 0;
  int num_matches = 0;    // ExtractStereoGcps GCPs of the pair
  int num_invalid = 0;    // a matched pixel outside one of the source images
  int num_projected = 0;  // distinct reference pixels after the z-buffer
  int num_confirmed = 0;  // of those, confirmed by enough other pairs
  double seconds = 0.0;
};

struct CalibratedStereoGcpResult {
  GcpSet gcps;  // source kStereo, raster order, one per reference pixel
  std::vector<CalibratedPairSummary> pairs;
  GcpSourceSummary summary;  // source "stereo"; num_input = sum of projected, num_inconsistent =
                             // not confirmed
  double seconds = 0.0;
};

// For each of the options.max_neighbors neighbours nearest to the reference (camera centres; ties:
// list order) n:
//  1. rectify (reference, n) with cv::stereoRectify (zero distortion, alpha = 1, the input size,
//     CALIB_ZERO_DISPARITY); relative pose from the Cameras: R = R_nᵀ R_ref, T = R_nᵀ (C_ref − C_n)
//     (R = camera-to-world rotation). When n is left of the reference the rectified images are
//     mirrored so that the reference is the left view with positive disparities;
//  2. disparity range d = f·B / z for z in [min_depth, max_depth] (widened by 10 % and 2 px for
//     the rectifying rotation), then ExtractStereoGcps(options);
//  3. each match (x_r, y_r, d) → point X = (x_r − c_x, y_r − c_y, f)·(B/d) in the rectified
//     reference frame → the reference camera frame (R_rectᵀ X) → projected to the nearest
//     reference pixel; depth = its z; σ_z = z² σ_d / (f B), σ_d = sigma_px; nearest point wins a
//     pixel (ties: first match in raster order). Matches whose rectified pixel falls outside either
//     source image are dropped.
// Consistency: every pair's dense NCC winner-take-all map is projected to the reference grid the
// same way (z-buffer). A pixel's GCP from pair i is kept when at least min_confirmations other
// pairs have a WTA depth within confirm_radius_px with |z_i − z_j| <= confirm_sigma·sqrt(σ_i² +
// σ_j²) — an independent match in another view agrees. (Deviation: confirming by the other
// pairs' GCPs proved too sparse: both sets are a few % of the pixels.) Among the kept
// GCPs of one pixel the one with the smallest σ wins (ties: lower pair index).
// Throws Error when there is no neighbour, a camera is invalid or images differ in size from their
// cameras, the depth range is not 0 < min < max, or a neighbour's centre coincides with the
// reference's; ConfigError from options.Check(). A pair whose disparity range is empty (too short
// a baseline) is reported in its summary with no matches, not thrown.
CalibratedStereoGcpResult ExtractCalibratedStereoGcps(const View& reference,
                                                      const std::vector<View>& neighbors,
                                                      double min_depth, double max_depth,
                                                      const StereoGcpOptions& options,
                                                      const ProgressCallback& progress = nullptr);

// What RefineGcpsOnLabels did.
struct GcpRefinementSummary {
  int input = 0;
  int refined = 0;                 // kept, with the depth of the cost's minimum
  int dropped_at_edge = 0;         // the minimum lay on the search window's edge: not bracketed
  int dropped_no_data = 0;         // no neighbour saw the window at some searched label
  double mean_shift_labels = 0.0;  // mean |new − old| label of the refined GCPs
  double seconds = 0.0;
};

// Re-estimates the depth of stereo GCPs of calibrated views with the plane-sweep cost Φ of the
// processing resolution (ComputePlaneSweepCostForRegions with `sweep`, pixel-wise): matches made at
// options.image_scale < 1 are a few depth labels off, since a disparity step of the small images
// spans several labels. A stereo GCP's σ is z²·sigma_px / (f·B) (ExtractCalibratedStereoGcps), so
// its match had the disparity d = f·B / z with f·B = z²·sigma_px / σ. For GCP g at pixel p:
//   the search interval is the labels between the depths f·B / (d + radius_px) and
//   f·B / (d − radius_px) (+∞ when d <= radius_px), rounded outward, within the label range;
//   C(l) = sum of Φ(q, l) over the window_px × window_px square around p (clipped to the image);
//   l* = argmin C(l) over the interval (ties: lower label);
//   a parabola through C(l* − 1), C(l*), C(l* + 1) gives the sub-label offset (clamped to ±0.5);
//   g.depth = labels.DepthOfLabel(l* + offset), g.sigma = half the depth step there.
// A GCP whose l* lies on the edge of its interval (and not on the label range's end) is dropped:
// the minimum is not bracketed, so the match was farther off than the search. So is one whose
// window has no data at a searched label, or whose σ is not positive. Order is kept; GCPs of other
// sources pass through unchanged. Throws what the sweep throws, Error for radius_px <= 0,
// sigma_px <= 0 or an even or non-positive window.
GcpSet RefineGcpsOnLabels(const GcpSet& gcps, const View& reference,
                          const std::vector<View>& neighbors, const LabelSpace& labels,
                          double radius_px, double sigma_px, int window_px,
                          const cost::PlaneSweepOptions& sweep,
                          GcpRefinementSummary* summary = nullptr);

}  // namespace gcpstereo::gcp
