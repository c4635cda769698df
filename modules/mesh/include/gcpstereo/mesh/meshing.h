// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/types.h"

namespace gcpstereo::mesh {

// Options of the depth-map triangulation (MeshFromDepthMap). YAML keys mesh.*. Not in the paper:
// the mesh is an output format (the paper shows depth maps only).
struct MeshingOptions {
  // How the two discontinuity tests below were set: the exact depth map of the synthetic "small"
  // courtyard (640×427, f = 575 px) meshed with both tests off gives 535 510 faces; for each, the
  // relative error between the face's plane and the true surface along the ray through its
  // centroid separates faces on a surface (error < 0.5 %) from faces bridging a depth step. With
  // the defaults, 20 of the 529 301 faces with error < 0.5 % are dropped and 4 of the 4 929 faces
  // with error > 2 % are kept (meshing_test.cpp, ExactDepthMapCriteria, checks the same on
  // "tiny"). Real surfaces stay below 86° there; bridging faces are mostly above 87°, and every
  // face above a ratio of 0.05 bridges a step.
  //
  // [mesh.max_depth_ratio] Depth-ratio test: a triangle is dropped when max/min of its three
  // vertex depths exceeds 1 + max_depth_ratio. Dimensionless, per grid cell (a slanted surface's
  // ratio grows with mesh.stride and falls with the resolution). 0 turns the test off.
  // Valid: [0, 10]. Default 0.05: an occluding edge between surfaces more than 5 % apart in depth
  // (a column 7 m in front of a wall 9 m away: 29 %) is always cut, whatever the slant.
  double max_depth_ratio = 0.05;
  // [mesh.max_view_angle_deg] Slant test: a triangle is dropped when the angle between its normal
  // and the viewing ray (camera centre → triangle centroid) exceeds this, in degrees. A triangle
  // that bridges a depth step is nearly parallel to the ray, so this catches the small steps the
  // ratio test lets through, at any depth. It also removes real surfaces seen at more than this
  // angle (poorly measured anyway), and on a noisy or label-quantised depth map, cells where the
  // depth jumps by much more than the pixel footprint. Valid: (0, 90]; 90 turns the test off
  // (a triangle of the pixel grid is never seen exactly edge-on). Default 86.
  double max_view_angle_deg = 86.0;
  // [mesh.stride] Grid spacing, in pixels: the mesh nodes are the pixels whose column and row are
  // multiples of the stride, plus the last column and row (so the mesh covers the whole image).
  // 1 = one vertex per valid pixel. Valid: [1, 1024].
  int stride_px = 1;

  // Throws ConfigError naming the YAML key, value and violated bound.
  void Check() const;
};

// What a triangulation did (for the log and report.json). Every grid cell offers two candidate
// triangles: candidate_faces = faces + dropped_invalid + dropped_depth_ratio + dropped_view_angle.
struct MeshingSummary {
  int grid_cols = 0;                     // grid nodes per row
  int grid_rows = 0;                     // grid nodes per column
  std::int64_t valid_nodes = 0;          // grid nodes with a valid depth
  std::int64_t vertices = 0;             // vertices of the mesh (valid nodes used by a face)
  std::int64_t isolated_nodes = 0;       // valid nodes used by no face (not in the mesh)
  std::int64_t faces = 0;                // triangles of the mesh
  std::int64_t candidate_faces = 0;      // 2 per grid cell
  std::int64_t dropped_invalid = 0;      // candidates with an invalid (unknown-depth) corner
  std::int64_t dropped_depth_ratio = 0;  // failed mesh.max_depth_ratio
  std::int64_t dropped_view_angle = 0;   // passed the ratio test, failed mesh.max_view_angle_deg
  double seconds = 0.0;                  // wall-clock time

  std::string FullReport() const;
};

// Triangulates a depth map over its pixel grid into a mesh in WORLD coordinates.
//
// depth: CV_32F depth along the camera's z (camera.width × camera.height); a pixel is valid when
//   IsValidDepth() (finite and > 0), +inf (kInvalidDepth) marks unknown pixels.
// image_bgr: CV_8UC3 (BGR) or CV_8UC1 image of the same size giving the vertex colours (stored as
//   RGB 0…255 in TriangleMesh::colors, the colour of the node's pixel; no averaging when
//   stride > 1), or an empty Mat for a mesh without colours.
// camera: the camera of the depth map; each valid node (col, row) becomes the vertex
//   camera.BackProject((col, row), depth) (the pixel-centre convention of core/camera.h).
//
// Triangulation: each grid cell with corners TL, TR, BL, BR is split along the diagonal whose two
// depths differ less (TL–BR on ties) into two triangles; a cell with exactly three valid corners
// gives the triangle of those three; a triangle is dropped when it fails the discontinuity tests
// of MeshingOptions (ratio test first, then the angle test; each drop counted once, under the first
// test it fails). Nodes that no face uses are left out. Faces are counter-clockwise as seen from
// the camera (in the image: TL → BL → TR), so their right-hand normals point toward the camera —
// "outside" for a surface seen from that camera, as TriangleMesh expects.
//
// Order: vertices in raster order of their nodes, faces in raster order of their cells (TL–BR
// cells: the lower-left triangle first). The output bytes do not depend on the thread count.
// Throws Error naming the argument for a depth map of the wrong type or size, an image of the
// wrong type or size, or an invalid camera.
TriangleMesh MeshFromDepthMap(const cv::Mat& depth, const cv::Mat& image_bgr, const Camera& camera,
                              const MeshingOptions& options, MeshingSummary* summary = nullptr);

// The valid nodes of the same grid (every stride_px-th pixel plus the last column and row) as
// world points, in raster order, for the optional point-cloud export (io::WritePointCloudPly).
// Positions only: PointCloud has no colour channel (see ColoredPointsFromDepthMap).
// Throws as MeshFromDepthMap (and ConfigError naming mesh.stride for stride_px < 1).
PointCloud PointCloudFromDepthMap(const cv::Mat& depth, const Camera& camera, int stride_px = 1);

// The same points with their colours, as a TriangleMesh without faces (io::WriteMeshPly writes it
// as a coloured point cloud that MeshLab and CloudCompare read). image_bgr as in MeshFromDepthMap.
TriangleMesh ColoredPointsFromDepthMap(const cv::Mat& depth, const cv::Mat& image_bgr,
                                       const Camera& camera, int stride_px = 1);

// Unit vertex normals in the mesh's frame, one per vertex: the face normals around each vertex
// weighted by the face's angle at that vertex (Thürmer & Wüthrich 1998; unlike area weights,
// independent of how a surface is split into triangles). Zero for a vertex that only degenerate
// faces (or none) use. Used for the renderer's smooth shading and the OBJ export's normals.
std::vector<Eigen::Vector3f> VertexNormals(const TriangleMesh& mesh);

}  // namespace gcpstereo::mesh
