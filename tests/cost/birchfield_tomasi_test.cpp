// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/birchfield_tomasi.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::cost {
namespace {

cv::Mat GreyRow(const std::vector<int>& values) {
  cv::Mat row(1, static_cast<int>(values.size()), CV_8UC1);
  for (std::size_t i = 0; i < values.size(); ++i) row.at<std::uint8_t>(0, i) = values[i];
  return row;
}

// Worked by hand from Birchfield & Tomasi (1998), eqs. (1)–(3), with
// I⁻(x) = ½(I(x) + I(x−1)), I⁺(x) = ½(I(x) + I(x+1)), border pixels replicated.
TEST(BirchfieldTomasi, HandComputedGreyRow) {
  const cv::Mat left = GreyRow({10, 20, 80, 40, 40});
  const cv::Mat right = GreyRow({20, 80, 40, 40, 0});
  const std::vector<double> d = {0.0, 1.0, -1.0, 0.5, 0.25};
  const CostVolume v = ComputeBirchfieldTomasiCost(left, right, d, cv::Rect(0, 0, 5, 1));
  EXPECT_EQ(v.max_cost(), 765.0f);
  const float tol = v.cost_step();
  // x=2, d=0: L=80, L±½ = {50, 60} → [50, 80]; R(2)=40, R±½ = {60, 40} → [40, 60].
  // L→R: max(0, 80−60, 40−80) = 20; R→L: max(0, 40−80, 50−40) = 10; BT = 10.
  EXPECT_NEAR(v.Cost(0, 2, 0), 10.0f, tol);
  // x=1, d=0: L [15, 50] ∋ 20; R [50, 80] ∋ 80 → L→R 30, R→L 30.
  EXPECT_NEAR(v.Cost(0, 1, 0), 30.0f, tol);
  // x=4, d=0: L [40, 40]; R(4)=0, [0, 20] → L→R 20, R→L 40 → 20.
  EXPECT_NEAR(v.Cost(0, 4, 0), 20.0f, tol);
  // x=3, d=1 → x_r=2: L(3)=40 within R's [40, 60] → 0.
  EXPECT_NEAR(v.Cost(0, 3, 1), 0.0f, tol);
  // x=0, d=1 → x_r=−1: outside the right image.
  EXPECT_FALSE(v.HasData(0, 0, 1));
  // x=2, d=−1 → x_r=3: R(3)=40, [20, 40]; L [50, 80]: L→R 40, R→L 10 → 10.
  EXPECT_NEAR(v.Cost(0, 2, 2), 10.0f, tol);
  EXPECT_FALSE(v.HasData(0, 4, 2));
  // x=1, d=0.25 → x_r=0.75: R(0.75)=65, R(0.25)=35, R(1.25)=70 → [35, 70]; L(1)=20, [15, 50].
  // L→R: max(0, 20−70, 35−20) = 15; R→L: max(0, 65−50, 15−65) = 15 → 15.
  EXPECT_NEAR(v.Cost(0, 1, 4), 15.0f, tol);
  // x=2, d=0.5 → x_r=1.5: R(1.5)=60, R(1)=80, R(2)=40 → [40, 80] ∋ L(2)=80 → 0.
  EXPECT_NEAR(v.Cost(0, 2, 3), 0.0f, tol);
  // x=0, d=0.5 → x_r=−0.5: outside.
  EXPECT_FALSE(v.HasData(0, 0, 3));
}

// A linear ramp sampled half a pixel apart costs 0 under BT while |ΔI| = 5: the point of the
// measure (insensitivity to image sampling).
TEST(BirchfieldTomasi, InsensitiveToHalfPixelSampling) {
  std::vector<int> l, r;
  for (int x = 0; x < 20; ++x) {
    l.push_back(10 * x + 20);
    r.push_back(10 * x + 25);  // the same ramp sampled at x + ½
  }
  const CostVolume v =
      ComputeBirchfieldTomasiCost(GreyRow(l), GreyRow(r), {0.0}, cv::Rect(0, 0, 20, 1));
  for (int x = 1; x < 19; ++x) EXPECT_EQ(v.Cost(0, x, 0), 0.0f) << x;
}

// The textbook definition written out independently for RGB rows (integer and fractional d).
struct Textbook {
  const cv::Mat& left;
  const cv::Mat& right;
  static double Lerp(const cv::Mat& image, int row, int ch, double t) {
    const double max_t = image.cols - 1;
    if (t < 0) t = 0;
    if (t > max_t) t = max_t;
    const int i0 = static_cast<int>(std::floor(t));
    const int i1 = std::min(i0 + 1, image.cols - 1);
    const double f = t - i0;
    return (1 - f) * image.at<cv::Vec3b>(row, i0)[ch] + f * image.at<cv::Vec3b>(row, i1)[ch];
  }
  static double OneSided(const cv::Mat& a, double xa, const cv::Mat& b, double xb, int row,
                         int ch) {
    const double va = Lerp(a, row, ch, xa);
    const double b0 = Lerp(b, row, ch, xb), bm = Lerp(b, row, ch, xb - 0.5),
                 bp = Lerp(b, row, ch, xb + 0.5);
    const double lo = std::min({b0, bm, bp}), hi = std::max({b0, bm, bp});
    return std::max({0.0, va - hi, lo - va});
  }
  double Cost(int row, int x, double d, bool use_max) const {
    double total = 0;
    for (int ch = 0; ch < 3; ++ch) {
      const double bt = std::min(OneSided(left, x, right, x - d, row, ch),
                                 OneSided(right, x - d, left, x, row, ch));
      total = use_max ? std::max(total, bt) : total + bt;
    }
    return total;
  }
};

TEST(BirchfieldTomasi, EqualsTextbookOnRandomRgbRows) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat left(3, 30, CV_8UC3), right(3, 30, CV_8UC3);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 30; ++c) {
      left.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
      right.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
    }
  }
  const std::vector<double> d = {0, 1, 2, 3, 7, -2, 0.5, 1.75, -0.3};
  const cv::Rect region(4, 1, 22, 2);
  for (const std::string channels : {"sum", "max"}) {
    BirchfieldTomasiOptions options;
    options.channels = channels;
    options.truncation = channels == "sum" ? 200.0 : 90.0;
    const CostVolume v = ComputeBirchfieldTomasiCost(left, right, d, region, options);
    const Textbook textbook{left, right};
    for (int row = 0; row < region.height; ++row) {
      for (int col = 0; col < region.width; ++col) {
        for (std::size_t l = 0; l < d.size(); ++l) {
          const int x = region.x + col;
          const double xr = x - d[l];
          if (xr < 0 || xr > 29) {
            EXPECT_FALSE(v.HasData(row, col, l));
            continue;
          }
          const double expected = std::min(
              textbook.Cost(region.y + row, x, d[l], channels == "max"), options.truncation);
          EXPECT_NEAR(v.Cost(row, col, l), expected, 0.5 * v.cost_step() + 1e-4)
              << channels << " row " << row << " col " << col << " d " << d[l];
        }
      }
    }
  }
}

TEST(BirchfieldTomasi, SameBytesForAnyThreadCount) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat left(40, 50, CV_8UC3), right(40, 50, CV_8UC3);
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 50; ++c) {
      left.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
      right.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
    }
  const std::vector<double> d = {0, 1, 2, 3, 4, 5, 6, 7};
  const CostVolume a = ComputeBirchfieldTomasiCost(left, right, d, cv::Rect(0, 0, 50, 40));
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const CostVolume b = ComputeBirchfieldTomasiCost(left, right, d, cv::Rect(0, 0, 50, 40));
  EXPECT_EQ(0, std::memcmp(a.PixelData(0, 0), b.PixelData(0, 0), a.memory_bytes()));
}

TEST(BirchfieldTomasi, BadInputsAreReported) {
  const cv::Mat a(4, 6, CV_8UC3, cv::Scalar::all(0)), b(4, 5, CV_8UC3, cv::Scalar::all(0));
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { ComputeBirchfieldTomasiCost(a, b, {0.0}, cv::Rect(0, 0, 6, 4)); }),
            "Birchfield-Tomasi cost: the right image (5x4, 3 channels) must have the left image's "
            "size and type (6x4, 3 channels)");
  EXPECT_EQ(message([&] { ComputeBirchfieldTomasiCost(a, a, {}, cv::Rect(0, 0, 6, 4)); }),
            "Birchfield-Tomasi cost: no disparities to evaluate");
  EXPECT_EQ(message([&] { ComputeBirchfieldTomasiCost(a, a, {NAN}, cv::Rect(0, 0, 6, 4)); }),
            "Birchfield-Tomasi cost: disparity nan is not finite");
  EXPECT_EQ(message([&] { ComputeBirchfieldTomasiCost(a, a, {0.0}, cv::Rect(2, 0, 6, 4)); }),
            "Birchfield-Tomasi cost: region 6x4 at (2, 0) is empty or not inside the 6x4 left "
            "image");
  BirchfieldTomasiOptions o;
  o.channels = "mean";
  EXPECT_EQ(message([&] { ComputeBirchfieldTomasiCost(a, a, {0.0}, cv::Rect(0, 0, 6, 4), o); }),
            "cost.bt_channels = mean. Violated constraint: one of sum, max");
  o = {};
  o.truncation = -1;
  EXPECT_EQ(message([&] { o.Check(); }),
            "cost.bt_truncation = -1. Violated constraint: 0 < bt_truncation < inf");
}

// Census term by hand: one grey row, census window 3 (the rows above and below replicate the row,
// so each horizontal neighbour contributes three bits and the vertical ones compare equal → 0).
// Left ramp up, right ramp down: at x = 2, d = 0 the left centre 30 has its left neighbour darker
// and the right centre 30 its right neighbour darker → 2 positions × 3 rows = 6 differing bits.
// BT(30, 30) = 0 there, so the cost is census_weight · 6.
// Whole-pixel disparities take a faster loop (pixel by pixel, hardware popcount where the CPU
// has it); its entries are the same bytes as the general loop's, which runs for every label as
// soon as one disparity is fractional. With and without census, summed and max channels, on a
// region that does not start at the image's origin.
TEST(BirchfieldTomasiCensus, WholePixelLoopGivesTheGeneralLoopsBytes) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat left(30, 60, CV_8UC3), right(30, 60, CV_8UC3);
  for (int r = 0; r < 30; ++r)
    for (int c = 0; c < 60; ++c) {
      left.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
      right.at<cv::Vec3b>(r, c) = cv::Vec3b(value(rng), value(rng), value(rng));
    }
  const std::vector<double> whole = {0, 1, 2, 3, 5, 8, 13, 21, 34, 55};
  std::vector<double> mixed = whole;
  mixed.push_back(2.5);
  const cv::Rect region(7, 3, 53, 20);  // to the right border
  for (const int census : {1, 5}) {
    for (const std::string channels : {"sum", "max"}) {
      BirchfieldTomasiOptions options;
      options.census_window_px = census;
      options.census_weight = 1.5;
      options.truncation = 40;
      options.channels = channels;
      const CostVolume fast = ComputeBirchfieldTomasiCost(left, right, whole, region, options);
      const CostVolume general = ComputeBirchfieldTomasiCost(left, right, mixed, region, options);
      ASSERT_EQ(fast.max_cost(), general.max_cost());
      int no_data = 0;
      for (int r = 0; r < region.height; ++r) {
        for (int c = 0; c < region.width; ++c) {
          for (int l = 0; l < static_cast<int>(whole.size()); ++l) {
            ASSERT_EQ(fast.PixelData(r, c)[l], general.PixelData(r, c)[l])
                << "census " << census << " " << channels << " pixel " << r << "," << c
                << " disparity " << whole[l];
            no_data += fast.HasData(r, c, l) ? 0 : 1;
          }
        }
      }
      EXPECT_GT(no_data, 0);  // the large disparities leave the right image: both mark it
    }
  }
}

TEST(BirchfieldTomasiCensus, HandComputedHammingDistance) {
  const cv::Mat left = GreyRow({10, 20, 30, 40, 50});
  const cv::Mat right = GreyRow({50, 40, 30, 20, 10});
  BirchfieldTomasiOptions options;
  options.census_window_px = 3;
  options.census_weight = 2.0;
  options.truncation = 30;
  const CostVolume v =
      ComputeBirchfieldTomasiCost(left, right, {0.0}, cv::Rect(0, 0, 5, 1), options);
  EXPECT_EQ(v.max_cost(), 30.0f + 2.0f * 8);  // truncation + weight · (3² − 1) bits
  EXPECT_NEAR(v.Cost(0, 2, 0), 12.0f, v.cost_step());
  // x = 0: left {·, 10, 20} → right neighbour not darker, left (replicated) equal → 0 bits;
  // right {·, 50, 40} → right neighbour darker → 3 bits. BT(10, 50): L [10, 15], R [45, 50] → 30
  // (= truncation). Cost 30 + 2 · 3.
  EXPECT_NEAR(v.Cost(0, 0, 0), 36.0f, v.cost_step());
}

// The census term is invariant to a monotonic intensity change between the views (exposure,
// gain), BT is not: on a right image that is 2 · left + 1, the census-only cost (tiny BT
// truncation) is minimal at the true disparity for every pixel with texture.
TEST(BirchfieldTomasiCensus, InvariantToMonotonicIntensityChange) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> value(0, 127);
  const int w = 40, h = 12, true_d = 3;
  cv::Mat left(h, w, CV_8UC1), right(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) left.at<std::uint8_t>(r, c) = value(rng);
  }
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const int src = std::min(c + true_d, w - 1);
      right.at<std::uint8_t>(r, c) =
          static_cast<std::uint8_t>(2 * left.at<std::uint8_t>(r, src) + 1);
    }
  }
  BirchfieldTomasiOptions options;
  options.census_window_px = 5;
  options.census_weight = 1.0;
  options.truncation = 0.01;  // BT contributes at most 0.01
  const std::vector<double> d = {0, 1, 2, 3, 4, 5, 6};
  const CostVolume v = ComputeBirchfieldTomasiCost(left, right, d, cv::Rect(0, 0, w, h), options);
  // Columns whose census windows lie inside the image in both views (no border replication).
  // A local extremum has an all-equal census code and can tie with another extremum, so the
  // true disparity is the unique minimum on most, not all, pixels.
  int unique = 0, counted = 0;
  for (int r = 2; r < h - 2; ++r) {
    for (int c = 6 + 2; c < w - 2 - true_d; ++c) {
      EXPECT_LE(v.Cost(r, c, true_d), 0.01f + v.cost_step()) << r << "," << c;
      bool is_unique = true;
      for (int l = 0; l < static_cast<int>(d.size()); ++l) {
        if (l != true_d && v.Cost(r, c, l) <= 0.01f + v.cost_step()) is_unique = false;
      }
      unique += is_unique;
      ++counted;
    }
  }
  EXPECT_GT(unique, 0.9 * counted) << unique << " of " << counted;
  // BT alone is not invariant: the same pixels at the true disparity cost far more than 0.
  const CostVolume bt = ComputeBirchfieldTomasiCost(left, right, d, cv::Rect(0, 0, w, h));
  double mean_bt = 0;
  for (int r = 2; r < h - 2; ++r) {
    for (int c = 8; c < w - 2 - true_d; ++c) mean_bt += bt.Cost(r, c, true_d) / counted;
  }
  EXPECT_GT(mean_bt, 20.0);
}

// A background (grey 90…130, disparity 1) with a bright foreground square (190…230, disparity 4) at
// left columns [20, 30). Right of the square the background is seen by both views, but the census
// window of a pixel 1–3 px from the edge still holds foreground neighbours, whose bits disagree
// with the background the right view shows there. The masked census (threshold 40 separates the
// two surfaces) ignores them: the cost at the true disparity is exactly 0, where the full census
// mostly pays for them. With a threshold that keeps every neighbour the mask changes nothing.
TEST(BirchfieldTomasiCensus, MaskIgnoresNeighboursAcrossADepthEdge) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> background(90, 130), foreground(190, 230);
  const int w = 48, h = 16;
  cv::Mat back(h, w + 8, CV_8UC1), fore(h, w + 8, CV_8UC1);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w + 8; ++c) {
      back.at<std::uint8_t>(r, c) = background(rng);
      fore.at<std::uint8_t>(r, c) = foreground(rng);
    }
  }
  cv::Mat left(h, w, CV_8UC1), right(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      left.at<std::uint8_t>(r, c) =
          c >= 20 && c < 30 ? fore.at<std::uint8_t>(r, c) : back.at<std::uint8_t>(r, c);
      // Right pixel c shows the foreground where c + 4 is in [20, 30), else the background at c
      // + 1.
      right.at<std::uint8_t>(r, c) = c + 4 >= 20 && c + 4 < 30 ? fore.at<std::uint8_t>(r, c + 4)
                                                               : back.at<std::uint8_t>(r, c + 1);
    }
  }
  BirchfieldTomasiOptions options;
  options.census_window_px = 7;
  options.census_weight = 2.0;
  options.truncation = 60;
  const std::vector<double> d = {0, 1, 2, 3, 4, 5};
  const cv::Rect all(0, 0, w, h);
  const CostVolume full = ComputeBirchfieldTomasiCost(left, right, d, all, options);
  options.census_mask_threshold = 40;
  const CostVolume masked = ComputeBirchfieldTomasiCost(left, right, d, all, options);
  // A foreground neighbour is brighter than the centre (bit 0); the background the right view shows
  // in its place is darker than the centre (bit 1) about half the time, so the full census pays on
  // most of these pixels, the masked one on none.
  int full_pays = 0, counted = 0;
  for (int r = 3; r < h - 3; ++r) {
    for (int c = 31; c <= 33; ++c) {  // background pixels with foreground in their window
      EXPECT_EQ(masked.Cost(r, c, 1), 0.0f) << r << "," << c;
      full_pays += full.Cost(r, c, 1) > 0.0f;
      ++counted;
    }
  }
  EXPECT_GT(full_pays, counted / 2) << full_pays << " of " << counted;
  options.census_mask_threshold = 255;
  const CostVolume keep_all = ComputeBirchfieldTomasiCost(left, right, d, all, options);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      for (int l = 0; l < static_cast<int>(d.size()); ++l) {
        ASSERT_EQ(keep_all.Cost(r, c, l), full.Cost(r, c, l)) << r << "," << c << "," << l;
      }
    }
  }
}

TEST(BirchfieldTomasiCensus, BadOptionsNameTheKey) {
  auto message = [](const BirchfieldTomasiOptions& o) {
    try {
      o.Check();
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  BirchfieldTomasiOptions o;
  o.census_window_px = 4;
  EXPECT_EQ(message(o),
            "cost.census_window_px = 4. Violated constraint: odd and 1 <= census_window_px <= 7");
  o.census_window_px = 9;
  EXPECT_EQ(message(o),
            "cost.census_window_px = 9. Violated constraint: odd and 1 <= census_window_px <= 7");
  o = {};
  o.census_weight = -1;
  EXPECT_EQ(message(o), "cost.census_weight = -1. Violated constraint: 0 <= census_weight < inf");
  o = {};
  o.census_mask_threshold = 256;
  EXPECT_EQ(message(o),
            "cost.census_mask_threshold = 256. Violated constraint: 0 <= census_mask_threshold "
            "<= 255");
  o = {};
  o.window.window_px = 2;
  EXPECT_EQ(message(o), "cost.window_px = 2. Violated constraint: odd and 1 <= window_px <= 101");
}

}  // namespace
}  // namespace gcpstereo::cost
