// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/mesh/surface_reconstruction.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "gcpstereo/core/error.h"

namespace gcpstereo::mesh {
namespace {

using Color = Eigen::Matrix<std::uint8_t, 3, 1>;

const Color kRed(255, 0, 0);
const Color kBlue(0, 0, 255);

// `count` points on the unit sphere (Fibonacci lattice, near-uniform), outward normals; the upper
// half (z > 0) red, the lower half blue.
OrientedPointCloud UnitSphere(int count) {
  OrientedPointCloud cloud;
  const double golden_angle = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double r = std::sqrt(1.0 - z * z);
    const double phi = golden_angle * i;
    const Eigen::Vector3f p(static_cast<float>(r * std::cos(phi)),
                            static_cast<float>(r * std::sin(phi)), static_cast<float>(z));
    cloud.points.push_back(p);
    cloud.normals.push_back(p.normalized());
    cloud.colors.push_back(z > 0.0 ? kRed : kBlue);
  }
  return cloud;
}

// A square patch [-1, 1]² of the plane z = 0, sampled on a grid, normals +z, grey.
OrientedPointCloud PlanePatch(int per_side) {
  OrientedPointCloud cloud;
  for (int row = 0; row < per_side; ++row) {
    for (int col = 0; col < per_side; ++col) {
      cloud.points.emplace_back(-1.0f + 2.0f * col / (per_side - 1),
                                -1.0f + 2.0f * row / (per_side - 1), 0.0f);
      cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
      cloud.colors.emplace_back(128, 128, 128);
    }
  }
  return cloud;
}

SurfaceOptions FastOptions() {
  SurfaceOptions options;
  options.depth = 7;
  return options;
}

// The sphere's mesh, computed once for the tests that only read it.
struct SphereResult {
  TriangleMesh mesh;
  SurfaceSummary summary;
};
const SphereResult& Sphere() {
  static const SphereResult result = [] {
    SphereResult r;
    r.mesh = ReconstructSurface(UnitSphere(10000), FastOptions(), &r.summary);
    return r;
  }();
  return result;
}

std::string ErrorText(const SurfaceOptions& options) {
  try {
    options.Check();
  } catch (const ConfigError& error) {
    return error.what();
  }
  return "(no error)";
}

std::string ErrorText(const OrientedPointCloud& cloud) {
  try {
    ReconstructSurface(cloud, FastOptions());
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(SurfaceReconstruction, SphereVerticesOnTheSurfaceFacesOutward) {
  const TriangleMesh& mesh = Sphere().mesh;
  const SurfaceSummary& summary = Sphere().summary;
  ASSERT_GT(mesh.faces.size(), 1000u);
  EXPECT_EQ(summary.input_points, 10000);
  EXPECT_EQ(summary.vertices, static_cast<std::int64_t>(mesh.vertices.size()));
  EXPECT_EQ(summary.faces, static_cast<std::int64_t>(mesh.faces.size()));
  EXPECT_EQ(summary.trimmed_faces, summary.poisson_faces - summary.faces);
  // A closed sphere densely sampled: nothing to trim.
  EXPECT_EQ(summary.trimmed_faces, 0);
  // Depth 7 over 1.1 × 2: cells of 1.7 cm; the surface stays well inside one cell.
  double max_error = 0.0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    max_error = std::max(max_error, std::abs(static_cast<double>(v.norm()) - 1.0));
  }
  EXPECT_LT(max_error, 0.01);
  // Counter-clockwise seen from outside: every face normal points away from the centre.
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3f& a = mesh.vertices[f[0]];
    const Eigen::Vector3f normal = (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a);
    ASSERT_GT(normal.dot(a + mesh.vertices[f[1]] + mesh.vertices[f[2]]), 0.0f);
  }
}

TEST(SurfaceReconstruction, ColoursOfTheNearestInputPoint) {
  const TriangleMesh& mesh = Sphere().mesh;
  ASSERT_EQ(mesh.colors.size(), mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const float z = mesh.vertices[v].z();
    if (z > 0.05f) {
      EXPECT_EQ(mesh.colors[v], kRed) << "vertex " << v << " z " << z;
    } else if (z < -0.05f) {
      EXPECT_EQ(mesh.colors[v], kBlue) << "vertex " << v << " z " << z;
    }
  }
  // Without colours in the input, none in the output.
  OrientedPointCloud uncoloured = PlanePatch(21);
  uncoloured.colors.clear();
  EXPECT_TRUE(ReconstructSurface(uncoloured, FastOptions()).colors.empty());
}

TEST(SurfaceReconstruction, PlanePatchBubbleTrimmed) {
  SurfaceSummary summary;
  const TriangleMesh mesh = ReconstructSurface(PlanePatch(101), FastOptions(), &summary);
  // The Poisson surface of an open patch closes itself far from the data; that part is cut.
  EXPECT_GT(summary.trimmed_faces, 0);
  EXPECT_NEAR(summary.median_spacing, 0.02, 1e-6);
  ASSERT_GT(mesh.faces.size(), 1000u);
  // Every remaining vertex lies within the trim distance of the patch.
  for (const Eigen::Vector3f& v : mesh.vertices) {
    const double dx = std::max(0.0, std::abs(static_cast<double>(v.x())) - 1.0);
    const double dy = std::max(0.0, std::abs(static_cast<double>(v.y())) - 1.0);
    const double distance = std::sqrt(dx * dx + dy * dy + static_cast<double>(v.z()) * v.z());
    ASSERT_LE(distance, summary.trim_distance + 1e-6) << v.transpose();
  }
  // The patch is covered: its centre region has mesh vertices close to the plane.
  int central = 0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    if (std::abs(v.x()) < 0.8f && std::abs(v.y()) < 0.8f) {
      ++central;
      EXPECT_LT(std::abs(v.z()), 0.02f);
    }
  }
  EXPECT_GT(central, 1000);
  // Every vertex is used by a face (unreferenced ones are dropped).
  std::vector<bool> used(mesh.vertices.size(), false);
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) used[f[k]] = true;
  }
  EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](bool u) { return u; }));
}

TEST(SurfaceReconstruction, ExplicitTrimDistance) {
  SurfaceOptions options = FastOptions();
  options.trim_distance = 0.05;
  SurfaceSummary summary;
  ReconstructSurface(PlanePatch(51), options, &summary);
  EXPECT_EQ(summary.trim_distance, 0.05);
  const nlohmann::json j = summary.ToJson();
  EXPECT_EQ(j.at("trim_distance").get<double>(), 0.05);
  EXPECT_EQ(j.at("input_points").get<std::int64_t>(), 51 * 51);
  EXPECT_EQ(j.at("trimmed_faces").get<std::int64_t>(), summary.trimmed_faces);
}

TEST(SurfaceReconstruction, SameOutputWhateverTheThreadCount) {
  const OrientedPointCloud cloud = UnitSphere(3000);
  SurfaceOptions one = FastOptions();
  one.depth = 6;
  one.threads = 1;
  SurfaceOptions two = one;
  two.threads = 2;
  const TriangleMesh a = ReconstructSurface(cloud, one);
  const TriangleMesh b = ReconstructSurface(cloud, two);
  const TriangleMesh c = ReconstructSurface(cloud, two);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(b.vertices, c.vertices);
  EXPECT_EQ(b.faces, c.faces);
}

TEST(SurfaceReconstruction, CloudWithoutExtentGivesAnEmptyMesh) {
  // An expected outcome, not an error: the summary says there is nothing to mesh.
  OrientedPointCloud cloud;
  for (int i = 0; i < 5; ++i) {
    cloud.points.emplace_back(1.0f, 2.0f, 3.0f);
    cloud.normals.emplace_back(0.0f, 0.0f, 1.0f);
  }
  SurfaceSummary summary;
  const TriangleMesh mesh = ReconstructSurface(cloud, FastOptions(), &summary);
  EXPECT_TRUE(mesh.vertices.empty());
  EXPECT_TRUE(mesh.faces.empty());
  EXPECT_EQ(summary.input_points, 5);
  EXPECT_EQ(summary.faces, 0);
}

TEST(SurfaceReconstruction, OptionErrors) {
  EXPECT_EQ(ErrorText(SurfaceOptions{}), "(no error)");
  SurfaceOptions options;
  options.depth = 3;
  EXPECT_EQ(ErrorText(options), "scene_mesh.depth = 3. Violated constraint: 5 <= depth <= 14");
  options = SurfaceOptions{};
  options.depth = 15;
  EXPECT_EQ(ErrorText(options), "scene_mesh.depth = 15. Violated constraint: 5 <= depth <= 14");
  options = SurfaceOptions{};
  options.point_weight = -1.0;
  EXPECT_EQ(ErrorText(options),
            "scene_mesh.point_weight = -1. Violated constraint: 0 <= point_weight <= 1000");
  options = SurfaceOptions{};
  options.trim_distance = -0.5;
  EXPECT_EQ(ErrorText(options),
            "scene_mesh.trim_distance = -0.5. Violated constraint: trim_distance >= 0 and "
            "finite (0 = automatic)");
  options.trim_distance = std::numeric_limits<double>::infinity();
  EXPECT_EQ(ErrorText(options),
            "scene_mesh.trim_distance = inf. Violated constraint: trim_distance >= 0 and "
            "finite (0 = automatic)");
  options = SurfaceOptions{};
  options.threads = -1;
  EXPECT_EQ(ErrorText(options),
            "scene_mesh.threads = -1. Violated constraint: 0 <= threads <= 1024 (0 = all)");
}

TEST(SurfaceReconstruction, InputErrors) {
  EXPECT_EQ(ErrorText(OrientedPointCloud{}), "ReconstructSurface: the point cloud is empty");
  OrientedPointCloud cloud = PlanePatch(10);
  cloud.normals.clear();
  EXPECT_EQ(ErrorText(cloud),
            "ReconstructSurface: the point cloud has no normals (an oriented cloud is required)");
  cloud = PlanePatch(10);
  cloud.normals.pop_back();
  EXPECT_EQ(ErrorText(cloud), "ReconstructSurface: the point cloud has 100 points but 99 normals");
  cloud = PlanePatch(10);
  cloud.colors.pop_back();
  EXPECT_EQ(ErrorText(cloud), "ReconstructSurface: the point cloud has 100 points but 99 colors");
  cloud = PlanePatch(10);
  cloud.num_views.assign(3, 2);
  EXPECT_EQ(ErrorText(cloud), "ReconstructSurface: the point cloud has 100 points but 3 num_views");
  cloud = PlanePatch(10);
  cloud.sigma.assign(101, 0.0f);
  EXPECT_EQ(ErrorText(cloud), "ReconstructSurface: the point cloud has 100 points but 101 sigma");
  cloud = PlanePatch(10);
  cloud.points[7].x() = std::nanf("");
  EXPECT_EQ(ErrorText(cloud), "ReconstructSurface: point 7 has a non-finite position or normal");
}

}  // namespace
}  // namespace gcpstereo::mesh
