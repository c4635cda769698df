// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Loaders on the real benchmark data in ../shared/data (each test skips when it is absent).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/SVD>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/types.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/point_cloud_io.h"
#include "test_data.h"

namespace gcpstereo::io {
namespace {

// Linear (DLT) triangulation of one point from two projection matrices.
Eigen::Vector3d Triangulate(const Eigen::Matrix<double, 3, 4>& P0, const Eigen::Vector2d& x0,
                            const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Vector2d& x1) {
  Eigen::Matrix4d A;
  A.row(0) = x0.x() * P0.row(2) - P0.row(0);
  A.row(1) = x0.y() * P0.row(2) - P0.row(1);
  A.row(2) = x1.x() * P1.row(2) - P1.row(0);
  A.row(3) = x1.y() * P1.row(2) - P1.row(1);
  const Eigen::Vector4d X =
      Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
  return X.head<3>() / X.w();
}

TEST(FountainP11, LoadsElevenViewsAndTriangulates) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "strecha/fountain-P11");
  DatasetRequest request;
  request.format = "strecha";
  request.path = path;
  request.reference = "0005";
  const Dataset full = LoadDataset(request);
  ASSERT_EQ(full.neighbors.size(), 10u);
  EXPECT_EQ(full.reference.image.size(), cv::Size(3072, 2048));
  EXPECT_FALSE(full.ground_truth.HasDepth());

  // A point 8 m in front of 0005's centre pixel, seen by 0004 and 0005, triangulates back.
  const Camera& cam5 = full.reference.camera;
  const View* view4 = nullptr;
  for (const View& v : full.neighbors) {
    if (v.name == "0004") view4 = &v;
  }
  ASSERT_NE(view4, nullptr);
  const Eigen::Vector3d X = cam5.BackProject(Eigen::Vector2d(1535.5, 1023.5), 8.0);
  Eigen::Vector2d x4, x5;
  double depth4 = 0.0, depth5 = 0.0;
  ASSERT_TRUE(cam5.Project(X, &x5, &depth5));
  ASSERT_TRUE(view4->camera.Project(X, &x4, &depth4));
  EXPECT_TRUE(view4->camera.InImage(x4));
  EXPECT_NEAR(depth5, 8.0, 1e-9);
  const Eigen::Vector3d back =
      Triangulate(cam5.ProjectionMatrix(), x5, view4->camera.ProjectionMatrix(), x4);
  EXPECT_LT((back - X).norm(), 1e-6);

  request.scale = 0.5;
  request.neighbors = {"0004", "0006"};
  const Dataset half = LoadDataset(request);
  ASSERT_EQ(half.neighbors.size(), 2u);
  for (const View* v : {&half.reference, &half.neighbors[0], &half.neighbors[1]}) {
    EXPECT_EQ(v->image.size(), cv::Size(1536, 1024)) << v->name;
    EXPECT_EQ(v->camera.width, 1536);
    EXPECT_EQ(v->camera.height, 1024);
  }
  // The half-size cameras see the same point at half the pixel coordinates (centre convention).
  Eigen::Vector2d x5_half;
  ASSERT_TRUE(half.reference.camera.Project(X, &x5_half, &depth5));
  EXPECT_NEAR(x5_half.x(), 0.5 * (x5.x() + 0.5) - 0.5, 1e-9);
}

TEST(FountainP11, AllElevenViewsLoadAtHalfSize) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "strecha/fountain-P11");
  const std::vector<std::string> names = ListDatasetViews("strecha", path);
  ASSERT_EQ(names.size(), 11u);
  EXPECT_EQ(names.front(), "0000");
  EXPECT_EQ(names.back(), "0010");
  DatasetRequest request;
  request.format = "strecha";
  request.path = path;
  request.reference = "0005";
  request.scale = 0.5;
  const Dataset d = LoadDataset(request);
  ASSERT_EQ(d.neighbors.size(), 10u);
  for (const View& v : d.neighbors) EXPECT_EQ(v.image.size(), cv::Size(1536, 1024)) << v.name;
}

struct DisparityStats {
  double min = 1e30, max = -1e30;
  int valid = 0;
};

DisparityStats Stats(const cv::Mat& disparity) {
  DisparityStats s;
  for (int r = 0; r < disparity.rows; ++r) {
    for (int c = 0; c < disparity.cols; ++c) {
      const float d = disparity.at<float>(r, c);
      if (!std::isfinite(d)) continue;
      s.min = std::min<double>(s.min, d);
      s.max = std::max<double>(s.max, d);
      ++s.valid;
    }
  }
  return s;
}

// Mean absolute grey difference between the reference pixels (where `use` and the GT depth are
// valid) and the neighbour pixel the cameras predict for depth = numerator / disparity, shifted by
// `shift_px` along x (the epipolar line of rectified views).
double MeanPhotometricError(const Dataset& d, const View& neighbor, const cv::Mat& use,
                            double shift_px) {
  cv::Mat ref_gray, nb_gray;
  cv::cvtColor(d.reference.image, ref_gray, cv::COLOR_BGR2GRAY);
  cv::cvtColor(neighbor.image, nb_gray, cv::COLOR_BGR2GRAY);
  double sum = 0.0;
  int count = 0;
  for (int r = 0; r < ref_gray.rows; ++r) {
    for (int c = 0; c < ref_gray.cols; ++c) {
      if (!use.empty() && use.at<std::uint8_t>(r, c) != 255) continue;
      const float disparity = d.ground_truth.disparity.at<float>(r, c);
      if (!std::isfinite(disparity)) continue;
      const double depth = d.disparity_numerator / disparity;
      const Eigen::Vector3d X = d.reference.camera.BackProject(Eigen::Vector2d(c, r), depth);
      Eigen::Vector2d x;
      double z = 0.0;
      if (!neighbor.camera.Project(X, &x, &z)) continue;
      const int xc = static_cast<int>(std::lround(x.x() + shift_px));
      const int yr = static_cast<int>(std::lround(x.y()));
      if (xc < 0 || yr < 0 || xc >= nb_gray.cols || yr >= nb_gray.rows) continue;
      sum += std::abs(int(ref_gray.at<std::uint8_t>(r, c)) - int(nb_gray.at<std::uint8_t>(yr, xc)));
      ++count;
    }
  }
  EXPECT_GT(count, 1000);
  return sum / std::max(count, 1);
}

// GT disparity + cameras predict where each reference pixel appears in every neighbour: the
// colours agree there much better than 2 px to either side. (A wrong disparity scale or camera
// spacing moves the prediction by many pixels in the farther views.)
void ExpectGroundTruthIsPhotoConsistent(const Dataset& d, const cv::Mat& use) {
  for (const View& neighbor : d.neighbors) {
    const double at_gt = MeanPhotometricError(d, neighbor, use, 0.0);
    const double left = MeanPhotometricError(d, neighbor, use, -2.0);
    const double right = MeanPhotometricError(d, neighbor, use, 2.0);
    EXPECT_LT(at_gt, 0.6 * std::min(left, right))
        << neighbor.name << ": " << at_gt << " vs " << left << " / " << right;
    std::printf("%s -> %s: mean |dgrey| %.2f at GT, %.2f / %.2f at -/+2 px\n",
                d.reference.name.c_str(), neighbor.name.c_str(), at_gt, left, right);
  }
}

TEST(Middlebury, TsukubaDisparityScaleAndMasks) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "middlebury/tsukuba");
  DatasetRequest request;
  request.format = "middlebury";
  request.path = path;
  request.reference = "scene1.row3.col3";
  request.neighbors = {"scene1.row3.col4", "scene1.row3.col2", "scene1.row3.col5"};
  const Dataset d = LoadDataset(request);
  EXPECT_EQ(d.reference.image.size(), cv::Size(384, 288));
  EXPECT_DOUBLE_EQ(d.disparity_numerator, 384.0);  // f = 384 px, one step
  const DisparityStats s = Stats(d.ground_truth.disparity);
  EXPECT_NEAR(s.min, 5.0, 1.0);
  EXPECT_NEAR(s.max, 14.0, 1.5);
  EXPECT_FALSE(d.ground_truth.mask_nonocc.empty());
  EXPECT_FALSE(d.ground_truth.mask_all.empty());
  EXPECT_FALSE(d.ground_truth.mask_disc.empty());
  ExpectGroundTruthIsPhotoConsistent(d, d.ground_truth.mask_nonocc);
}

TEST(Middlebury, VenusDisparityScaleAndRightMap) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "middlebury/venus");
  DatasetRequest request;
  request.format = "middlebury";
  request.path = path;
  request.reference = "im2";
  request.neighbors = {"im6", "im3", "im1", "im4"};
  const Dataset d = LoadDataset(request);
  EXPECT_EQ(d.reference.image.size(), cv::Size(434, 383));
  EXPECT_DOUBLE_EQ(d.disparity_numerator, 434.0 * 4);
  const DisparityStats s = Stats(d.ground_truth.disparity);
  EXPECT_NEAR(s.min, 3.0, 1.0);
  EXPECT_NEAR(s.max, 20.0, 1.5);
  ASSERT_FALSE(d.ground_truth.disparity_right.empty());
  EXPECT_FALSE(d.ground_truth.mask_nonocc.empty());
  // Left-right consistency of disp2/disp6 in the non-occluded area: a pixel x of im2 appears at
  // x − d in im6, where im6's map holds (nearly) the same disparity.
  int consistent = 0, total = 0;
  for (int r = 0; r < d.reference.image.rows; ++r) {
    for (int c = 0; c < d.reference.image.cols; ++c) {
      if (d.ground_truth.mask_nonocc.at<std::uint8_t>(r, c) != 255) continue;
      const float dl = d.ground_truth.disparity.at<float>(r, c);
      const int xr = static_cast<int>(std::lround(c - dl));
      if (xr < 0) continue;
      ++total;
      consistent += std::abs(d.ground_truth.disparity_right.at<float>(r, xr) - dl) <= 1.0f;
    }
  }
  EXPECT_GT(consistent, 0.95 * total);
  ExpectGroundTruthIsPhotoConsistent(d, d.ground_truth.mask_nonocc);

  request.scale = 0.5;
  const Dataset half = LoadDataset(request);
  EXPECT_EQ(half.reference.image.size(), cv::Size(217, 192));
  const DisparityStats hs = Stats(half.ground_truth.disparity);
  EXPECT_NEAR(hs.max, 0.5 * s.max, 0.5);
  EXPECT_NEAR(half.disparity_numerator, 0.5 * d.disparity_numerator, 1e-9);
}

TEST(Middlebury, Aloe2006DisparityScale) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "middlebury/Aloe");
  DatasetRequest request;
  request.format = "middlebury";
  request.path = path;
  request.reference = "view1";
  request.neighbors = {"view5", "view2", "view0"};
  const Dataset d = LoadDataset(request);
  const int width = d.reference.image.cols;
  EXPECT_LT(width, 600);  // third size
  EXPECT_DOUBLE_EQ(d.disparity_numerator, width * 4.0);
  ASSERT_TRUE(d.ground_truth.HasDisparity());
  ASSERT_FALSE(d.ground_truth.disparity_right.empty());
  EXPECT_TRUE(d.ground_truth.mask_nonocc.empty());  // the 2006 sets have no masks
  const DisparityStats s = Stats(d.ground_truth.disparity);
  EXPECT_GT(s.min, 5.0);
  EXPECT_LT(s.max, 90.0);
  EXPECT_GT(s.valid, 0.7 * d.reference.image.total());
  ExpectGroundTruthIsPhotoConsistent(d, cv::Mat());
}

TEST(Kitti, VelodyneProjectsOntoMatchingColours) {
  GCPSTEREO_REQUIRE_SHARED_DATA(drive, "kitti/2011_09_26/2011_09_26_drive_0009_sync");
  DatasetRequest request;
  request.format = "kitti_raw";
  request.path = drive;
  request.reference = "0000000010";
  const Dataset d = LoadDataset(request);
  EXPECT_EQ(d.reference.image.size(), cv::Size(1242, 375));
  ASSERT_EQ(d.neighbors.size(), 1u);
  EXPECT_NEAR(d.disparity_numerator / d.reference.camera.K(0, 0), 0.532, 0.01);  // baseline m
  const PointCloud cloud = ReadPointCloud(KittiVelodynePath(drive, "0000000010"));
  EXPECT_GT(cloud.size(), 50000u);
  ASSERT_EQ(cloud.intensity.size(), cloud.size());

  cv::Mat left, right;
  cv::cvtColor(d.reference.image, left, cv::COLOR_BGR2GRAY);
  cv::cvtColor(d.neighbors[0].image, right, cv::COLOR_BGR2GRAY);
  // Mean |Δgrey| at the prediction, at −8 px, +8 px, and (a finer check of the geometry) ±2 px.
  double sum[5] = {0, 0, 0, 0, 0};
  int count = 0;
  for (const Eigen::Vector3f& p : cloud.points) {
    const Eigen::Vector4d X = d.world_from_lidar * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    Eigen::Vector2d xl, xr;
    double zl = 0.0, zr = 0.0;
    if (!d.reference.camera.Project(X.head<3>(), &xl, &zl) || zl < 3.0) continue;
    if (!d.neighbors[0].camera.Project(X.head<3>(), &xr, &zr)) continue;
    // The predicted disparity agrees with the rectified model.
    EXPECT_NEAR(xl.x() - xr.x(), d.disparity_numerator / zl, 0.05);
    const int ul = static_cast<int>(std::lround(xl.x())),
              vl = static_cast<int>(std::lround(xl.y()));
    const int ur = static_cast<int>(std::lround(xr.x())),
              vr = static_cast<int>(std::lround(xr.y()));
    if (vl < 0 || vl >= left.rows || ul < 0 || ul >= left.cols) continue;
    if (vr < 0 || vr >= right.rows || ur - 8 < 0 || ur + 8 >= right.cols) continue;
    const int l = left.at<std::uint8_t>(vl, ul);
    sum[0] += std::abs(l - right.at<std::uint8_t>(vr, ur));
    sum[1] += std::abs(l - right.at<std::uint8_t>(vr, ur - 8));
    sum[2] += std::abs(l - right.at<std::uint8_t>(vr, ur + 8));
    sum[3] += std::abs(l - right.at<std::uint8_t>(vr, ur - 2));
    sum[4] += std::abs(l - right.at<std::uint8_t>(vr, ur + 2));
    ++count;
  }
  ASSERT_GT(count, 5000);
  const double at_prediction = sum[0] / count;
  EXPECT_LT(at_prediction, 0.7 * sum[1] / count);
  EXPECT_LT(at_prediction, 0.7 * sum[2] / count);
  EXPECT_LT(at_prediction, 0.95 * sum[3] / count);
  EXPECT_LT(at_prediction, 0.95 * sum[4] / count);
  RecordProperty("mean_abs_diff_at_prediction", std::to_string(at_prediction));
  std::printf(
      "KITTI: %d points, mean |dgrey| at prediction %.2f, at -8/+8 px %.2f/%.2f, "
      "at -2/+2 px %.2f/%.2f\n",
      count, at_prediction, sum[1] / count, sum[2] / count, sum[3] / count, sum[4] / count);
}

}  // namespace
}  // namespace gcpstereo::io
