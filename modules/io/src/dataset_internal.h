// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Helpers shared by the data set loaders (strecha_io.cc, middlebury_io.cc, kitti_io.cc,
// colmap_dataset_io.cc).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "gcpstereo/core/types.h"
#include "gcpstereo/io/dataset_io.h"

namespace gcpstereo::io::internal {

// Throws ConfigError unless 0 < request.scale <= 4 (finite) and the path names a folder.
void CheckRequest(const DatasetRequest& request);

// "a, b, c".
std::string JoinNames(const std::vector<std::string>& names);

// Resolves the reference and neighbour names against the views a data set offers. An empty
// neighbour list means every other view (in `available` order). Throws ConfigError naming the key
// (dataset.reference / dataset.neighbors), the unknown name and the valid names; duplicate
// neighbours and the reference listed as its own neighbour are errors too.
void ResolveViewNames(const DatasetRequest& request, const std::vector<std::string>& available,
                      std::vector<std::string>* neighbors);

// Resizes an image to `size` for the dataset scale (cv::INTER_AREA; no-op when equal).
cv::Mat ResizeImage(const cv::Mat& image, cv::Size size);

// Nearest-neighbour resize for maps whose values must not be mixed (depth, disparity, masks).
cv::Mat ResizeNearest(const cv::Mat& map, cv::Size size);

// Lower-case file extension including the dot ("" when none).
std::string LowerExtension(const std::string& path);

// The view names of each format (ListDatasetViews dispatches to them).
std::vector<std::string> StrechaViewNames(const std::string& path);
std::vector<std::string> MiddleburyViewNames(const std::string& path);
std::vector<std::string> KittiFrameNames(const std::string& drive_path);
std::vector<std::string> ColmapViewNames(const std::string& path);

bool IsFile(const std::string& path);
bool IsFolder(const std::string& path);

}  // namespace gcpstereo::io::internal
