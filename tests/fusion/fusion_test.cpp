// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/fusion/fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/synth/generator.h"
#include "gcpstereo/synth/scene.h"

namespace gcpstereo::fusion {
namespace {

// ---------------------------------------------------------------------------------------------
// Fixtures

// The synthetic "tiny" courtyard (5 views, 160×107), generated once.
const synth::SyntheticScene& TinyScene() {
  static const synth::SyntheticScene scene = [] {
    synth::SynthOptions options;
    options.preset = "tiny";
    return synth::GenerateScene(options);
  }();
  return scene;
}

std::vector<FusionView> ViewsOf(const synth::SyntheticScene& scene) {
  std::vector<FusionView> views;
  for (size_t i = 0; i < scene.views.size(); ++i) {
    views.push_back(
        {scene.views[i].name, scene.views[i].camera, scene.depth[i].clone(), scene.views[i].image});
  }
  return views;
}

// A plane {X : normal · X = offset} (normal unit length).
struct Plane {
  Eigen::Vector3d normal;
  double offset = 0.0;
  double SignedDistance(const Eigen::Vector3d& X) const { return normal.dot(X) - offset; }
};

Plane TiltedPlane() {
  Plane plane;
  plane.normal = Eigen::Vector3d(0.2, -0.3, -1.0).normalized();
  plane.offset = plane.normal.dot(Eigen::Vector3d(0.0, 0.0, 5.0));
  return plane;
}

Camera MakeCamera(const Eigen::Vector3d& center, const Eigen::Matrix3d& rotation) {
  Camera camera;
  camera.width = 160;
  camera.height = 120;
  camera.K << 200.0, 0.0, 79.5, 0.0, 200.0, 59.5, 0.0, 0.0, 1.0;
  camera.world_from_camera_rotation = rotation;
  camera.center_world = center;
  return camera;
}

// The exact depth map of the plane seen by `camera` (+inf where it is behind the camera).
cv::Mat PlaneDepth(const Camera& camera, const Plane& plane) {
  cv::Mat depth(camera.height, camera.width, CV_32F);
  const Eigen::Matrix3d K_inverse = camera.K.inverse();
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      // Ray with camera z = 1, in the world frame.
      const Eigen::Vector3d ray =
          camera.world_from_camera_rotation * (K_inverse * Eigen::Vector3d(col, row, 1.0));
      const double d =
          (plane.offset - plane.normal.dot(camera.center_world)) / plane.normal.dot(ray);
      depth.at<float>(row, col) = d > 0.0 ? static_cast<float>(d) : kInvalidDepth;
    }
  }
  return depth;
}

// `count` cameras on a line along x (0.2 m apart), turned slightly towards (0, 0, 5), all seeing
// the tilted plane; view i's image is the uniform BGR colour (10 i, 100, 200).
std::vector<FusionView> PlaneViews(int count, const Plane& plane) {
  std::vector<FusionView> views;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d center(0.2 * (i - (count - 1) / 2.0), 0.05 * i, 0.0);
    const double yaw = -std::atan2(center.x(), 5.0);
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).matrix();
    FusionView view;
    view.name = "plane" + std::to_string(i);
    view.camera = MakeCamera(center, rotation);
    view.depth = PlaneDepth(view.camera, plane);
    view.image_bgr = cv::Mat(120, 160, CV_8UC3, cv::Scalar(10 * i, 100, 200));
    views.push_back(view);
  }
  return views;
}

void ExpectSameCloud(const OrientedPointCloud& a, const OrientedPointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  ASSERT_EQ(a.sigma.size(), b.sigma.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.points[i], b.points[i]) << i;
    ASSERT_EQ(a.normals[i], b.normals[i]) << i;
    ASSERT_EQ(a.colors[i], b.colors[i]) << i;
    ASSERT_EQ(a.num_views[i], b.num_views[i]) << i;
    ASSERT_EQ(a.sigma[i], b.sigma[i]) << i;
  }
}

void ExpectChannelsConsistent(const OrientedPointCloud& cloud) {
  EXPECT_EQ(cloud.normals.size(), cloud.size());
  EXPECT_EQ(cloud.colors.size(), cloud.size());
  EXPECT_EQ(cloud.num_views.size(), cloud.size());
  EXPECT_EQ(cloud.sigma.size(), cloud.size());
}

// ---------------------------------------------------------------------------------------------
// Options

std::string CheckError(const FusionOptions& options) {
  try {
    options.Check();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FusionOptions, DefaultsAreValid) { EXPECT_EQ(CheckError(FusionOptions()), "(no error)"); }

TEST(FusionOptions, CheckNamesKeyValueAndBound) {
  FusionOptions o;
  o.min_views = 0;
  EXPECT_EQ(CheckError(o), "fusion.min_views = 0. Violated constraint: 1 <= min_views <= 64");
  o.min_views = 65;
  EXPECT_EQ(CheckError(o), "fusion.min_views = 65. Violated constraint: 1 <= min_views <= 64");
  o = FusionOptions();
  o.depth_tolerance = 0.0;
  EXPECT_EQ(CheckError(o),
            "fusion.depth_tolerance = 0. Violated constraint: 0 < depth_tolerance <= 1");
  o.depth_tolerance = 1.5;
  EXPECT_EQ(CheckError(o),
            "fusion.depth_tolerance = 1.5. Violated constraint: 0 < depth_tolerance <= 1");
  o.depth_tolerance = std::numeric_limits<double>::infinity();
  EXPECT_EQ(CheckError(o),
            "fusion.depth_tolerance = inf. Violated constraint: 0 < depth_tolerance <= 1");
  o = FusionOptions();
  o.normal_tolerance_deg = 0.0;
  EXPECT_EQ(CheckError(o),
            "fusion.normal_tolerance_deg = 0. Violated constraint: 0 < "
            "normal_tolerance_deg <= 180");
  o.normal_tolerance_deg = 180.5;
  EXPECT_EQ(CheckError(o),
            "fusion.normal_tolerance_deg = 180.5. Violated constraint: 0 < "
            "normal_tolerance_deg <= 180");
  o = FusionOptions();
  o.normal_radius_px = 0;
  EXPECT_EQ(CheckError(o),
            "fusion.normal_radius_px = 0. Violated constraint: 1 <= normal_radius_px <= 16");
  o.normal_radius_px = 17;
  EXPECT_EQ(CheckError(o),
            "fusion.normal_radius_px = 17. Violated constraint: 1 <= normal_radius_px <= 16");
  o = FusionOptions();
  o.stride_px = 0;
  EXPECT_EQ(CheckError(o), "fusion.stride_px = 0. Violated constraint: 1 <= stride_px <= 64");
  o.stride_px = 65;
  EXPECT_EQ(CheckError(o), "fusion.stride_px = 65. Violated constraint: 1 <= stride_px <= 64");
}

TEST(FusionOptions, FuseDepthMapsChecksTheOptions) {
  FusionOptions o;
  o.min_views = 0;
  EXPECT_THROW(FuseDepthMaps(PlaneViews(2, TiltedPlane()), o), ConfigError);
}

// ---------------------------------------------------------------------------------------------
// Bad input

std::string FuseError(const std::vector<FusionView>& views) {
  try {
    FuseDepthMaps(views, FusionOptions());
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FuseDepthMaps, RejectsBadInputWithClearMessages) {
  EXPECT_EQ(FuseError({}), "FuseDepthMaps: no views");

  std::vector<FusionView> views = PlaneViews(2, TiltedPlane());
  views[1].depth.convertTo(views[1].depth, CV_64F);
  EXPECT_EQ(FuseError(views),
            "FuseDepthMaps: view 1 'plane1': the depth map must be CV_32FC1, "
            "got type " +
                std::to_string(CV_64F));

  views = PlaneViews(2, TiltedPlane());
  views[0].depth = views[0].depth(cv::Rect(0, 0, 100, 120)).clone();
  EXPECT_EQ(FuseError(views),
            "FuseDepthMaps: view 0 'plane0': the depth map is 100x120 but the camera is 160x120");

  views = PlaneViews(2, TiltedPlane());
  views[1].image_bgr = cv::Mat();
  EXPECT_EQ(FuseError(views),
            "FuseDepthMaps: view 1 'plane1': the image must be CV_8UC3 (BGR) "
            "or CV_8UC1, got an empty image");

  views = PlaneViews(2, TiltedPlane());
  views[1].image_bgr = cv::Mat(60, 80, CV_8UC3, cv::Scalar::all(0));
  EXPECT_EQ(FuseError(views),
            "FuseDepthMaps: view 1 'plane1': the image is 80x60 but the depth map is 160x120");

  views = PlaneViews(2, TiltedPlane());
  views[0].camera.K(0, 0) = -1.0;
  EXPECT_NE(FuseError(views).find("FuseDepthMaps: view 0 'plane0'"), std::string::npos);
}

TEST(FuseDepthMaps, CancelledByTheProgressCallbackThrows) {
  int calls = 0;
  EXPECT_THROW(FuseDepthMaps(PlaneViews(3, TiltedPlane()), FusionOptions(), nullptr,
                             [&](double) { return ++calls < 2; }),
               Error);
  EXPECT_EQ(calls, 2);
}

// ---------------------------------------------------------------------------------------------
// Normals

TEST(DepthMapNormals, TiltedPlaneGivesThePlaneNormalTowardsTheCamera) {
  const Plane plane = TiltedPlane();
  // A rotated camera, so that the world frame differs from the camera frame.
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()))
                                       .matrix();
  const Camera camera = MakeCamera(Eigen::Vector3d(0.3, -0.2, 0.1), rotation);
  const cv::Mat normals = DepthMapNormals(PlaneDepth(camera, plane), camera);
  ASSERT_EQ(normals.type(), CV_32FC3);
  ASSERT_EQ(normals.size(), cv::Size(160, 120));
  // The cameras are on the side the normal points to (normal · center > offset).
  ASSERT_GT(plane.SignedDistance(camera.center_world), 0.0);
  const Eigen::Vector3d expected = plane.normal;
  double worst = 0.0;
  for (int row = 0; row < 120; ++row) {
    for (int col = 0; col < 160; ++col) {
      const cv::Vec3f n = normals.at<cv::Vec3f>(row, col);
      ASSERT_TRUE(std::isfinite(n[0])) << col << "," << row;  // borders too: one-sided
      worst = std::max(worst, (Eigen::Vector3d(n[0], n[1], n[2]) - expected).norm());
    }
  }
  EXPECT_LT(worst, 1e-4);
}

TEST(DepthMapNormals, DepthStepTakesEachSidesOwnSurfaceAndUndefinedIsNaN) {
  const Camera camera = MakeCamera(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
  Plane back = TiltedPlane();
  Plane front;  // fronto-parallel at 3 m
  front.normal = Eigen::Vector3d(0, 0, 1);
  front.offset = 3.0;
  cv::Mat depth = PlaneDepth(camera, back);
  PlaneDepth(camera, front).colRange(0, 80).copyTo(depth.colRange(0, 80));
  depth.at<float>(60, 120) = kInvalidDepth;
  // An isolated valid pixel: no valid neighbour.
  depth.at<float>(0, 159) = 4.0f;
  depth.at<float>(0, 158) = kInvalidDepth;
  depth.at<float>(1, 159) = kInvalidDepth;
  const cv::Mat normals = DepthMapNormals(depth, camera);
  const cv::Vec3f left = normals.at<cv::Vec3f>(30, 79);   // last column of the front plane
  const cv::Vec3f right = normals.at<cv::Vec3f>(30, 80);  // first column of the back plane
  EXPECT_NEAR(left[2], -1.0f, 1e-5);
  EXPECT_LT((Eigen::Vector3d(right[0], right[1], right[2]) - back.normal).norm(), 1e-4);
  EXPECT_TRUE(std::isnan(normals.at<cv::Vec3f>(60, 120)[0]));
  EXPECT_TRUE(std::isnan(normals.at<cv::Vec3f>(0, 159)[0]));
  EXPECT_TRUE(std::isfinite(normals.at<cv::Vec3f>(60, 121)[0]));  // one-sided
}

TEST(DepthMapNormals, LargerRadiusIsExactOnPlanesAndDampsNoise) {
  const Plane plane = TiltedPlane();
  const Camera camera = MakeCamera(Eigen::Vector3d(0.1, 0.0, 0.0), Eigen::Matrix3d::Identity());
  const cv::Mat exact = PlaneDepth(camera, plane);
  cv::Mat noisy = exact.clone();
  cv::RNG rng(7);
  for (int row = 0; row < noisy.rows; ++row) {
    for (int col = 0; col < noisy.cols; ++col) {
      noisy.at<float>(row, col) *= static_cast<float>(1.0 + rng.gaussian(0.001));
    }
  }
  auto mean_angle_deg = [&](const cv::Mat& depth, int radius) {
    const cv::Mat normals = DepthMapNormals(depth, camera, radius);
    double sum = 0.0;
    for (int row = 0; row < normals.rows; ++row) {
      for (int col = 0; col < normals.cols; ++col) {
        const cv::Vec3f n = normals.at<cv::Vec3f>(row, col);
        const double c = std::clamp(Eigen::Vector3d(n[0], n[1], n[2]).dot(plane.normal), -1.0, 1.0);
        sum += std::acos(c) * 180.0 / 3.14159265358979323846;
      }
    }
    return sum / normals.total();
  };
  EXPECT_LT(mean_angle_deg(exact, 4), 0.01);
  const double noisy1 = mean_angle_deg(noisy, 1);
  const double noisy4 = mean_angle_deg(noisy, 4);
  std::cout << "mean normal error at 0.1 % depth noise: radius 1 " << noisy1 << " deg, radius 4 "
            << noisy4 << " deg\n";
  EXPECT_LT(noisy4, 0.5 * noisy1);
  EXPECT_THROW(DepthMapNormals(exact, camera, 0), Error);
}

TEST(DepthMapNormals, RejectsWrongTypeAndSize) {
  const Camera camera = MakeCamera(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity());
  EXPECT_THROW(DepthMapNormals(cv::Mat(120, 160, CV_64F, cv::Scalar(1.0)), camera), Error);
  EXPECT_THROW(DepthMapNormals(cv::Mat(100, 160, CV_32F, cv::Scalar(1.0)), camera), Error);
}

// ---------------------------------------------------------------------------------------------
// Fusion on planes

TEST(FuseDepthMaps, PlaneSeenByManyViewsIsFusedOnceNotNTimes) {
  const Plane plane = TiltedPlane();
  const int kViews = 5;
  const std::vector<FusionView> views = PlaneViews(kViews, plane);
  FusionSummary summary;
  const OrientedPointCloud cloud = FuseDepthMaps(views, FusionOptions(), &summary);
  ExpectChannelsConsistent(cloud);
  const std::int64_t one_view = 160 * 120;
  std::cout << summary.FullReport() << "\n";
  // Without the consumed marks every view would emit its own copy: about 5 × 19 200 points. The
  // union of the five views is a bit larger than one view (the cameras are 0.8 m apart), and
  // nearest-pixel lookups leave a few pixels of a later view unmarked.
  EXPECT_GT(static_cast<std::int64_t>(cloud.size()), one_view * 9 / 10);
  EXPECT_LT(static_cast<std::int64_t>(cloud.size()), one_view * 3 / 2);
  EXPECT_EQ(summary.total_points, static_cast<std::int64_t>(cloud.size()));
  ASSERT_EQ(summary.views.size(), static_cast<size_t>(kViews));
  std::int64_t kept = 0;
  for (const FusionViewSummary& v : summary.views) {
    kept += v.kept;
    EXPECT_EQ(v.samples, one_view);
    EXPECT_EQ(v.samples, v.consumed + v.no_normal + v.rejected + v.kept);
  }
  EXPECT_EQ(kept, summary.total_points);
  EXPECT_EQ(summary.views[0].kept + summary.views[0].rejected, one_view);
  // Most of the first view's pixels are seen by all five views.
  EXPECT_GT(summary.views[0].mean_views_kept, 4.0);
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_LT(std::abs(plane.SignedDistance(cloud.points[i].cast<double>())), 1e-4) << i;
    ASSERT_GE(cloud.num_views[i], 2);
    ASSERT_LT((cloud.normals[i].cast<double>() - plane.normal).norm(), 1e-4) << i;
    ASSERT_EQ(cloud.sigma[i], 0.0f);
  }
  // Colours: RGB from BGR images (B = 10 i, G = 100, R = 200), averaged over the agreeing views.
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(cloud.colors[i][0], 200);
    ASSERT_EQ(cloud.colors[i][1], 100);
    ASSERT_LE(cloud.colors[i][2], 40);
  }
  const nlohmann::json json = summary.ToJson();
  EXPECT_EQ(json["total_points"].get<std::int64_t>(), summary.total_points);
  EXPECT_EQ(json["views"].size(), static_cast<size_t>(kViews));
  EXPECT_EQ(json["views"][0]["name"], "plane0");
}

TEST(FuseDepthMaps, StrideSamplesEveryNthSourcePixel) {
  FusionOptions options;
  options.stride_px = 4;
  options.min_views = 1;
  FusionSummary summary;
  FuseDepthMaps(PlaneViews(1, TiltedPlane()), options, &summary);
  EXPECT_EQ(summary.views[0].samples, 40 * 30);
  EXPECT_EQ(summary.views[0].valid_pixels, 160 * 120);
  EXPECT_EQ(summary.total_points, 40 * 30);
}

TEST(FuseDepthMaps, CorruptedRegionOfOneViewIsRejectedUnlessMinViewsIsOne) {
  const Plane plane = TiltedPlane();
  std::vector<FusionView> views = PlaneViews(4, plane);
  const cv::Rect region(40, 30, 60, 40);
  views[2].depth(region) *= 1.3;  // 30 % too far
  auto off_plane = [&](const OrientedPointCloud& cloud) {
    std::int64_t count = 0;
    for (const Eigen::Vector3f& p : cloud.points) {
      if (std::abs(plane.SignedDistance(p.cast<double>())) > 1e-3) ++count;
    }
    return count;
  };
  FusionOptions options;
  options.min_views = 2;
  const OrientedPointCloud robust = FuseDepthMaps(views, options);
  EXPECT_EQ(off_plane(robust), 0);
  // The surface behind the corrupted region is still there (seen by the other three views).
  EXPECT_GT(robust.size(), static_cast<size_t>(160 * 120 * 9 / 10));

  options.min_views = 1;
  FusionSummary summary;
  const OrientedPointCloud everything = FuseDepthMaps(views, options, &summary);
  EXPECT_EQ(off_plane(everything), region.area());
  for (size_t i = 0; i < everything.size(); ++i) {
    if (std::abs(plane.SignedDistance(everything.points[i].cast<double>())) > 1e-3) {
      ASSERT_EQ(everything.num_views[i], 1);
    }
  }
}

TEST(FuseDepthMaps, MinViewsAboveTheViewCountGivesAnEmptyCloud) {
  FusionOptions options;
  options.min_views = 4;
  FusionSummary summary;
  const OrientedPointCloud cloud = FuseDepthMaps(PlaneViews(3, TiltedPlane()), options, &summary);
  EXPECT_TRUE(cloud.empty());
  EXPECT_EQ(summary.views[0].rejected, 160 * 120);
}

TEST(AppendGcpPoints, TakesNormalAndColourFromTheNearestFusedPoints) {
  const Plane plane = TiltedPlane();
  OrientedPointCloud cloud = FuseDepthMaps(PlaneViews(3, plane), FusionOptions());
  const size_t fused = cloud.size();
  PointCloud gcps;
  gcps.points.emplace_back(0.0f, 0.0f, 5.0f);
  gcps.points.emplace_back(
      0.1f, 0.1f,
      static_cast<float>((plane.offset - plane.normal.x() * 0.1 - plane.normal.y() * 0.1) /
                         plane.normal.z()));
  gcps.sigma = {0.01f, 0.02f};
  AppendGcpPoints(gcps, &cloud);
  ExpectChannelsConsistent(cloud);
  ASSERT_EQ(cloud.size(), fused + 2);
  for (size_t i = fused; i < cloud.size(); ++i) {
    EXPECT_EQ(cloud.points[i], gcps.points[i - fused]);
    EXPECT_EQ(cloud.num_views[i], 0);
    EXPECT_EQ(cloud.sigma[i], gcps.sigma[i - fused]);
    EXPECT_LT((cloud.normals[i].cast<double>() - plane.normal).norm(), 1e-4);
    EXPECT_EQ(cloud.colors[i][0], 200);
  }

  OrientedPointCloud empty;
  EXPECT_THROW(AppendGcpPoints(gcps, &empty), Error);
  gcps.sigma.pop_back();
  EXPECT_THROW(AppendGcpPoints(gcps, &cloud), Error);
}

// ---------------------------------------------------------------------------------------------
// Fusion of the synthetic courtyard

TEST(FuseDepthMaps, ExactDepthMapsGivePointsOnTheTrueSurface) {
  const synth::SyntheticScene& scene = TinyScene();
  const std::vector<FusionView> views = ViewsOf(scene);
  FusionOptions options;
  options.min_views = 3;
  FusionSummary summary;
  const OrientedPointCloud cloud = FuseDepthMaps(views, options, &summary);
  std::cout << summary.FullReport() << "\n";
  ExpectChannelsConsistent(cloud);
  ASSERT_GT(cloud.size(), 5000u);

  // Each point against the exact depth maps: of the views in which it lies inside the image, the
  // smallest relative difference between its depth and the true depth at the nearest pixel (a
  // view that sees an occluder there gives a large one).
  std::vector<double> errors;
  double color_error_sum = 0.0;
  std::int64_t color_count = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_GE(cloud.num_views[i], 3);
    double best = std::numeric_limits<double>::infinity();
    int best_view = -1;
    Eigen::Vector2i best_pixel(0, 0);
    for (size_t v = 0; v < views.size(); ++v) {
      Eigen::Vector2d pixel;
      double z = 0.0;
      if (!views[v].camera.Project(cloud.points[i].cast<double>(), &pixel, &z)) continue;
      if (!views[v].camera.InImage(pixel)) continue;
      const int col = static_cast<int>(std::lround(pixel.x()));
      const int row = static_cast<int>(std::lround(pixel.y()));
      if (col >= views[v].camera.width || row >= views[v].camera.height) continue;
      const float d = views[v].depth.at<float>(row, col);
      if (!IsValidDepth(d)) continue;
      const double e = std::abs(z - d) / d;
      if (e < best) {
        best = e;
        best_view = static_cast<int>(v);
        best_pixel = Eigen::Vector2i(col, row);
      }
    }
    ASSERT_GE(best_view, 0) << i;
    errors.push_back(best);
    const cv::Vec3b bgr = views[best_view].image_bgr.at<cv::Vec3b>(best_pixel.y(), best_pixel.x());
    for (int k = 0; k < 3; ++k) color_error_sum += std::abs(cloud.colors[i][k] - bgr[2 - k]);
    color_count += 3;
  }
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2];
  const double p99 = errors[errors.size() * 99 / 100];
  std::cout << "relative depth error: median " << median << ", p99 " << p99 << ", max "
            << errors.back() << "; mean colour difference " << color_error_sum / color_count
            << "\n";
  // The points are means of exact back-projections at neighbouring pixels: on the surface up to
  // the curvature over a pixel, and to the nearest-pixel lookup of this check (half a pixel of
  // slope).
  EXPECT_LT(median, 1e-3);
  EXPECT_LT(p99, 5e-3);
  EXPECT_LE(errors.back(), 0.011);  // the depth tolerance bounds every point
  // Colours: the mean of the views' colours (exposure differs a little per view) in RGB order.
  EXPECT_LT(color_error_sum / color_count, 12.0);
}

TEST(FuseDepthMaps, DeterministicWhateverTheThreadCount) {
  const std::vector<FusionView> views = ViewsOf(TinyScene());
  const FusionOptions options;
  const OrientedPointCloud first = FuseDepthMaps(views, options);
  ExpectSameCloud(first, FuseDepthMaps(views, options));
  OrientedPointCloud one_thread, two_threads;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one_thread = FuseDepthMaps(views, options);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two_threads = FuseDepthMaps(views, options);
  }
  ExpectSameCloud(first, one_thread);
  ExpectSameCloud(one_thread, two_threads);
}

// Not a test (wall-clock times are not asserted): the fusion of a realistic case, timed. Run with
//   gcpstereo_fusion_test --gtest_also_run_disabled_tests --gtest_filter='*Timing*'
// The 11 cameras of the "fountain" preset at half resolution (768×512), depth maps ray-traced in
// the analytic courtyard with 0.3 % multiplicative noise, grey images.
TEST(FuseDepthMaps, DISABLED_FountainHalfResolutionTiming) {
  const synth::PresetGeometry geometry = synth::MakePresetGeometry("fountain");
  const synth::AnalyticScene scene =
      synth::AnalyticScene::MakeCourtyard(geometry.texture_min_wavelength_m, 1);
  std::vector<FusionView> views;
  for (size_t v = 0; v < geometry.cameras.size(); ++v) {
    FusionView view;
    view.name = geometry.view_names[v];
    view.camera = geometry.cameras[v].Rescaled(0.5);
    const Camera& camera = view.camera;
    view.depth = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(kInvalidDepth));
    view.image_bgr = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar::all(128));
    const Eigen::Matrix3d K_inverse = camera.K.inverse();
    tbb::parallel_for(0, camera.height, [&](int row) {
      std::mt19937 rng(static_cast<unsigned>(v * 100000 + row));
      std::normal_distribution<double> noise(0.0, 0.003);
      for (int col = 0; col < camera.width; ++col) {
        const Eigen::Vector3d ray_camera = K_inverse * Eigen::Vector3d(col, row, 1.0);
        const Eigen::Vector3d direction =
            (camera.world_from_camera_rotation * ray_camera).normalized();
        synth::SurfaceHit hit;
        if (!scene.Intersect(camera.center_world, direction, 1000.0, &hit)) continue;
        const double depth = hit.t * ray_camera.z() / ray_camera.norm();
        view.depth.at<float>(row, col) = static_cast<float>(depth * (1.0 + noise(rng)));
      }
    });
    views.push_back(view);
  }
  FusionSummary summary;
  FuseDepthMaps(views, FusionOptions(), &summary);
  std::cout << summary.FullReport() << "\n";
  FusionOptions no_normal_test;
  no_normal_test.normal_tolerance_deg = 180.0;
  FuseDepthMaps(views, no_normal_test, &summary);
  std::cout << "normal_tolerance_deg = 180: " << summary.FullReport() << "\n";
}

}  // namespace
}  // namespace gcpstereo::fusion
