// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/view_selection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/io/camera_io.h"
#include "test_data.h"

namespace gcpstereo::cost {
namespace {

using gcpstereo::testing::ErrorOf;

constexpr double kPi = 3.14159265358979323846;

Camera MakeCamera(const Eigen::Vector3d& center, const Eigen::Matrix3d& world_from_camera) {
  Camera camera;
  camera.K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  camera.world_from_camera_rotation = world_from_camera;
  camera.center_world = center;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

// A camera at `center` looking along `forward`, world z up (image y = world −z).
Camera LookingAlong(const Eigen::Vector3d& center, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d y(0, 0, -1);
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Matrix3d r;
  r << x, y, z;
  return MakeCamera(center, r);
}

std::set<int> AsSet(const std::vector<int>& v) { return {v.begin(), v.end()}; }

// 24 cameras on a circle of radius 10 m in the plane z = 0, every 15°, looking at the centre; view
// 0 is the reference. View 24 stands 5 cm beside the reference (triangulation angle ≈ 0.3°), view
// 25 behind it looking away from the scene.
std::vector<Camera> RingScene() {
  std::vector<Camera> cameras;
  for (int i = 0; i < 24; ++i) {
    const double phi = i * 15.0 * kPi / 180.0;
    const Eigen::Vector3d c(10 * std::cos(phi), 10 * std::sin(phi), 0);
    cameras.push_back(LookingAlong(c, -c));
  }
  const Eigen::Vector3d twin(10, 0.05, 0);
  cameras.push_back(LookingAlong(twin, -twin));
  cameras.push_back(LookingAlong(Eigen::Vector3d(12, 0, 0), Eigen::Vector3d(1, 0, 0)));
  return cameras;
}

TEST(ViewSelection, RingPicksTheNearestViewsOnEitherSide) {
  const std::vector<Camera> cameras = RingScene();
  ViewSelectionOptions options;
  options.count = 2;
  const ViewSelection two = SelectNeighbors(cameras, 0, {}, options);
  EXPECT_EQ(two.basis, "frustum");
  EXPECT_EQ(AsSet(two.neighbors), (std::set<int>{1, 23}));

  options.count = 6;
  const ViewSelection six = SelectNeighbors(cameras, 0, {}, options);
  EXPECT_EQ(AsSet(six.neighbors), (std::set<int>{1, 2, 3, 21, 22, 23}));
  ASSERT_EQ(six.candidates.size(), 25u);

  // With room for every view, only those in front of the grid's fronto-parallel plane (through the
  // centre) with a usable baseline are chosen: ±15° … ±75°; not the 5 cm twin, the camera facing
  // away, the one at 90° (edge-on) or those beyond.
  options.count = 64;
  const ViewSelection all = SelectNeighbors(cameras, 0, {}, options);
  EXPECT_EQ(AsSet(all.neighbors), (std::set<int>{1, 2, 3, 4, 5, 19, 20, 21, 22, 23}));
  for (const NeighborScore& c : all.candidates) {
    if (c.index == 24) {
      EXPECT_EQ(c.score, 0.0);
      EXPECT_GT(c.shared_fraction, 0.99);  // sees everything, but at ≈ 0.3°
      EXPECT_LT(c.median_angle_deg, 1.0);
    }
    if (c.index == 25) {
      EXPECT_EQ(c.score, 0.0);
      EXPECT_EQ(c.shared_points, 0);
    }
  }
  // Best first, ties broken by the lower index: the symmetric pair 1 / 23 ties exactly or nearly.
  for (std::size_t i = 1; i < all.candidates.size(); ++i) {
    EXPECT_GE(all.candidates[i - 1].score, all.candidates[i].score);
  }
}

TEST(ViewSelection, RectifiedSequenceUsesTheMedianBaseline) {
  // Five parallel cameras 10 cm apart (no converging axes): the grid lies at z₀ = b / tan θ_opt
  // with b = 15 cm the median distance from the reference (view 2), where the views two steps away
  // see the points on the principal ray at 13.2° and those one step away at 6.7° (off-axis points
  // at somewhat less: they are farther).
  std::vector<Camera> cameras;
  for (int i = 0; i < 5; ++i)
    cameras.push_back(RectifiedSequenceCamera(500, 319.5, 239.5, 0.1, i, 640, 480));
  ViewSelectionOptions options;
  options.count = 2;
  const ViewSelection s = SelectNeighbors(cameras, 2, {}, options);
  EXPECT_EQ(s.basis, "frustum");
  EXPECT_EQ(AsSet(s.neighbors), (std::set<int>{0, 4}));
  ASSERT_EQ(s.candidates.size(), 4u);
  EXPECT_GT(s.candidates[0].median_angle_deg, 11.0);
  EXPECT_LT(s.candidates[0].median_angle_deg, 13.3);
  EXPECT_GT(s.candidates[2].median_angle_deg, 5.5);
  EXPECT_LT(s.candidates[2].median_angle_deg, 6.7);
  EXPECT_GT(s.candidates[3].score, 0.0);
}

TEST(ViewSelection, GivenPointsExcludeViewsThatDoNotSeeThem) {
  // Reference at the origin looking along +z (world = camera frame); L one metre to its left
  // turned 25° to the left, R one metre to its right turned 25° to the right.
  const auto yawed = [](double x, double yaw_deg) {
    return MakeCamera(
        Eigen::Vector3d(x, 0, 0),
        Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix());
  };
  const std::vector<Camera> cameras = {yawed(0, 0), yawed(-1, -25), yawed(1, 25)};
  ViewSelectionOptions options;

  // Without points both overlap the reference's frustum and both are chosen.
  const ViewSelection frustum = SelectNeighbors(cameras, 0, {}, options);
  EXPECT_EQ(frustum.basis, "frustum");
  EXPECT_EQ(AsSet(frustum.neighbors), (std::set<int>{1, 2}));

  // Points on the plane z = 10 m, x in [−4, −1]: seen by the reference and L only.
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i <= 30; ++i) {
    for (int j = 0; j <= 20; ++j) points.emplace_back(-4.0 + 0.1 * i, -2.0 + 0.2 * j, 10.0);
  }
  points.emplace_back(0, 0, -5);  // behind the reference: ignored
  const ViewSelection selection = SelectNeighbors(cameras, 0, points, options);
  EXPECT_EQ(selection.basis, "points");
  EXPECT_EQ(selection.points_given, static_cast<int>(points.size()));
  EXPECT_EQ(selection.points_used, 31 * 21);
  EXPECT_EQ(selection.neighbors, (std::vector<int>{1}));
  ASSERT_EQ(selection.candidates.size(), 2u);
  EXPECT_EQ(selection.candidates[1].index, 2);
  EXPECT_EQ(selection.candidates[1].shared_points, 0);
  EXPECT_EQ(selection.candidates[1].score, 0.0);

  const nlohmann::json json = selection.ToJson({"ref", "left", "right"});
  EXPECT_EQ(json["neighbors"], nlohmann::json::array({"left"}));
  EXPECT_EQ(json["basis"], "points");
  EXPECT_EQ(json["candidates"][1]["name"], "right");
  EXPECT_EQ(ErrorOf([&] { (void)selection.ToJson({"ref"}); }),
            "view selection: no name for view index 1 (1 names)");
}

TEST(ViewSelection, CheckNamesKeyValueAndBound) {
  const auto check = [](auto modify) {
    ViewSelectionOptions options;
    modify(options);
    return ErrorOf([&] { options.Check(); });
  };
  EXPECT_EQ(check([](ViewSelectionOptions&) {}), "(no error)");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.count = 0; }),
            "dataset.neighbor_count = 0. Violated constraint: 1 <= count <= 64");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.count = 65; }),
            "dataset.neighbor_count = 65. Violated constraint: 1 <= count <= 64");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.min_angle_deg = 0; }),
            "dataset.neighbor_selection.min_angle_deg = 0. Violated constraint: 0 < min_angle_deg "
            "< optimal_angle_deg (10)");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.min_angle_deg = 12; }),
            "dataset.neighbor_selection.min_angle_deg = 12. Violated constraint: 0 < "
            "min_angle_deg < optimal_angle_deg (10)");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.optimal_angle_deg = 50; }),
            "dataset.neighbor_selection.optimal_angle_deg = 50. Violated constraint: "
            "optimal_angle_deg < max_angle_deg (45)");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.max_angle_deg = 90; }),
            "dataset.neighbor_selection.max_angle_deg = 90. Violated constraint: max_angle_deg < "
            "90");
  EXPECT_EQ(check([](ViewSelectionOptions& o) { o.grid_step_px = 0; }),
            "dataset.neighbor_selection.grid_step_px = 0. Violated constraint: grid_step_px >= 1");
}

TEST(ViewSelection, BadInputsThrow) {
  const std::vector<Camera> cameras = RingScene();
  EXPECT_EQ(ErrorOf([&] { SelectNeighbors(cameras, 26, {}, {}); }),
            "view selection: reference index 26 outside 0 … 25");
  EXPECT_EQ(ErrorOf([&] { SelectNeighbors(cameras, 0, {}, {}, 5.0, 5.0); }),
            "view selection: depth bounds [5, 5] need 0 <= min_depth < max_depth");
  ViewSelectionOptions bad;
  bad.count = 0;
  EXPECT_EQ(ErrorOf([&] { SelectNeighbors(cameras, 0, {}, bad); }),
            "dataset.neighbor_count = 0. Violated constraint: 1 <= count <= 64");
}

// fountain-P11's Strecha cameras, or an empty list when the data is absent.
std::vector<Camera> FountainCameras(const std::string& dir) {
  std::vector<Camera> cameras;
  for (int i = 0; i < 11; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "/%04d.jpg.camera", i);
    cameras.push_back(io::ReadStrechaCamera(dir + name));
  }
  return cameras;
}

std::string Names(const std::vector<int>& views) {
  std::vector<int> sorted = views;
  std::sort(sorted.begin(), sorted.end());
  std::ostringstream s;
  for (int v : sorted) s << std::setw(4) << std::setfill('0') << v << ' ';
  return s.str();
}

void PrintTable(const std::string& title, const std::vector<Camera>& cameras,
                const std::vector<Eigen::Vector3d>& points) {
  std::cout << title << "\n";
  for (int ref = 0; ref < static_cast<int>(cameras.size()); ++ref) {
    const ViewSelection s = SelectNeighbors(cameras, ref, points, {});
    std::cout << "  " << std::setw(4) << std::setfill('0') << ref << std::setfill(' ') << " ["
              << s.basis << ", " << s.points_used << " pts]: " << Names(s.neighbors) << " | best:";
    for (std::size_t i = 0; i < s.candidates.size() && i < 8; ++i) {
      const NeighborScore& c = s.candidates[i];
      std::cout << ' ' << c.index << '(' << std::fixed << std::setprecision(2) << c.score << ", "
                << std::setprecision(1) << c.median_angle_deg << "°)";
      std::cout.unsetf(std::ios::fixed);
    }
    std::cout << "\n";
  }
}

TEST(ViewSelection, FountainP11ReferenceFiveMatchesThePaper) {
  GCPSTEREO_REQUIRE_SHARED_DATA(dir, "strecha/fountain-P11/cameras");
  const std::vector<Camera> cameras = FountainCameras(dir);
  const ViewSelection s = SelectNeighbors(cameras, 5, {}, {});
  EXPECT_EQ(s.basis, "frustum");
  // The paper matches 0005 against 0002, 0003, 0004, 0006, 0007, 0008; the frustum-based choice
  // is exactly that set: the three nearest views on either side of the arc (≈ 10°, 20°, 30° from
  // 0005). 0001 (38°) and 0009 (43°) follow closely, since their angles are still on the plateau,
  // but they see less of the reference's image.
  EXPECT_EQ(AsSet(s.neighbors), (std::set<int>{2, 3, 4, 6, 7, 8}));
  PrintTable("fountain-P11, neighbours without points (frustum basis):", cameras, {});
}

// POINT3D_ID X Y Z … of COLMAP's points3D.txt.
std::vector<Eigen::Vector3d> ReadColmapPoints(const std::string& path) {
  std::vector<Eigen::Vector3d> points;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    long id = 0;
    Eigen::Vector3d p;
    if (s >> id >> p.x() >> p.y() >> p.z()) points.push_back(p);
  }
  return points;
}

TEST(ViewSelection, FountainP11WithColmapPoints) {
  GCPSTEREO_REQUIRE_SHARED_DATA(dir, "strecha/fountain-P11/cameras");
  GCPSTEREO_REQUIRE_SHARED_DATA(points_path, "colmap/fountain-P11/sparse-txt/points3D.txt");
  const std::vector<Camera> cameras = FountainCameras(dir);
  const std::vector<Eigen::Vector3d> points = ReadColmapPoints(points_path);
  ASSERT_EQ(points.size(), 15038u);
  const ViewSelection s = SelectNeighbors(cameras, 5, points, {});
  EXPECT_EQ(s.basis, "points");
  // The SfM points give the same set as the frustum basis and the paper.
  EXPECT_EQ(AsSet(s.neighbors), (std::set<int>{2, 3, 4, 6, 7, 8}));
  PrintTable("fountain-P11, neighbours with COLMAP's 15,038 SfM points:", cameras, points);
}

}  // namespace
}  // namespace gcpstereo::cost
