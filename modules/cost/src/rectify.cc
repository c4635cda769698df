// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/rectify.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace gcpstereo::cost {

RectifiedCalibratedPair RectifyCalibratedPair(const View& reference, const View& neighbor) {
  const cv::Size size = reference.image.size();
  const Camera& ref_camera = reference.camera;
  const Camera& nb_camera = neighbor.camera;
  // Relative pose, camera 1 = reference: X_nb = R X_ref + T.
  const Eigen::Matrix3d r_rel =
      nb_camera.world_from_camera_rotation.transpose() * ref_camera.world_from_camera_rotation;
  const Eigen::Vector3d t_rel = nb_camera.world_from_camera_rotation.transpose() *
                                (ref_camera.center_world - nb_camera.center_world);
  cv::Mat k1, k2, r, t;
  cv::eigen2cv(ref_camera.K, k1);
  cv::eigen2cv(nb_camera.K, k2);
  cv::eigen2cv(r_rel, r);
  cv::eigen2cv(t_rel, t);
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(k1, cv::noArray(), k2, cv::noArray(), size, r, t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 1.0, size);
  RectifiedCalibratedPair pair;
  if (std::abs(p2.at<double>(1, 3)) > std::abs(p2.at<double>(0, 3))) {
    pair.vertical = true;
    return pair;
  }
  pair.focal_px = p1.at<double>(0, 0);
  pair.cx = p1.at<double>(0, 2);
  pair.cy = p1.at<double>(1, 2);
  pair.baseline = std::abs(p2.at<double>(0, 3)) / pair.focal_px;
  pair.mirrored = p2.at<double>(0, 3) > 0.0;  // neighbour left of the reference
  Eigen::Matrix3d rect_from_ref;
  cv::cv2eigen(r1, rect_from_ref);
  pair.ref_from_rect = rect_from_ref.transpose();

  auto rectify = [&](const cv::Mat& image, const cv::Mat& k, const cv::Mat& rect,
                     const cv::Mat& projection, cv::Mat* out, cv::Mat* valid) {
    cv::Mat map_x, map_y;
    cv::initUndistortRectifyMap(k, cv::noArray(), rect, projection, size, CV_32FC1, map_x, map_y);
    cv::remap(image, *out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    const cv::Mat ones(image.size(), CV_8U, cv::Scalar(255));
    cv::remap(ones, *valid, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    cv::erode(*valid, *valid, cv::Mat());
    if (pair.mirrored) {
      cv::flip(*out, *out, 1);
      cv::flip(*valid, *valid, 1);
    }
  };
  rectify(reference.image, k1, r1, p1, &pair.left, &pair.left_valid);
  rectify(neighbor.image, k2, r2, p2, &pair.right, &pair.right_valid);
  return pair;
}

std::vector<std::size_t> NeighborsByDistance(const View& reference,
                                             const std::vector<View>& neighbors) {
  std::vector<std::size_t> order(neighbors.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return (neighbors[a].camera.center_world - reference.camera.center_world).norm() <
           (neighbors[b].camera.center_world - reference.camera.center_world).norm();
  });
  return order;
}

}  // namespace gcpstereo::cost
