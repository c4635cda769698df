// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/mesh/render.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/mesh/meshing.h"
#include "test_scenes.h"

namespace gcpstereo::mesh {
namespace {

using Color = Eigen::Matrix<std::uint8_t, 3, 1>;

Camera PinholeCamera(int width, int height, double focal_px, double cx, double cy) {
  Camera camera;
  camera.K << focal_px, 0.0, cx, 0.0, focal_px, cy, 0.0, 0.0, 1.0;
  camera.width = width;
  camera.height = height;
  return camera;
}

// The world point of `camera` seen at pixel (u, v) at depth z.
Eigen::Vector3f At(const Camera& camera, double u, double v, double z) {
  return camera.BackProject(Eigen::Vector2d(u, v), z).cast<float>();
}

// A quad seen by `camera` with corners at pixels (u0, v0)–(u1, v1), depth z, one colour;
// faces counter-clockwise as seen (the layout MeshFromDepthMap uses): 0 TL, 1 TR, 2 BL, 3 BR.
TriangleMesh Quad(const Camera& camera, double u0, double v0, double u1, double v1, double z,
                  const Color& rgb) {
  TriangleMesh mesh;
  mesh.vertices = {At(camera, u0, v0, z), At(camera, u1, v0, z), At(camera, u0, v1, z),
                   At(camera, u1, v1, z)};
  mesh.colors.assign(4, rgb);
  mesh.faces = {Eigen::Vector3i(0, 2, 3), Eigen::Vector3i(0, 3, 1)};
  return mesh;
}

bool SameBytes(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

MeshRenderOptions ColorOnly() {
  MeshRenderOptions options;
  options.mode = "color";
  options.supersampling = 1;
  return options;
}

TEST(RenderMeshTest, QuadCoversExactlyThePixelCentresInsideIt) {
  const Camera camera = PinholeCamera(64, 48, 100.0, 31.5, 23.5);
  const TriangleMesh quad = Quad(camera, 10.5, 8.5, 40.5, 30.5, 10.0, Color(200, 100, 50));
  const MeshRenderResult result = RenderMesh(quad, camera, ColorOnly());
  ASSERT_EQ(result.image.type(), CV_8UC3);
  ASSERT_EQ(result.image.size(), cv::Size(64, 48));
  EXPECT_EQ(result.covered_pixels, 30 * 22);
  // The shared diagonal passes exactly through pixels (18, 14) and (33, 25): each is drawn once.
  EXPECT_EQ(result.samples_rasterised, 30 * 22);
  EXPECT_EQ(result.faces_drawn, 2);
  EXPECT_EQ(result.faces_skipped, 0);
  for (int row = 0; row < 48; ++row) {
    for (int col = 0; col < 64; ++col) {
      const bool inside = col >= 11 && col <= 40 && row >= 9 && row <= 30;
      if (!inside) {
        EXPECT_EQ(result.image.at<cv::Vec3b>(row, col), cv::Vec3b(48, 48, 48));
        EXPECT_EQ(result.depth.at<float>(row, col), std::numeric_limits<float>::infinity());
        EXPECT_EQ(result.face_index.at<int>(row, col), -1);
        continue;
      }
      EXPECT_EQ(result.image.at<cv::Vec3b>(row, col), cv::Vec3b(50, 100, 200)) << col << "," << row;
      EXPECT_NEAR(result.depth.at<float>(row, col), 10.0, 1e-5);
      // Face 0 is below the diagonal TL–BR: (row − 8.5)·30 > (col − 10.5)·22.
      const int side = 15 * row - (11 * col + 12);  // ×2 of the inequality, in integers
      const int face = result.face_index.at<int>(row, col);
      if (side > 0) {
        EXPECT_EQ(face, 0) << col << "," << row;
      } else if (side < 0) {
        EXPECT_EQ(face, 1) << col << "," << row;
      } else {
        EXPECT_TRUE(face == 0 || face == 1);
      }
    }
  }
}

TEST(RenderMeshTest, JitteredGridHasNoGapAndNoOverlap) {
  // A 12 × 9 grid of 4-px cells whose interior vertices are moved by multiples of 1/4 px (so that
  // many vertices and edges pass exactly through pixel centres), at random depths.
  const int cells_x = 12, cells_y = 9, spacing = 4;
  const Camera camera =
      PinholeCamera(cells_x * spacing + 1, cells_y * spacing + 1, 80.0, 20.0, 15.0);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> jitter(-3, 3);
  std::uniform_real_distribution<double> depth(5.0, 6.0);
  TriangleMesh mesh;
  for (int r = 0; r <= cells_y; ++r) {
    for (int c = 0; c <= cells_x; ++c) {
      const bool border = r == 0 || c == 0 || r == cells_y || c == cells_x;
      const double u = c * spacing + (border ? 0.0 : 0.25 * jitter(rng));
      const double v = r * spacing + (border ? 0.0 : 0.25 * jitter(rng));
      mesh.vertices.push_back(At(camera, u, v, depth(rng)));
    }
  }
  for (int r = 0; r < cells_y; ++r) {
    for (int c = 0; c < cells_x; ++c) {
      const int tl = r * (cells_x + 1) + c, tr = tl + 1, bl = tl + cells_x + 1, br = bl + 1;
      if ((r + c) % 2 == 0) {
        mesh.faces.emplace_back(tl, bl, br);
        mesh.faces.emplace_back(tl, br, tr);
      } else {
        mesh.faces.emplace_back(tl, bl, tr);
        mesh.faces.emplace_back(tr, bl, br);
      }
    }
  }
  for (const bool reversed : {false, true}) {
    TriangleMesh m = mesh;
    if (reversed) {
      for (Eigen::Vector3i& f : m.faces) std::swap(f[1], f[2]);
    }
    const MeshRenderResult result = RenderMesh(m, camera, ColorOnly());
    for (int row = 1; row < camera.height - 1; ++row) {
      for (int col = 1; col < camera.width - 1; ++col) {
        EXPECT_GE(result.face_index.at<int>(row, col), 0) << "gap at " << col << "," << row;
      }
    }
    EXPECT_EQ(result.samples_rasterised, result.covered_pixels) << "overlap";
    EXPECT_GE(result.covered_pixels, (camera.width - 2) * (camera.height - 2));
  }
}

TEST(RenderMeshTest, DepthBufferReproducesTheMeshedDepthMap) {
  const synth::SyntheticScene& scene = testing::TinyScene();
  const View& view = scene.views[scene.reference_index];
  const cv::Mat& depth = scene.depth[scene.reference_index];
  MeshingSummary summary;
  const TriangleMesh mesh =
      MeshFromDepthMap(depth, view.image, view.camera, MeshingOptions(), &summary);
  const MeshRenderResult result = RenderMesh(mesh, view.camera, ColorOnly());
  const int valid = cv::countNonZero(depth < std::numeric_limits<float>::infinity());
  int checked = 0;
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      if (result.face_index.at<int>(row, col) < 0) continue;
      const float expected = depth.at<float>(row, col);
      ASSERT_TRUE(IsValidDepth(expected)) << col << "," << row;
      EXPECT_NEAR(result.depth.at<float>(row, col), expected, 1e-4 * expected) << col << "," << row;
      // Pixel centres are vertices, so the interpolated colour is the vertex's: the photo.
      EXPECT_EQ(result.image.at<cv::Vec3b>(row, col), view.image.at<cv::Vec3b>(row, col));
      ++checked;
    }
  }
  // Pixel centres are vertices. By the tie rule a vertex sample belongs to the face containing the
  // point just right of and below it: in its grid cell (the vertex is the cell's top-left corner),
  // the triangle whose top edge is horizontal. So exactly the top-left vertices of such faces are
  // covered; the others lie on the mesh's right or bottom border.
  cv::Mat expected_cover(depth.size(), CV_8U, cv::Scalar(0));
  for (const Eigen::Vector3i& f : mesh.faces) {
    cv::Point p[3];
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector2d pixel;
      double z = 0.0;
      ASSERT_TRUE(view.camera.Project(mesh.vertices[f[k]].cast<double>(), &pixel, &z));
      p[k] = cv::Point(static_cast<int>(std::lround(pixel.x())),
                       static_cast<int>(std::lround(pixel.y())));
    }
    for (int k = 0; k < 3; ++k) {
      const cv::Point& a = p[k];
      const cv::Point& b = p[(k + 1) % 3];
      const cv::Point& c = p[(k + 2) % 3];
      if (a.y == b.y && c.y > a.y) expected_cover.at<std::uint8_t>(a.y, std::min(a.x, b.x)) = 1;
    }
  }
  int mismatches = 0;
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      if ((expected_cover.at<std::uint8_t>(row, col) != 0) !=
          (result.face_index.at<int>(row, col) >= 0)) {
        ++mismatches;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GE(checked, valid * 9 / 10);  // measured: 15 980 of 16 829
  EXPECT_EQ(checked, result.covered_pixels);
}

// An independent check of the projection conventions: the generator's exact surface mesh,
// rendered from the reference camera, gives the ray-traced depth map.
TEST(RenderMeshTest, ExactSceneMeshReproducesTheRayTracedDepth) {
  const synth::SyntheticScene& scene = testing::TinyScene();
  const View& view = scene.views[scene.reference_index];
  const cv::Mat& depth = scene.depth[scene.reference_index];
  const MeshRenderResult result = RenderMesh(scene.mesh, view.camera, ColorOnly());
  int valid = 0, close = 0, coverage_mismatch = 0, histogram[5] = {0, 0, 0, 0, 0};
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      const float expected = depth.at<float>(row, col);
      // Covered exactly where the ray tracer found a surface (the sky stays empty).
      if (IsValidDepth(expected) != (result.face_index.at<int>(row, col) >= 0)) {
        ++coverage_mismatch;
      }
      if (!IsValidDepth(expected)) continue;
      ++valid;
      const double error = std::abs(result.depth.at<float>(row, col) - expected) / expected;
      if (error < 1e-3) ++close;
      ++histogram[error < 1e-4 ? 0 : error < 1e-3 ? 1 : error < 1e-2 ? 2 : error < 1e-1 ? 3 : 4];
    }
  }
  std::printf(
      "exact mesh vs ray-traced depth: %d valid, errors <1e-4 %d, <1e-3 %d, <1e-2 %d, "
      "<1e-1 %d, more %d\n",
      valid, histogram[0], histogram[1], histogram[2], histogram[3], histogram[4]);
  // Measured: 16 829 valid pixels, 16 763 within 1e-3 (the tessellation's 4 mm chord error is
  // ≈ 1e-3 at 5 m), 3 off by more than 1 % (silhouettes of thin posts).
  EXPECT_EQ(coverage_mismatch, 0);
  EXPECT_GE(close, valid * 99 / 100);
}

TEST(RenderMeshTest, HeadlightShadingFollowsTheSurfaceSlant) {
  const Camera camera = PinholeCamera(65, 49, 100.0, 32.0, 24.0);
  MeshRenderOptions options;
  options.supersampling = 1;
  options.ambient = 0.25;
  options.surface_grey = 200;
  // Fronto-parallel: |n·d| = 1 at the principal point.
  TriangleMesh quad = Quad(camera, 10.5, 8.5, 50.5, 40.5, 10.0, Color(200, 100, 50));
  options.mode = "shaded";
  EXPECT_EQ(RenderMeshPreview(quad, camera, options).at<cv::Vec3b>(24, 32),
            cv::Vec3b(200, 200, 200));
  // Turned by 60° about the vertical axis through (0, 0, 10): |n·d| = 0.5 at the principal point.
  const Eigen::AngleAxisf turn(static_cast<float>(M_PI / 3.0), Eigen::Vector3f::UnitY());
  for (Eigen::Vector3f& v : quad.vertices) {
    v = turn * (v - Eigen::Vector3f(0, 0, 10)) + Eigen::Vector3f(0, 0, 10);
  }
  for (const double crease_angle_deg : {180.0, 40.0, 0.0}) {
    options.crease_angle_deg = crease_angle_deg;
    options.mode = "shaded";
    const cv::Vec3b grey = RenderMeshPreview(quad, camera, options).at<cv::Vec3b>(24, 32);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(grey[k], 200 * (0.25 + 0.75 * 0.5), 1.0);
    options.mode = "color_shaded";
    const cv::Vec3b bgr = RenderMeshPreview(quad, camera, options).at<cv::Vec3b>(24, 32);
    EXPECT_NEAR(bgr[0], 50 * 0.625, 1.0);
    EXPECT_NEAR(bgr[1], 100 * 0.625, 1.0);
    EXPECT_NEAR(bgr[2], 200 * 0.625, 1.0);
    options.mode = "color";
    EXPECT_EQ(RenderMeshPreview(quad, camera, options).at<cv::Vec3b>(24, 32),
              cv::Vec3b(50, 100, 200));
  }
  // Without colours, "color" draws the surface grey.
  quad.colors.clear();
  options.mode = "color";
  EXPECT_EQ(RenderMeshPreview(quad, camera, options).at<cv::Vec3b>(24, 32),
            cv::Vec3b(200, 200, 200));
}

TEST(RenderMeshTest, CreaseAngleKeepsSharpEdgesSharp) {
  // A vertical ridge 10 m in front of the camera, its two wings turned 45° away on either side:
  // a 90° edge.
  const Camera camera = PinholeCamera(65, 49, 100.0, 32.0, 24.0);
  TriangleMesh ridge;
  ridge.vertices = {{0, -2, 10}, {0, 2, 10}, {2, -2, 12}, {2, 2, 12}, {-2, -2, 12}, {-2, 2, 12}};
  ridge.faces = {Eigen::Vector3i(0, 1, 3), Eigen::Vector3i(0, 3, 2), Eigen::Vector3i(4, 5, 1),
                 Eigen::Vector3i(4, 1, 0)};
  MeshRenderOptions options;
  options.mode = "shaded";
  options.supersampling = 1;
  auto grey_at = [&](double crease_angle_deg, int col) {
    options.crease_angle_deg = crease_angle_deg;
    return static_cast<int>(RenderMeshPreview(ridge, camera, options).at<cv::Vec3b>(24, col)[0]);
  };
  for (const int col : {30, 34}) {  // two pixels either side of the ridge
    const int flat = grey_at(0.0, col);
    EXPECT_NEAR(flat, 210 * (0.25 + 0.75 * std::sqrt(0.5)), 3.0);  // |n·d| ≈ cos 45°
    EXPECT_EQ(grey_at(40.0, col), flat);                           // 45° > 40°: the face normals
    EXPECT_GT(grey_at(50.0, col), flat + 30);  // 45° < 50°: the ridge's averaged normal
    EXPECT_EQ(grey_at(180.0, col), grey_at(50.0, col));
  }
}

TEST(RenderMeshTest, NearestFaceWinsAndBackFacesCanBeCulled) {
  const Camera camera = PinholeCamera(40, 30, 50.0, 19.5, 14.5);
  TriangleMesh far = Quad(camera, 5.5, 5.5, 30.5, 20.5, 8.0, Color(255, 0, 0));
  const TriangleMesh near = Quad(camera, 10.5, 10.5, 35.5, 25.5, 4.0, Color(0, 255, 0));
  TriangleMesh both = far;
  for (const Eigen::Vector3i& f : near.faces)
    both.faces.push_back(f + Eigen::Vector3i::Constant(4));
  both.vertices.insert(both.vertices.end(), near.vertices.begin(), near.vertices.end());
  both.colors.insert(both.colors.end(), near.colors.begin(), near.colors.end());
  MeshRenderResult result = RenderMesh(both, camera, ColorOnly());
  EXPECT_EQ(result.image.at<cv::Vec3b>(15, 20), cv::Vec3b(0, 255, 0));  // overlap: the near quad
  EXPECT_EQ(result.image.at<cv::Vec3b>(7, 7), cv::Vec3b(0, 0, 255));    // the far quad alone
  EXPECT_NEAR(result.depth.at<float>(15, 20), 4.0, 1e-5);
  EXPECT_GT(result.samples_rasterised, result.covered_pixels);  // overdraw counted

  // Reverse the far quad: seen from behind, it is culled on request.
  for (Eigen::Vector3i& f : far.faces) std::swap(f[1], f[2]);
  MeshRenderOptions options = ColorOnly();
  options.cull_back_faces = true;
  result = RenderMesh(far, camera, options);
  EXPECT_EQ(result.faces_culled, 2);
  EXPECT_EQ(result.covered_pixels, 0);
  options.cull_back_faces = false;
  result = RenderMesh(far, camera, options);
  EXPECT_EQ(result.faces_culled, 0);
  EXPECT_EQ(result.covered_pixels, 25 * 15);
}

TEST(RenderMeshTest, FacesReachingBehindTheCameraAreClipped) {
  // A ground plane 1 m below the camera (y = 1 in the camera frame, y down) from 100 m behind to
  // 200 m in front: rows below the horizon (row > cy) see it at depth f / (row − cy).
  const Camera camera = PinholeCamera(40, 30, 50.0, 19.5, 14.5);
  TriangleMesh ground;
  ground.vertices = {{-100, 1, 200}, {100, 1, 200}, {-100, 1, -100}, {100, 1, -100}};
  ground.faces = {Eigen::Vector3i(0, 2, 3), Eigen::Vector3i(0, 3, 1)};
  MeshRenderOptions options = ColorOnly();
  const MeshRenderResult result = RenderMesh(ground, camera, options);
  EXPECT_EQ(result.faces_clipped, 2);
  EXPECT_EQ(result.faces_drawn, 2);
  EXPECT_EQ(result.covered_pixels, 15 * 40);
  EXPECT_EQ(result.samples_rasterised, 15 * 40);
  for (int row = 0; row < 30; ++row) {
    for (int col = 0; col < 40; ++col) {
      if (row < 15) {
        EXPECT_EQ(result.face_index.at<int>(row, col), -1) << col << "," << row;
      } else {
        EXPECT_NEAR(result.depth.at<float>(row, col), 50.0 / (row - 14.5),
                    1e-5 * 50.0 / (row - 14.5))
            << col << "," << row;
      }
    }
  }
  // Seen from below, the plane is a back face: culled, clipped or not.
  options.cull_back_faces = true;
  EXPECT_EQ(RenderMesh(ground, camera, options).faces_culled, 0);  // seen from above: front
  for (Eigen::Vector3i& f : ground.faces) std::swap(f[1], f[2]);
  EXPECT_EQ(RenderMesh(ground, camera, options).faces_culled, 2);
  // A non-finite vertex makes its faces unusable.
  ground.vertices[3].x() = std::numeric_limits<float>::quiet_NaN();
  options.cull_back_faces = false;
  EXPECT_EQ(RenderMesh(ground, camera, options).faces_skipped, 2);
}

TEST(RenderMeshTest, SupersamplingAntiAliasesEdges) {
  const Camera camera = PinholeCamera(40, 30, 50.0, 19.5, 14.5);
  // Left edge at x = 10.0: pixel 10 (samples at 9.75 and 10.25) is half covered.
  const TriangleMesh quad = Quad(camera, 10.0, 5.5, 30.5, 20.5, 8.0, Color(200, 100, 50));
  MeshRenderOptions options = ColorOnly();
  options.supersampling = 2;
  const MeshRenderResult result = RenderMesh(quad, camera, options);
  ASSERT_EQ(result.image.size(), cv::Size(40, 30));
  EXPECT_EQ(result.image.at<cv::Vec3b>(10, 10),
            cv::Vec3b((48 + 50) / 2, (48 + 100) / 2, (48 + 200) / 2));
  EXPECT_EQ(result.image.at<cv::Vec3b>(10, 11), cv::Vec3b(50, 100, 200));
  EXPECT_EQ(result.image.at<cv::Vec3b>(10, 9), cv::Vec3b(48, 48, 48));
  EXPECT_NEAR(result.depth.at<float>(10, 10), 8.0, 1e-5);  // the nearest of the samples
  EXPECT_GE(result.face_index.at<int>(10, 10), 0);
  EXPECT_EQ(result.face_index.at<int>(10, 9), -1);
}

TEST(OrbitCameraTest, ZeroAnglesGiveTheReference) {
  const Camera reference = testing::TiltedCamera(64, 48, 60.0);
  const Eigen::Vector3d pivot = reference.WorldFromCamera(Eigen::Vector3d(0.3, -0.2, 7.0));
  const Camera orbit = OrbitCamera(reference, 0.0, 0.0, pivot);
  EXPECT_EQ(orbit.K, reference.K);
  EXPECT_EQ(orbit.world_from_camera_rotation, reference.world_from_camera_rotation);
  EXPECT_LT((orbit.center_world - reference.center_world).norm(), 1e-12);
  EXPECT_EQ(orbit.width, reference.width);
  EXPECT_EQ(orbit.height, reference.height);
}

TEST(OrbitCameraTest, MovesOnASphereAroundThePivotKeepingItInView) {
  const Camera reference = testing::TiltedCamera(64, 48, 60.0);
  const Eigen::Vector3d pivot = reference.WorldFromCamera(Eigen::Vector3d(0.3, -0.2, 7.0));
  Eigen::Vector2d reference_pixel, pixel;
  double depth = 0.0;
  ASSERT_TRUE(reference.Project(pivot, &reference_pixel, &depth));
  const Eigen::Vector3d right = reference.world_from_camera_rotation.col(0);
  const Eigen::Vector3d up = -reference.world_from_camera_rotation.col(1);
  for (const auto& [yaw, pitch] : {std::pair{30.0, 0.0}, {0.0, 20.0}, {-25.0, 15.0}}) {
    const Camera orbit = OrbitCamera(reference, yaw, pitch, pivot);
    EXPECT_NO_THROW(orbit.Validate("orbit"));
    EXPECT_NEAR((orbit.center_world - pivot).norm(), (reference.center_world - pivot).norm(), 1e-9);
    ASSERT_TRUE(orbit.Project(pivot, &pixel, &depth));
    EXPECT_LT((pixel - reference_pixel).norm(), 1e-9) << yaw << " " << pitch;
    const Eigen::Vector3d moved = orbit.center_world - reference.center_world;
    if (yaw != 0.0) {
      EXPECT_EQ(moved.dot(right) > 0.0, yaw > 0.0);
    }
    if (pitch != 0.0) {
      EXPECT_GT(moved.dot(up), 0.0);
    }
  }
  // The angle between the old and the new viewing direction is the yaw alone.
  const Camera turned = OrbitCamera(reference, 30.0, 0.0, pivot);
  EXPECT_NEAR(std::acos(turned.world_from_camera_rotation.col(2).dot(
                  reference.world_from_camera_rotation.col(2))) *
                  180.0 / M_PI,
              30.0, 1e-9);
}

TEST(OrbitCameraTest, MedianVertexIsComponentWise) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 10, 5}, {1, 30, -2}, {100, 20, 0}};
  EXPECT_EQ(MedianVertex(mesh), Eigen::Vector3d(1, 20, 0));
  EXPECT_THROW(MedianVertex(TriangleMesh()), Error);
}

TEST(RenderMeshTest, SameBytesWhateverTheThreadCount) {
  const synth::SyntheticScene& scene = testing::TinyScene();
  const View& view = scene.views[scene.reference_index];
  const TriangleMesh mesh = MeshFromDepthMap(scene.depth[scene.reference_index], view.image,
                                             view.camera, MeshingOptions());
  const Camera orbit = OrbitCamera(view.camera, 25.0, 10.0, MedianVertex(mesh));
  MeshRenderResult one, two;
  tbb::task_arena(1).execute([&] { one = RenderMesh(mesh, orbit, MeshRenderOptions()); });
  tbb::task_arena(2).execute([&] { two = RenderMesh(mesh, orbit, MeshRenderOptions()); });
  EXPECT_TRUE(SameBytes(one.image, two.image));
  EXPECT_TRUE(SameBytes(one.depth, two.depth));
  EXPECT_TRUE(SameBytes(one.face_index, two.face_index));
  EXPECT_GT(one.covered_pixels, view.camera.width * view.camera.height / 3);
}

TEST(RenderMeshTest, BadInputsNameTheProblem) {
  const Camera camera = PinholeCamera(40, 30, 50.0, 19.5, 14.5);
  TriangleMesh mesh = Quad(camera, 5.5, 5.5, 30.5, 20.5, 8.0, Color(255, 0, 0));
  auto message_of = [](auto&& call) -> std::string {
    try {
      call();
    } catch (const Error& e) {
      return e.what();
    }
    return "no exception";
  };
  const MeshRenderOptions options;
  TriangleMesh bad = mesh;
  bad.colors.pop_back();
  EXPECT_EQ(message_of([&] { RenderMesh(bad, camera, options); }),
            "RenderMesh: the mesh has 3 colours for 4 vertices (expected none or one per vertex)");
  bad = mesh;
  bad.faces[1][2] = 4;
  EXPECT_EQ(message_of([&] { RenderMesh(bad, camera, options); }),
            "RenderMesh: face 1 refers to vertex 4 but the mesh has 4 vertices");
  Camera bad_camera = camera;
  bad_camera.width = 0;
  EXPECT_EQ(message_of([&] { RenderMesh(mesh, bad_camera, options); }),
            "RenderMesh: camera: image size must be positive, got 0x30");
  MeshRenderOptions o;
  o.mode = "wireframe";
  EXPECT_EQ(
      message_of([&] { o.Check(); }),
      "mesh.preview.mode = wireframe. Violated constraint: one of color, shaded, color_shaded");
  o = MeshRenderOptions();
  o.ambient = 1.5;
  EXPECT_EQ(message_of([&] { o.Check(); }),
            "mesh.preview.ambient = 1.5. Violated constraint: 0 <= ambient <= 1");
  o = MeshRenderOptions();
  o.crease_angle_deg = 181.0;
  EXPECT_EQ(
      message_of([&] { o.Check(); }),
      "mesh.preview.crease_angle_deg = 181. Violated constraint: 0 <= crease_angle_deg <= 180");
  o = MeshRenderOptions();
  o.supersampling = 5;
  EXPECT_EQ(message_of([&] { o.Check(); }),
            "mesh.preview.supersampling = 5. Violated constraint: 1 <= supersampling <= 4");
  o = MeshRenderOptions();
  o.background_grey = 256;
  EXPECT_EQ(message_of([&] { o.Check(); }),
            "mesh.preview.background_grey = 256. Violated constraint: 0 <= background_grey <= 255");
  o = MeshRenderOptions();
  o.surface_grey = -1;
  EXPECT_THROW(RenderMesh(mesh, camera, o), ConfigError);
  // An empty mesh is a valid input: background only.
  const MeshRenderResult empty = RenderMesh(TriangleMesh(), camera, MeshRenderOptions());
  EXPECT_EQ(empty.covered_pixels, 0);
  EXPECT_EQ(cv::countNonZero(empty.image.reshape(1) != 48), 0);
}

// Not a check: writes previews of the synthetic courtyard (640×427 images) for a person to look
// at when GCPSTEREO_MESH_PREVIEW_DIR names a folder (e.g. /tmp). GCPSTEREO_MESH_PREVIEW_PRESET
// picks the preset meshed (default tiny; small takes a few seconds to generate).
TEST(RenderMeshTest, WritePreviewsWhenAsked) {
  const char* dir = std::getenv("GCPSTEREO_MESH_PREVIEW_DIR");
  if (dir == nullptr) GTEST_SKIP() << "set GCPSTEREO_MESH_PREVIEW_DIR to write the previews";
  const char* preset_env = std::getenv("GCPSTEREO_MESH_PREVIEW_PRESET");
  const std::string preset = preset_env != nullptr ? preset_env : "tiny";
  synth::SynthOptions synth_options;
  synth_options.preset = preset;
  const synth::SyntheticScene scene = synth::GenerateScene(synth_options);
  const View& view = scene.views[scene.reference_index];
  const TriangleMesh mesh = MeshFromDepthMap(scene.depth[scene.reference_index], view.image,
                                             view.camera, MeshingOptions());
  const Camera camera = view.camera.Rescaled(640.0 / view.camera.width);
  const Eigen::Vector3d pivot = MedianVertex(mesh);
  MeshRenderOptions options;
  for (const std::string mode : {"color_shaded", "shaded"}) {
    options.mode = mode;
    const std::string prefix = std::string(dir) + "/mesh_" + preset + "_" + mode;
    cv::imwrite(prefix + "_front.png", RenderMeshPreview(mesh, camera, options));
    cv::imwrite(prefix + "_orbit.png",
                RenderMeshPreview(mesh, OrbitCamera(camera, 30.0, 15.0, pivot), options));
  }
  // The exact surface of the generator, for comparison.
  options.mode = "shaded";
  cv::imwrite(std::string(dir) + "/mesh_" + preset + "_exact_orbit.png",
              RenderMeshPreview(scene.mesh, OrbitCamera(camera, 30.0, 15.0, pivot), options));
}

}  // namespace
}  // namespace gcpstereo::mesh
