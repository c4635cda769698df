// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Middlebury rectified multi-view scenes with their official file names:
//   tsukuba (2001)       scene1.row3.col1…col5.ppm, GT truedisp.row3.col3.pgm: disparity = I/16 for
//                        col3↔col4 (one view step)
//   2001 / 2003 sets     im0…im8.ppm (2001, e.g. venus) or .png (2003 quarter size, cones/teddy),
//                        GT disp2 / disp6 (.pgm: I/8, .png: I/4) for the im2↔im6 pair (4 steps)
//   2005 / 2006 sets     view0…view6.png, GT disp1.png / disp5.png for view1↔view5 (4 steps):
//                        I/3 at third size (width ≤ 600 px), I/2 at half size (≤ 1000 px), I at
//                        full size
//   masks                nonocc.png, all.png, disc.png when present (they describe the left view
//                        of the GT pair: col3 / im2 / view1)
// Stored value 0 = unknown (→ +inf).
//
// Camera model (an arbitrary metric scale: Middlebury publishes no calibration). Views are
// rectified and equally spaced along x, numbered left to right; view i gets
//   RectifiedSequenceCamera(f = image width in px, cx = (width − 1)/2, cy = (height − 1)/2,
//                           B = 1 unit per view step, index = i, width, height),
// i.e. identity rotation and centre (i, 0, 0). A point at depth Z then moves f/Z px per view step,
// so the GT pair of k view steps has disparity k f / Z and
//   disparity_numerator = f · B · k   (disparity in the GT convention = numerator / depth),
// depth = numerator / disparity in "view-step units". Only ratios matter to the algorithms.
// With dataset.scale = s: images are resized (INTER_AREA), cameras use Camera::Rescaled (f → s f),
// GT disparities and masks are resized nearest-neighbour and disparities multiplied by s, so the
// numerator is s f B k and depths are unchanged.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "dataset_internal.h"
#include "gcpstereo/core/camera.h"
#include "gcpstereo/core/error.h"
#include "gcpstereo/core/logging.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"

namespace fs = std::filesystem;

namespace gcpstereo::io {
namespace {

struct MiddleburyView {
  std::string name;  // file name without extension, e.g. "im2"
  std::string file;
  int index = 0;  // position along x, in view steps
};

struct MiddleburyLayout {
  std::string family;
  std::vector<MiddleburyView> views;  // sorted by index
  // The ground-truth pair: left view (its map, masks) and right view (its map), k steps apart.
  std::string gt_left_view, gt_left_file;
  std::string gt_right_view, gt_right_file;
  double divisor = 1.0;  // disparity = stored value / divisor; 0 = from the image width (2005/6)
  int gt_steps = 1;
};

MiddleburyLayout DetectLayout(const std::string& path) {
  const std::regex tsukuba(R"(scene1\.row3\.col(\d)\.(ppm|png))");
  const std::regex im(R"(im(\d)\.(ppm|png))");
  const std::regex view(R"(view(\d)\.png)");
  std::vector<MiddleburyView> tsukuba_views, im_views, view_views;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(path, ec)) {
    if (!entry.is_regular_file()) continue;
    const std::string file = entry.path().filename().string();
    const std::string stem = entry.path().stem().string();
    std::smatch m;
    if (std::regex_match(file, m, tsukuba)) {
      tsukuba_views.push_back({stem, file, std::stoi(m[1]) - 1});
    } else if (std::regex_match(file, m, im)) {
      im_views.push_back({stem, file, std::stoi(m[1])});
    } else if (std::regex_match(file, m, view)) {
      view_views.push_back({stem, file, std::stoi(m[1])});
    }
  }
  if (ec) throw IoError(path, "cannot list folder: " + ec.message());

  MiddleburyLayout layout;
  auto first_existing = [&path](std::initializer_list<const char*> names) -> std::string {
    for (const char* n : names) {
      if (internal::IsFile((fs::path(path) / n).string())) return n;
    }
    return "";
  };
  if (!tsukuba_views.empty()) {
    layout.family = "tsukuba";
    layout.views = tsukuba_views;
    layout.gt_left_view = "scene1.row3.col3";
    layout.gt_left_file = first_existing({"truedisp.row3.col3.pgm", "truedisp.row3.col3.png"});
    layout.divisor = 16.0;
    layout.gt_steps = 1;
  } else if (!im_views.empty()) {
    layout.views = im_views;
    layout.gt_left_view = "im2";
    layout.gt_right_view = "im6";
    layout.gt_left_file = first_existing({"disp2.pgm", "disp2.png"});
    layout.gt_right_file = first_existing({"disp6.pgm", "disp6.png"});
    // 2001 sets ship 8-bit PGMs scaled by 8; the 2003 quarter-size PNGs are scaled by 4.
    const bool png =
        internal::LowerExtension(layout.gt_left_file.empty() ? layout.gt_right_file
                                                             : layout.gt_left_file) == ".png";
    layout.family = png ? "2003" : "2001";
    layout.divisor = png ? 4.0 : 8.0;
    layout.gt_steps = 4;
  } else if (!view_views.empty()) {
    layout.family = "2005/2006";
    layout.views = view_views;
    layout.gt_left_view = "view1";
    layout.gt_right_view = "view5";
    layout.gt_left_file = first_existing({"disp1.png"});
    layout.gt_right_file = first_existing({"disp5.png"});
    layout.divisor = 0.0;  // from the image width, see ResolveDivisor
    layout.gt_steps = 4;
  } else {
    throw IoError(path,
                  "not a Middlebury scene folder: expected scene1.row3.colN.ppm (tsukuba), "
                  "imN.ppm/png (2001/2003) or viewN.png (2005/2006) files");
  }
  std::sort(layout.views.begin(), layout.views.end(),
            [](const MiddleburyView& a, const MiddleburyView& b) { return a.index < b.index; });
  for (std::size_t i = 1; i < layout.views.size(); ++i) {
    if (layout.views[i].index == layout.views[i - 1].index) {
      throw IoError(path, "two images for view '" + layout.views[i].name +
                              "': " + layout.views[i - 1].file + " and " + layout.views[i].file);
    }
  }
  return layout;
}

// 2005/2006 sets come at full (≈1390 px wide), half (≈695) and third (≈463) size; their disparity
// PNGs store the full-size disparity, so the disparity at the stored size is I/3 (third size),
// I/2 (half size) or I (full size). The size is recognised from the image width.
double ResolveDivisor(const MiddleburyLayout& layout, int image_width) {
  if (layout.divisor > 0.0) return layout.divisor;
  if (image_width <= 600) return 3.0;
  if (image_width <= 1000) return 2.0;
  return 1.0;
}

// Reads a Middlebury disparity image (8-bit, 0 = unknown) as CV_32F disparity (unknown = +inf).
cv::Mat ReadDisparity(const std::string& file, double divisor, const cv::Size& expected_size) {
  cv::Mat stored = ReadImage(file, cv::IMREAD_UNCHANGED);
  if (stored.channels() == 3) cv::cvtColor(stored, stored, cv::COLOR_BGR2GRAY);
  if (stored.channels() != 1 || (stored.depth() != CV_8U && stored.depth() != CV_16U)) {
    throw IoError(file, "expected an 8- or 16-bit grey disparity image, got " +
                            cv::typeToString(stored.type()));
  }
  if (stored.size() != expected_size) {
    std::ostringstream s;
    s << "ground-truth disparity is " << stored.cols << "x" << stored.rows << ", the images are "
      << expected_size.width << "x" << expected_size.height;
    throw IoError(file, s.str());
  }
  cv::Mat disparity;
  stored.convertTo(disparity, CV_32F, 1.0 / divisor);
  disparity.setTo(kInvalidDepth, stored == 0);
  return disparity;
}

cv::Mat ReadMask(const std::string& file, const cv::Size& expected_size) {
  cv::Mat mask = ReadImage(file, cv::IMREAD_GRAYSCALE);
  if (mask.size() != expected_size) {
    std::ostringstream s;
    s << "mask is " << mask.cols << "x" << mask.rows << ", the images are " << expected_size.width
      << "x" << expected_size.height;
    throw IoError(file, s.str());
  }
  return mask;
}

// Resizes a disparity map for the scale and multiplies the values by it (+inf stays +inf).
cv::Mat ScaleDisparity(const cv::Mat& disparity, const cv::Size& size, double scale) {
  if (disparity.empty()) return disparity;
  cv::Mat out = internal::ResizeNearest(disparity, size).clone();
  if (scale != 1.0) out *= scale;
  return out;
}

}  // namespace

namespace internal {

std::vector<std::string> MiddleburyViewNames(const std::string& path) {
  std::vector<std::string> names;
  for (const auto& v : DetectLayout(path).views) names.push_back(v.name);
  return names;
}

}  // namespace internal

Dataset LoadMiddleburyDataset(const DatasetRequest& request) {
  internal::CheckRequest(request);
  const MiddleburyLayout layout = DetectLayout(request.path);
  std::vector<std::string> names;
  for (const auto& v : layout.views) names.push_back(v.name);
  std::vector<std::string> neighbor_names;
  internal::ResolveViewNames(request, names, &neighbor_names);
  if (!request.load_neighbors) neighbor_names.clear();
  auto find_view = [&layout](const std::string& name) {
    return *std::find_if(layout.views.begin(), layout.views.end(),
                         [&name](const MiddleburyView& v) { return v.name == name; });
  };

  Dataset dataset;
  dataset.format = "middlebury";
  dataset.path = request.path;
  dataset.rectified = true;
  dataset.world_from_lidar.setIdentity();

  cv::Size full_size;
  std::string reference_file;  // named in a size mismatch: which file the size came from
  double focal_px = 0.0;
  auto load_view = [&](const std::string& name) {
    const MiddleburyView& v = find_view(name);
    const std::string file = (fs::path(request.path) / v.file).string();
    View view;
    view.name = name;
    view.image = ReadColorImage(file);
    if (full_size.empty()) {
      full_size = view.image.size();
      reference_file = v.file;
      focal_px = full_size.width;
    } else if (view.image.size() != full_size) {
      std::ostringstream s;
      s << "image is " << view.image.cols << "x" << view.image.rows << ", the reference "
        << reference_file << " is " << full_size.width << "x" << full_size.height
        << " (views of a rectified set must match)";
      throw IoError(file, s.str());
    }
    constexpr double kBaselinePerView = 1.0;  // arbitrary unit: one view step
    view.camera =
        RectifiedSequenceCamera(focal_px, 0.5 * (full_size.width - 1), 0.5 * (full_size.height - 1),
                                kBaselinePerView, v.index, full_size.width, full_size.height);
    if (request.scale != 1.0) {
      view.camera = view.camera.Rescaled(request.scale);
      view.image =
          internal::ResizeImage(view.image, cv::Size(view.camera.width, view.camera.height));
    }
    return view;
  };
  dataset.reference = load_view(request.reference);
  for (const auto& name : neighbor_names) dataset.neighbors.push_back(load_view(name));
  const double scaled_focal_px = dataset.reference.camera.K(0, 0);
  dataset.disparity_numerator = scaled_focal_px * 1.0 * layout.gt_steps;

  // Ground truth: the GT pair's left view carries its map, the other map (for occlusion checks)
  // and the masks; its right view carries its own map.
  const cv::Size scaled_size = dataset.reference.image.size();
  const double divisor = ResolveDivisor(layout, full_size.width);
  const fs::path dir(request.path);
  GroundTruth& gt = dataset.ground_truth;
  if (request.reference == layout.gt_left_view && !layout.gt_left_file.empty()) {
    gt.disparity = ReadDisparity((dir / layout.gt_left_file).string(), divisor, full_size);
    if (!layout.gt_right_file.empty()) {
      gt.disparity_right = ReadDisparity((dir / layout.gt_right_file).string(), divisor, full_size);
    }
    if (internal::IsFile((dir / "nonocc.png").string())) {
      gt.mask_nonocc = ReadMask((dir / "nonocc.png").string(), full_size);
    }
    if (internal::IsFile((dir / "all.png").string())) {
      gt.mask_all = ReadMask((dir / "all.png").string(), full_size);
    }
    if (internal::IsFile((dir / "disc.png").string())) {
      gt.mask_disc = ReadMask((dir / "disc.png").string(), full_size);
    }
  } else if (request.reference == layout.gt_right_view && !layout.gt_right_file.empty()) {
    gt.disparity = ReadDisparity((dir / layout.gt_right_file).string(), divisor, full_size);
  }
  gt.disparity = ScaleDisparity(gt.disparity, scaled_size, request.scale);
  gt.disparity_right = ScaleDisparity(gt.disparity_right, scaled_size, request.scale);
  gt.mask_nonocc = internal::ResizeNearest(gt.mask_nonocc, scaled_size);
  gt.mask_all = internal::ResizeNearest(gt.mask_all, scaled_size);
  gt.mask_disc = internal::ResizeNearest(gt.mask_disc, scaled_size);
  if (gt.HasDisparity()) {
    gt.depth = cv::Mat(scaled_size, CV_32F);
    for (int r = 0; r < scaled_size.height; ++r) {
      const float* d = gt.disparity.ptr<float>(r);
      float* z = gt.depth.ptr<float>(r);
      for (int c = 0; c < scaled_size.width; ++c) {
        z[c] = std::isfinite(d[c]) && d[c] > 0.0f
                   ? static_cast<float>(dataset.disparity_numerator / d[c])
                   : kInvalidDepth;
      }
    }
  }
  spdlog::info("middlebury {} ({}): reference {} + {} neighbours, {}x{}, GT disparity {}",
               request.path, layout.family, request.reference, dataset.neighbors.size(),
               scaled_size.width, scaled_size.height,
               gt.HasDisparity() ? "I/" + std::to_string(divisor) : std::string("absent"));
  return dataset;
}

}  // namespace gcpstereo::io
