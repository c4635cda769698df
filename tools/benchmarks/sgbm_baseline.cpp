// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// gcpstereo_sgbm_baseline: OpenCV's semi-global block matching on a rectified pair, as the
// baseline the benchmark script (tools/benchmark.py) measures gcpstereo against.
//
// Method: Hirschmüller, "Stereo Processing by Semiglobal Matching and Mutual Information", PAMI
// 2008, as implemented by cv::StereoSGBM (Birchfield–Tomasi sub-pixel cost on a Sobel-prefiltered
// image summed over block_size × block_size windows; paths: 8 with MODE_HH, 4 with MODE_HH4, 5
// with MODE_SGBM (single pass), and MODE_SGBM_3WAY, OpenCV's fastest variant, the default here).
// Smoothness: E(D) = Σ_p C(p, D_p) + Σ_{q∈N_p} P1·[|D_p − D_q| = 1] + P2·[|D_p − D_q| > 1].
// Parameters (defaults = the values OpenCV's stereo_match sample uses for colour images):
//   P1 = 8 · 3 · block_size²   (penalty for a disparity change of one pixel; 3 = channels)
//   P2 = 32 · 3 · block_size²  (penalty for larger changes)
//   disp12MaxDiff = 1 px       (left-right consistency check)
//   preFilterCap = 63, uniquenessRatio = 10 %, speckleWindowSize = 100 px,
//   speckleRange = 32 (= 2 px in OpenCV's 1/16-px units).
// Output: the reference (left) view's disparity in pixels as float32; pixels SGBM leaves invalid
// (left border without a match, failed uniqueness/left-right checks, removed speckles) are +inf,
// multiplied by --scale (1 for the ground-truth pairs). Written as PFM in the Middlebury 2014
// convention (header "Pf", "W H", "-1.0", rows bottom to top) with gcpstereo::io::WritePfm.
//
// Input: either two image files (--left, --right) or a data set through gcpstereo's loaders
// (--format middlebury|kitti_raw --path DIR --reference NAME [--neighbor NAME]): the reference is
// the left image and the first neighbour the right one, so the disparity is in the data set's
// ground-truth convention when the pair is the ground-truth pair (Middlebury im2/im6, col3/col4,
// view1/view5; KITTI left/right).
// With --lidar-holdout (kitti_raw), the frame's Velodyne scan is projected and split exactly as
// `gcpstereo run … --set eval.lidar_holdout=true` does (gcp::SplitScanForHoldout: 8×8 checkerboard,
// visible points only; with --lidar-motion registration the scan is first motion-compensated
// as gcp.lidar.motion.mode registration does, pipeline::LoadLidarScan) and SGBM is scored on the
// held-out points (KITTI-style bad-3, bad-1), so its numbers compare one to one with the pipeline's
// metrics.lidar_holdout.result. With --filled-output, a second map is written whose invalid pixels
// are filled as the KITTI stereo devkit does before scoring sparse submissions (io_disp.h,
// interpolateBackground: each invalid run inside a row takes the smaller, i.e. background,
// disparity of its two valid neighbours; row ends and then column ends are extrapolated from the
// nearest valid pixel); the hold-out scores are then reported for both maps.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/system.h"
#include "gcpstereo/core/types.h"
#include "gcpstereo/eval/lidar.h"
#include "gcpstereo/gcp/lidar_holdout.h"
#include "gcpstereo/io/atomic_file.h"
#include "gcpstereo/io/dataset_io.h"
#include "gcpstereo/io/image_io.h"
#include "gcpstereo/io/pfm.h"
#include "gcpstereo/pipeline/lidar_scan.h"

namespace {

using gcpstereo::ConfigError;
using nlohmann::json;

struct SgbmArgs {
  // Input: files …
  std::string left_path, right_path;
  // … or a data set.
  std::string format, dataset_path, reference, neighbor;
  // Output.
  std::string output_path, report_path;
  std::string filled_output_path;  // optional: the KITTI-devkit background-filled map
  // SGBM parameters (see the file comment). Range: num_disparities > 0 and divisible by 16;
  // block_size odd, >= 1; p1/p2 < 0 = the defaults from block_size; p2 > p1.
  int num_disparities = 64;  // px, search range [min_disparity, min_disparity + num_disparities)
  int min_disparity = 0;     // px
  int block_size = 5;        // px, matching window side
  int p1 = -1;               // default 8·3·block_size²
  int p2 = -1;               // default 32·3·block_size²
  int disp12_max_diff = 1;   // px, < 0 disables the left-right check
  int pre_filter_cap = 63;
  int uniqueness_ratio = 10;       // percent
  int speckle_window_size = 100;   // px, 0 disables speckle filtering
  int speckle_range = 32;          // in 1/16 px
  std::string mode = "sgbm_3way";  // sgbm_3way, sgbm or hh
  double scale = 1.0;  // factor from the pair's disparity to the ground truth's convention
  int repeat = 1;      // runs of compute() for the timing (the minimum is reported)
  bool lidar_holdout = false;
  int holdout_block_px = 8;
  std::string lidar_motion = "off";  // gcp.lidar.motion.mode: off | registration
};

int ModeOf(const std::string& mode) {
  if (mode == "sgbm_3way") return cv::StereoSGBM::MODE_SGBM_3WAY;
  if (mode == "sgbm") return cv::StereoSGBM::MODE_SGBM;
  if (mode == "hh") return cv::StereoSGBM::MODE_HH;
  if (mode == "hh4") return cv::StereoSGBM::MODE_HH4;
  throw ConfigError("--mode: '" + mode + "' is not one of sgbm_3way, sgbm, hh, hh4");
}

void CheckArgs(const SgbmArgs& a) {
  if (a.num_disparities <= 0 || a.num_disparities % 16 != 0) {
    throw ConfigError("--num-disparities = " + std::to_string(a.num_disparities) +
                      ". Violated constraint: > 0 and divisible by 16 (OpenCV)");
  }
  if (a.block_size < 1 || a.block_size % 2 == 0) {
    throw ConfigError("--block-size = " + std::to_string(a.block_size) +
                      ". Violated constraint: odd and >= 1");
  }
  if (!(a.scale > 0.0) || !std::isfinite(a.scale)) {
    throw ConfigError("--scale = " + std::to_string(a.scale) + ". Violated constraint: > 0");
  }
  if (a.repeat < 1) {
    throw ConfigError("--repeat = " + std::to_string(a.repeat) + ". Violated constraint: >= 1");
  }
  const bool files = !a.left_path.empty() || !a.right_path.empty();
  const bool dataset = !a.format.empty() || !a.dataset_path.empty();
  if (files == dataset) {
    throw ConfigError("give either --left and --right, or --format, --path and --reference");
  }
  if (files && (a.left_path.empty() || a.right_path.empty())) {
    throw ConfigError("--left and --right go together");
  }
  if (dataset && (a.format.empty() || a.dataset_path.empty() || a.reference.empty())) {
    throw ConfigError("--format, --path and --reference go together");
  }
  if (a.lidar_holdout && a.format != "kitti_raw") {
    throw ConfigError("--lidar-holdout needs --format kitti_raw");
  }
}

// The reference view's disparity in px (+inf = invalid), times `scale`.
cv::Mat ToFloatDisparity(const cv::Mat& fixed_point, int min_disparity, double scale) {
  cv::Mat disparity;
  fixed_point.convertTo(disparity, CV_32F, scale / cv::StereoMatcher::DISP_SCALE);
  // OpenCV marks invalid pixels with (min_disparity − 1) · 16.
  disparity.setTo(std::numeric_limits<float>::infinity(),
                  fixed_point < min_disparity * cv::StereoMatcher::DISP_SCALE);
  return disparity;
}

// The KITTI stereo devkit's interpolateBackground (devkit_stereo_flow io_disp.h) on a float map
// with non-finite = invalid. A map without any valid pixel stays as it is.
cv::Mat FillBackground(const cv::Mat& disparity) {
  cv::Mat d = disparity.clone();
  const int width = d.cols, height = d.rows;
  auto valid = [&](int u, int v) { return std::isfinite(d.at<float>(v, u)); };
  for (int v = 0; v < height; ++v) {
    int count = 0;
    for (int u = 0; u < width; ++u) {
      if (valid(u, v)) {
        if (count >= 1) {
          const int u1 = u - count, u2 = u - 1;
          if (u1 > 0 && u2 < width - 1) {
            const float fill = std::min(d.at<float>(v, u1 - 1), d.at<float>(v, u2 + 1));
            for (int k = u1; k <= u2; ++k) d.at<float>(v, k) = fill;
          }
        }
        count = 0;
      } else {
        ++count;
      }
    }
    for (int u = 0; u < width; ++u) {  // extrapolate to the left
      if (valid(u, v)) {
        for (int k = 0; k < u; ++k) d.at<float>(v, k) = d.at<float>(v, u);
        break;
      }
    }
    for (int u = width - 1; u >= 0; --u) {  // extrapolate to the right
      if (valid(u, v)) {
        for (int k = u + 1; k < width; ++k) d.at<float>(v, k) = d.at<float>(v, u);
        break;
      }
    }
  }
  for (int u = 0; u < width; ++u) {
    for (int v = 0; v < height; ++v) {  // extrapolate to the top
      if (valid(u, v)) {
        for (int k = 0; k < v; ++k) d.at<float>(k, u) = d.at<float>(v, u);
        break;
      }
    }
    for (int v = height - 1; v >= 0; --v) {  // extrapolate to the bottom
      if (valid(u, v)) {
        for (int k = v + 1; k < height; ++k) d.at<float>(k, u) = d.at<float>(v, u);
        break;
      }
    }
  }
  return d;
}

int Main(int argc, char** argv) {
  SgbmArgs a;
  CLI::App app{
      "gcpstereo_sgbm_baseline — OpenCV StereoSGBM on a rectified pair (left = "
      "reference), disparity written as PFM (+inf = invalid); the baseline of "
      "tools/benchmark.py"};
  app.add_option("--left", a.left_path, "left (reference) image file");
  app.add_option("--right", a.right_path, "right image file");
  app.add_option("--format", a.format, "data set format instead of files: middlebury or kitti_raw");
  app.add_option("--path", a.dataset_path, "data set folder (kitti_raw: the drive folder)");
  app.add_option("--reference", a.reference,
                 "reference (left) view: im2, scene1.row3.col3, "
                 "view1, or the KITTI frame 0000000010");
  app.add_option("--neighbor", a.neighbor, "right view (middlebury; kitti_raw: ignored)");
  app.add_option("-o,--output", a.output_path, "disparity PFM to write")->required();
  app.add_option("--filled-output", a.filled_output_path,
                 "also write the map with invalid pixels filled as the KITTI devkit does "
                 "(background interpolation)");
  app.add_option("--report", a.report_path,
                 "write parameters, timing (and hold-out scores) as JSON");
  app.add_option("--num-disparities", a.num_disparities, "search range, px, multiple of 16")
      ->capture_default_str();
  app.add_option("--min-disparity", a.min_disparity, "smallest disparity, px")
      ->capture_default_str();
  app.add_option("--block-size", a.block_size, "matching block side, odd, px")
      ->capture_default_str();
  app.add_option("--p1", a.p1, "penalty for ±1 px changes (default 8·3·block²)");
  app.add_option("--p2", a.p2, "penalty for larger changes (default 32·3·block²)");
  app.add_option("--disp12-max-diff", a.disp12_max_diff, "left-right check tolerance, px (<0: off)")
      ->capture_default_str();
  app.add_option("--pre-filter-cap", a.pre_filter_cap)->capture_default_str();
  app.add_option("--uniqueness-ratio", a.uniqueness_ratio, "percent")->capture_default_str();
  app.add_option("--speckle-window-size", a.speckle_window_size, "px (0: no speckle filter)")
      ->capture_default_str();
  app.add_option("--speckle-range", a.speckle_range, "1/16 px")->capture_default_str();
  app.add_option("--mode", a.mode, "sgbm_3way, sgbm (5 paths), hh (8 paths) or hh4")
      ->capture_default_str();
  app.add_option("--scale", a.scale,
                 "multiply the disparity into the ground truth's convention "
                 "(1 on the ground-truth pair)")
      ->capture_default_str();
  app.add_option("--repeat", a.repeat, "run SGBM this many times and report the fastest")
      ->capture_default_str();
  app.add_flag("--lidar-holdout", a.lidar_holdout,
               "kitti_raw: score against the held-out half of the Velodyne scan, split exactly as "
               "gcpstereo run --set eval.lidar_holdout=true");
  app.add_option("--lidar-motion", a.lidar_motion,
                 "kitti_raw: off, or registration to compensate the sweep's motion first, as "
                 "gcp.lidar.motion.mode registration does (configs/kitti_lidar.yaml)")
      ->check(CLI::IsMember({"off", "registration"}))
      ->capture_default_str();
  app.add_option("--holdout-block", a.holdout_block_px,
                 "checkerboard block, px (eval.holdout_block_px)")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  CheckArgs(a);

  gcpstereo::Timer load_timer;
  cv::Mat left, right;
  gcpstereo::Dataset dataset;
  if (!a.left_path.empty()) {
    left = gcpstereo::io::ReadColorImage(a.left_path);
    right = gcpstereo::io::ReadColorImage(a.right_path);
  } else {
    gcpstereo::io::DatasetRequest request;
    request.format = a.format;
    request.path = a.dataset_path;
    request.reference = a.reference;
    if (!a.neighbor.empty()) request.neighbors = {a.neighbor};
    dataset = gcpstereo::io::LoadDataset(request);
    if (!dataset.rectified || dataset.neighbors.empty()) {
      throw ConfigError("--format " + a.format + ": SGBM needs a rectified pair");
    }
    left = dataset.reference.image;
    right = dataset.neighbors.front().image;
  }
  if (left.size() != right.size()) {
    throw gcpstereo::Error("the left and right images differ in size");
  }
  const double load_seconds = load_timer.ElapsedSeconds();

  const int channels = left.channels();
  const int p1 = a.p1 >= 0 ? a.p1 : 8 * channels * a.block_size * a.block_size;
  const int p2 = a.p2 >= 0 ? a.p2 : 32 * channels * a.block_size * a.block_size;
  if (p2 <= p1) {
    throw ConfigError("--p2 = " + std::to_string(p2) + ". Violated constraint: > --p1 (" +
                      std::to_string(p1) + ")");
  }
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      a.min_disparity, a.num_disparities, a.block_size, p1, p2, a.disp12_max_diff, a.pre_filter_cap,
      a.uniqueness_ratio, a.speckle_window_size, a.speckle_range, ModeOf(a.mode));
  cv::Mat fixed_point;
  double best_seconds = std::numeric_limits<double>::infinity();
  for (int i = 0; i < a.repeat; ++i) {
    gcpstereo::Timer timer;
    sgbm->compute(left, right, fixed_point);
    best_seconds = std::min(best_seconds, timer.ElapsedSeconds());
  }
  const cv::Mat disparity = ToFloatDisparity(fixed_point, a.min_disparity, a.scale);
  const int invalid = cv::countNonZero(disparity == std::numeric_limits<float>::infinity());
  const double invalid_percent = 100.0 * invalid / static_cast<double>(disparity.total());
  gcpstereo::io::WritePfm(a.output_path, disparity);
  cv::Mat filled;
  if (!a.filled_output_path.empty()) {
    filled = FillBackground(disparity);
    gcpstereo::io::WritePfm(a.filled_output_path, filled);
  }

  json report = {{"method", "cv::StereoSGBM"},
                 {"opencv_version", CV_VERSION},
                 {"width", left.cols},
                 {"height", left.rows},
                 {"parameters",
                  {{"mode", a.mode},
                   {"min_disparity", a.min_disparity},
                   {"num_disparities", a.num_disparities},
                   {"block_size", a.block_size},
                   {"p1", p1},
                   {"p2", p2},
                   {"disp12_max_diff", a.disp12_max_diff},
                   {"pre_filter_cap", a.pre_filter_cap},
                   {"uniqueness_ratio", a.uniqueness_ratio},
                   {"speckle_window_size", a.speckle_window_size},
                   {"speckle_range", a.speckle_range},
                   {"scale", a.scale}}},
                 {"seconds", best_seconds},
                 {"repeat", a.repeat},
                 {"load_seconds", load_seconds},
                 {"threads", cv::getNumThreads()},
                 {"invalid_percent", invalid_percent},
                 {"output", a.output_path}};
  if (!filled.empty()) report["filled_output"] = a.filled_output_path;

  if (a.lidar_holdout) {
    // The same split as `gcpstereo run --set eval.lidar_holdout=true` (gcp::SplitScanForHoldout
    // with the default gcp.lidar.* options, as in configs/kitti_lidar.yaml): the visible points of
    // the scoring blocks, in disparity = numerator / depth.
    const std::string scan_path = gcpstereo::io::KittiVelodynePath(a.dataset_path, a.reference);
    gcpstereo::gcp::LidarMotionOptions motion;
    motion.mode = a.lidar_motion;
    const gcpstereo::PointCloud cloud =
        gcpstereo::pipeline::LoadLidarScan(scan_path, a.dataset_path, a.reference, motion);
    const std::vector<gcpstereo::eval::ReferencePoint> held_out =
        gcpstereo::gcp::SplitScanForHoldout(
            cloud, dataset.world_from_lidar, dataset.reference.camera,
            gcpstereo::gcp::LidarGcpOptions{}, a.holdout_block_px, dataset.disparity_numerator)
            .scored;
    report["lidar_holdout"] = {
        {"scan", scan_path},
        {"lidar_motion", a.lidar_motion},
        {"block_px", a.holdout_block_px},
        {"points", held_out.size()},
        {"result", gcpstereo::eval::EvaluateAgainstPoints(disparity, held_out).ToJson()}};
    if (!filled.empty()) {
      report["lidar_holdout"]["filled"] =
          gcpstereo::eval::EvaluateAgainstPoints(filled, held_out).ToJson();
    }
  }

  std::printf(
      "sgbm: %dx%d, disparities %d…%d, block %d, mode %s: %.3f s (%d threads), %.1f %% "
      "invalid -> %s\n",
      left.cols, left.rows, a.min_disparity, a.min_disparity + a.num_disparities - 1, a.block_size,
      a.mode.c_str(), best_seconds, cv::getNumThreads(), invalid_percent, a.output_path.c_str());
  if (report.contains("lidar_holdout")) {
    const json& r = report["lidar_holdout"]["result"];
    std::printf("sgbm: held-out LiDAR points %lld: bad-3 %.2f %%, bad-1 %.2f %%\n",
                static_cast<long long>(r.value("counted", 0LL)), r.value("bad3_percent", 0.0),
                r.value("bad1_percent", 0.0));
    if (report["lidar_holdout"].contains("filled")) {
      const json& f = report["lidar_holdout"]["filled"];
      std::printf("sgbm: background-filled map: bad-3 %.2f %%, bad-1 %.2f %%\n",
                  f.value("bad3_percent", 0.0), f.value("bad1_percent", 0.0));
    }
  }
  if (!a.report_path.empty()) {
    const std::string text = report.dump(2) + "\n";
    gcpstereo::io::WriteBytesAtomically(a.report_path, text.data(), text.size());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const gcpstereo::Error& e) {
    std::fprintf(stderr, "gcpstereo_sgbm_baseline: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gcpstereo_sgbm_baseline: internal error: %s\n", e.what());
    return 2;
  }
}
