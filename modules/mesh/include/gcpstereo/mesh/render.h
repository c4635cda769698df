// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/types.h"

namespace gcpstereo::mesh {

// Options of the software mesh renderer (previews for a person to look at). YAML keys
// mesh.preview.*. Not in the paper.
struct MeshRenderOptions {
  // [mesh.preview.mode] What a pixel shows: "color" (the interpolated vertex colours, unlit),
  // "shaded" (a grey surface lit by a headlight: shows the 3D shape) or "color_shaded" (vertex
  // colours × headlight shading).
  std::string mode = "color_shaded";
  // [mesh.preview.ambient] Lighting: shade = ambient + (1 − ambient) · |n · d|, with n the unit
  // surface normal and d the unit ray of the pixel (a headlight at the camera centre; two-sided,
  // so back faces are lit too). Fraction, valid [0, 1].
  double ambient = 0.25;
  // [mesh.preview.crease_angle_deg] Normals: each face corner takes its vertex's normal (the
  // mean of the face normals around it, weighted by their angles at the vertex), interpolated per
  // pixel (Phong), unless that normal is more than this angle from the face's own normal — a sharp
  // edge, where the corner keeps the face normal, so boxes stay boxes while tessellated curves look
  // smooth. Degrees, valid [0, 180]; 0 = flat shading (one normal per face: shows every facet), 180
  // = smooth everywhere.
  double crease_angle_deg = 40.0;
  // [mesh.preview.supersampling] Anti-aliasing: s × s samples per pixel (rendered at s times the
  // size with camera.Rescaled(s), then box-filtered). Valid [1, 4].
  int supersampling = 2;
  // [mesh.preview.cull_back_faces] Skip faces seen from behind (clockwise on screen). Faces of a
  // depth-map mesh are counter-clockwise seen from the camera that made them (meshing.h).
  bool cull_back_faces = false;
  // [mesh.preview.background_grey] Grey level of pixels no face covers, 0…255 (dark grey).
  int background_grey = 48;
  // [mesh.preview.surface_grey] Grey level (0…255) of a mesh without vertex colours, and of the
  // surface in "shaded" mode.
  int surface_grey = 210;

  // Throws ConfigError naming the YAML key, value and violated bound.
  void Check() const;
};

// A rendering and its buffers.
struct MeshRenderResult {
  cv::Mat image;  // CV_8UC3 BGR, camera.height × camera.width
  // CV_32F camera z of the nearest face at each pixel centre, +inf where no face. With
  // supersampling s > 1: the minimum over the pixel's s × s samples.
  cv::Mat depth;
  // CV_32S index of the face seen at the pixel (of the sample giving `depth`), −1 where none.
  cv::Mat face_index;
  std::int64_t faces_drawn = 0;     // faces that reached the rasteriser (some may cover no sample)
  std::int64_t faces_culled = 0;    // back faces skipped (cull_back_faces)
  std::int64_t faces_skipped = 0;   // a non-finite vertex, or zero area on screen
  std::int64_t faces_clipped = 0;   // crossed the near plane or the guard band (drawn in part)
  std::int64_t covered_pixels = 0;  // pixels with a face (face_index >= 0)
  // Samples inside some face, counted once per face before the depth test (at the supersampled
  // resolution): equals the covered samples for a mesh whose faces do not overlap on screen;
  // the excess is overdraw.
  std::int64_t samples_rasterised = 0;
  double seconds = 0.0;
};

// Renders `mesh` (world coordinates) as seen by `camera`: z-buffered rasterisation of every face.
//
// Rasterisation: vertices are projected once and snapped to 1/256 pixel; a pixel (col, row) is
// sampled at its centre (col, row) (core/camera.h) and covered by a triangle when the exact
// integer edge functions say so, with a tie rule for samples exactly on an edge or vertex (the
// sample belongs to the face containing the point just right of and below it): neighbouring
// faces leave no gap and cover no sample twice. Faces reaching behind the camera (camera z below
// 1e-6 mesh units) or far outside the image (beyond a guard band of max(width, height) pixels
// on every side) are clipped in the camera frame, so large faces (a ground plane) are drawn
// correctly from anywhere. Depth is where the pixel ray meets the face's plane (computed from the
// unsnapped vertices, so exact at every sample); colours and normals are interpolated with the
// barycentrics of that point (perspective-correct). The nearest face wins; on equal depth the face
// listed first. Lighting uses the world-frame face or vertex normals; faces are two-sided unless
// cull_back_faces. Rows are rasterised in parallel (TBB) over fixed bands of rows, each band going
// through the faces in mesh order, so the bytes do not depend on the thread count. Throws Error for
// an invalid camera, colours not one per vertex, a face index out of range, or more than 131072
// samples (camera size × supersampling) per side.
MeshRenderResult RenderMesh(const TriangleMesh& mesh, const Camera& camera,
                            const MeshRenderOptions& options);

// RenderMesh(...).image.
cv::Mat RenderMeshPreview(const TriangleMesh& mesh, const Camera& view_camera,
                          const MeshRenderOptions& options);

// The camera `reference` moved on a sphere around `pivot` (world point), still looking the same
// way relative to the pivot (a turntable view): pitched by pitch_deg about the reference camera's
// left axis (−x), then turned by yaw_deg about its up axis (−y), both through the pivot. Positive
// yaw moves the camera to its right (the scene is seen more from the right), positive pitch moves
// it up (looking down more).
// Intrinsics and size are kept. With both angles 0 it is `reference` (up to rounding of the
// centre).
Camera OrbitCamera(const Camera& reference, double yaw_deg, double pitch_deg,
                   const Eigen::Vector3d& pivot);

// The component-wise median of the mesh's vertices: a robust pivot for OrbitCamera. Throws Error
// for a mesh without vertices.
Eigen::Vector3d MedianVertex(const TriangleMesh& mesh);

}  // namespace gcpstereo::mesh
