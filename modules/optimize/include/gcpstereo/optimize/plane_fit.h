// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
// Segment-wise plane fitting of a disparity map, after the global optimisation.
//
// The reference image is over-segmented by colour (Felzenszwalb & Huttenlocher's graph-based
// segmentation, OpenCV ximgproc) and in every segment a plane d = a·x + b·y + c is fitted robustly
// (RANSAC, then least squares on its inliers) to the disparities of the segment's support pixels.
// Where nearly all of a segment lies on its plane, the pixels off it take the plane's value: a
// small colour segment rarely straddles a depth edge, so its few pixels that disagree with the
// rest are foreground fattened over it or mismatches in weak texture. Over a 3-D plane the
// disparity of a rectified pair is affine in the image coordinates, so slanted surfaces are fitted
// exactly. A segment with too few support pixels, or whose support is not mostly on one plane
// (a curved surface, a segment across a depth edge), is left as it is. By default only pixels
// nearer than their plane are changed (foreground fattened over the segment), and the caller can
// freeze pixels whose value another rule set (e.g. the background fill of half-occluded pixels).
#pragma once

#include <opencv2/core/mat.hpp>

namespace gcpstereo::optimize {

// The colour over-segmentation (also used by the pipeline to keep E_gcp in segments that hold a
// GCP, optimizer.prior_segment_k).
struct SegmentationOptions {
  double sigma = 0.5;       // Gaussian smoothing before segmenting, px (> 0)
  double k = 50.0;          // Felzenszwalb's scale k: larger = larger segments
  int min_segment_px = 20;  // smaller segments are merged into a neighbour
};

struct PlaneFitOptions {
  SegmentationOptions segmentation;
  int min_support_px = 20;            // a segment with fewer support pixels is left alone
  double inlier_px = 1.0;             // |d − plane| ≤ this: the pixel lies on the plane
  double min_inlier_fraction = 0.95;  // of the support pixels, for the plane to be used
  int ransac_iterations = 100;        // random triples per segment (deterministic seeds)
  // false: only the pixels off the plane take its value (the rest keep theirs); true: every
  // finite pixel of an accepted segment takes the plane's value.
  bool replace_all = false;
  // Only pixels nearer than their plane (larger disparity) take its value: the fattening of a
  // foreground over the segment, not the segment's own relief.
  bool only_farther = true;
};

struct PlaneFitSummary {
  int segments = 0;         // segments of the image
  int fitted_segments = 0;  // segments whose plane was used
  int changed_pixels = 0;   // pixels whose disparity changed
  cv::Mat segment_labels;   // the colour segmentation (SegmentImage)
};

// Labels of the colour segmentation of `image_bgr` (CV_8UC3): CV_32S, 0 … segments − 1.
cv::Mat SegmentImage(const cv::Mat& image_bgr, const SegmentationOptions& options);

// Fits the planes and rewrites `disparity` (CV_32F, the reference's size; NaN or ±inf = unknown,
// never support and never changed). `support` is CV_8U with 255 where a pixel may support a fit
// (e.g. the left-right consistent ones), or empty for every finite pixel; `frozen` is CV_8U with
// 255 where a pixel must keep its value, or empty for none. Every other pixel of an accepted
// segment is compared with the plane, support or not. Same result for any thread count. Throws
// Error on bad input.
PlaneFitSummary FitSegmentPlanes(const cv::Mat& image_bgr, const cv::Mat& support,
                                 const cv::Mat& frozen, const PlaneFitOptions& options,
                                 cv::Mat* disparity);

}  // namespace gcpstereo::optimize
