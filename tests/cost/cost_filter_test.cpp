// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/cost/cost_filter.h"

#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "gcpstereo/core/error.h"
#include "gcpstereo/cost/birchfield_tomasi.h"
#include "gcpstereo/cost/plane_sweep.h"

namespace gcpstereo::cost {
namespace {

bool SameBytes(const CostVolume& a, const CostVolume& b) {
  if (a.region() != b.region() || a.num_labels() != b.num_labels() ||
      a.max_cost() != b.max_cost()) {
    return false;
  }
  for (int r = 0; r < a.height(); ++r) {
    for (int c = 0; c < a.width(); ++c) {
      if (std::memcmp(a.PixelData(r, c), b.PixelData(r, c),
                      sizeof(std::uint16_t) * a.num_labels()) != 0) {
        return false;
      }
    }
  }
  return true;
}

cv::Mat RandomImage(int rows, int cols, int type, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  cv::Mat image(rows, cols, type);
  for (auto it = image.begin<std::uint8_t>(); it != image.end<std::uint8_t>(); ++it) {
    *it = static_cast<std::uint8_t>(value(rng));
  }
  // Some spatial structure: blocks of constant colour plus noise.
  cv::Mat blocks(rows / 4 + 1, cols / 4 + 1, type);
  for (auto it = blocks.begin<std::uint8_t>(); it != blocks.end<std::uint8_t>(); ++it) {
    *it = static_cast<std::uint8_t>(value(rng));
  }
  cv::Mat big;
  cv::resize(blocks, big, cv::Size(), 4, 4, cv::INTER_NEAREST);
  cv::addWeighted(big(cv::Rect(0, 0, cols, rows)), 0.8, image, 0.2, 0, image);
  return image;
}

// One row, box window 3 (the 3×3 window clipped to the single row is horizontal): hand means,
// with the no-data entry replaced by its nearest neighbour with data for the filter only.
TEST(CostFilter, BoxMeanHandComputedWithNoData) {
  CostVolume raw(cv::Rect(0, 0, 4, 1), 1, 100.0f);
  raw.SetNoData(0, 0, 0);
  raw.SetCost(0, 1, 0, 10);
  raw.SetCost(0, 2, 0, 20);
  raw.SetCost(0, 3, 0, 60);
  CostFilterOptions options;
  options.window_px = 3;
  options.filter = "box";
  const cv::Mat guide(1, 4, CV_8UC1, cv::Scalar(0));
  const CostVolume out = FilterCostVolume(raw, guide, raw.region(), options);
  const float tol = out.cost_step();
  EXPECT_EQ(out.max_cost(), 100.0f);
  EXPECT_FALSE(out.HasData(0, 0, 0));                          // stays without data
  EXPECT_NEAR(out.Cost(0, 1, 0), (10 + 10 + 20) / 3.0f, tol);  // filled ND = 10
  EXPECT_NEAR(out.Cost(0, 2, 0), (10 + 20 + 60) / 3.0f, tol);
  EXPECT_NEAR(out.Cost(0, 3, 0), (20 + 60) / 2.0f, tol);  // window clipped at the border
}

// 3×3 box on a 3×3 grid: the centre is the mean of all nine, a corner the mean of its 2×2 block.
TEST(CostFilter, BoxMeanTwoDimensional) {
  CostVolume raw(cv::Rect(5, 7, 3, 3), 2, 1000.0f);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      raw.SetCost(r, c, 0, static_cast<float>(10 * (3 * r + c)));  // 0 … 80
      raw.SetCost(r, c, 1, 500.0f);
    }
  }
  CostFilterOptions options;
  options.window_px = 3;
  options.filter = "box";
  const cv::Mat guide(20, 20, CV_8UC3, cv::Scalar(1, 2, 3));
  const CostVolume out = FilterCostVolume(raw, guide, cv::Rect(6, 8, 2, 2), options);
  ASSERT_EQ(out.region(), cv::Rect(6, 8, 2, 2));
  const float tol = out.cost_step();
  EXPECT_NEAR(out.Cost(0, 0, 0), 40.0f, tol);                                 // centre (1,1) of raw
  EXPECT_NEAR(out.Cost(1, 1, 0), (40 + 50 + 70 + 80) / 4.0f, tol);            // corner (2,2)
  EXPECT_NEAR(out.Cost(0, 1, 0), (10 + 20 + 40 + 50 + 70 + 80) / 6.0f, tol);  // edge (1,2)
  EXPECT_NEAR(out.Cost(1, 0, 1), 500.0f, tol);
}

// With a constant guide the guided filter has var(I) = 0, so a = 0, b = mean c and the output
// is the box mean of the box mean (He et al., eq. 8 with a ≡ 0).
TEST(CostFilter, GuidedWithConstantGuideIsTwoBoxMeans) {
  CostVolume raw(cv::Rect(0, 0, 7, 5), 1, 100.0f);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> value(0.0f, 100.0f);
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 7; ++c) raw.SetCost(r, c, 0, value(rng));
  }
  const cv::Mat guide(5, 7, CV_8UC3, cv::Scalar(90, 120, 30));
  CostFilterOptions box, guided;
  box.window_px = guided.window_px = 3;
  box.filter = "box";
  const CostVolume once = FilterCostVolume(raw, guide, raw.region(), box);
  const CostVolume twice = FilterCostVolume(once, guide, raw.region(), box);
  const CostVolume out = FilterCostVolume(raw, guide, raw.region(), guided);
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 7; ++c) {
      EXPECT_NEAR(out.Cost(r, c, 0), twice.Cost(r, c, 0), 3 * out.cost_step()) << r << "," << c;
    }
  }
}

// The point of the guided filter: a cost step that coincides with a colour edge survives (the box
// mean smears it over the window), in grey and in colour guides.
TEST(CostFilter, GuidedKeepsCostStepAtColourEdge) {
  for (const int type : {CV_8UC1, CV_8UC3}) {
    const int w = 20, h = 9;
    cv::Mat guide(h, w, type, cv::Scalar::all(40));
    guide(cv::Rect(10, 0, 10, h)).setTo(cv::Scalar::all(200));
    CostVolume raw(cv::Rect(0, 0, w, h), 1, 100.0f);
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) raw.SetCost(r, c, 0, c < 10 ? 0.0f : 80.0f);
    }
    CostFilterOptions guided, box;
    guided.window_px = box.window_px = 7;
    box.filter = "box";
    const CostVolume g = FilterCostVolume(raw, guide, raw.region(), guided);
    const CostVolume b = FilterCostVolume(raw, guide, raw.region(), box);
    for (int c = 7; c <= 12; ++c) {
      const float expected = c < 10 ? 0.0f : 80.0f;
      EXPECT_NEAR(g.Cost(4, c, 0), expected, 0.5f) << "type " << type << " col " << c;
    }
    EXPECT_GT(b.Cost(4, 9, 0), 20.0f);  // the box mean blurs the step
    EXPECT_LT(b.Cost(4, 10, 0), 60.0f);
  }
}

// He et al.'s guided filter written out directly, one pixel and one window at a time in double
// precision, on a raw volume over `outer` (windows clipped to it), for one label.
double ReferenceGuided(const CostVolume& raw, const cv::Mat& guide, int label, int radius,
                       double epsilon, int row, int col, bool guided) {
  const cv::Rect outer = raw.region();
  const int w = outer.width, h = outer.height, k = guide.channels();
  // The slice with entries without data replaced by the nearest entry of the row (ties left).
  auto cost = [&](int r, int c) {
    for (int d = 0; d < w; ++d) {
      for (const int x : {c - d, c + d}) {
        if (x >= 0 && x < w && raw.HasData(r, x, label)) return double(raw.Cost(r, x, label));
      }
    }
    return double(raw.max_cost());
  };
  auto level = [&](int r, int c, int ch) {
    return guide.ptr<std::uint8_t>(outer.y + r)[(outer.x + c) * k + ch] / 255.0;
  };
  auto window = [&](int r, int c, auto&& f) {
    double sum = 0.0;
    int n = 0;
    for (int y = std::max(r - radius, 0); y <= std::min(r + radius, h - 1); ++y) {
      for (int x = std::max(c - radius, 0); x <= std::min(c + radius, w - 1); ++x, ++n) {
        sum += f(y, x);
      }
    }
    return sum / n;
  };
  if (!guided) return window(row, col, cost);
  // a (k coefficients) and b of the window centred at (r, c).
  auto coefficients = [&](int r, int c) {
    cv::Matx33d sigma = cv::Matx33d::eye() * epsilon;
    if (k == 1) sigma = cv::Matx33d::eye();
    cv::Vec3d mean_i, cov;
    const double mean_c = window(r, c, cost);
    for (int i = 0; i < k; ++i) {
      mean_i[i] = window(r, c, [&](int y, int x) { return level(y, x, i); });
      cov[i] = window(r, c, [&](int y, int x) { return level(y, x, i) * cost(y, x); }) -
               mean_i[i] * mean_c;
    }
    for (int i = 0; i < k; ++i) {
      for (int j = 0; j < k; ++j) {
        sigma(i, j) = window(r, c, [&](int y, int x) { return level(y, x, i) * level(y, x, j); }) -
                      mean_i[i] * mean_i[j] + (i == j ? epsilon : 0.0);
      }
    }
    const cv::Vec3d a = sigma.inv() * cov;
    double b = mean_c;
    for (int i = 0; i < k; ++i) b -= a[i] * mean_i[i];
    return std::make_pair(a, b);
  };
  double q = 0.0;
  int n = 0;
  cv::Vec3d mean_a;
  for (int y = std::max(row - radius, 0); y <= std::min(row + radius, h - 1); ++y) {
    for (int x = std::max(col - radius, 0); x <= std::min(col + radius, w - 1); ++x, ++n) {
      const auto [a, b] = coefficients(y, x);
      mean_a += a;
      q += b;
    }
  }
  q /= n;
  for (int i = 0; i < k; ++i) q += mean_a[i] / n * level(row, col, i);
  return q;
}

// The streaming filter (4 labels side by side, running sums, rings of rows) against the filter
// written out directly: grey and colour guides, box and guided, windows 3 and 7, a label count
// that is not a multiple of 4, entries without data, a region inside a larger volume. Equal to a
// quantisation step (the two round differently only where a value falls on a step's edge).
TEST(CostFilter, StreamingFilterEqualsTheFilterWrittenOut) {
  const cv::Rect outer(3, 2, 23, 17), region(6, 4, 15, 12);
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> stored(0, 65534);
  std::bernoulli_distribution no_data(0.04);
  CostVolume raw(outer, 6, 90.0f);
  for (int r = 0; r < outer.height; ++r) {
    for (int c = 0; c < outer.width; ++c) {
      for (int l = 0; l < 6; ++l) {
        // Label 5 has a whole row without data (max_cost for the filter).
        const bool empty = (l == 5 && r == 7) || no_data(rng);
        raw.MutablePixelData(r, c)[l] =
            empty ? CostVolume::kNoData : static_cast<std::uint16_t>(stored(rng));
      }
    }
  }
  for (const int type : {CV_8UC1, CV_8UC3}) {
    const cv::Mat guide = RandomImage(24, 30, type, 23);
    for (const std::string filter : {"guided", "box"}) {
      for (const int window : {3, 7}) {
        CostFilterOptions options;
        options.filter = filter;
        options.window_px = window;
        options.guided_epsilon = 1e-3;
        const CostVolume out = FilterCostVolume(raw, guide, region, options);
        double worst = 0.0;
        for (int r = 0; r < region.height; ++r) {
          for (int c = 0; c < region.width; ++c) {
            const int rr = region.y - outer.y + r, cc = region.x - outer.x + c;
            for (int l = 0; l < 6; ++l) {
              if (!raw.HasData(rr, cc, l)) {
                EXPECT_FALSE(out.HasData(r, c, l));
                continue;
              }
              const double expected =
                  std::clamp(ReferenceGuided(raw, guide, l, (window - 1) / 2, 1e-3, rr, cc,
                                             filter == "guided"),
                             0.0, double(raw.max_cost()));
              worst = std::max(worst, std::abs(out.Cost(r, c, l) - expected));
            }
          }
        }
        EXPECT_LE(worst, out.cost_step() * 1.001)
            << "type " << type << " " << filter << " window " << window;
      }
    }
  }
}

// Rows wider than a filter task's strip of columns (128): the strips' seams give the filter
// written out, a tile at another offset (other seams) is a crop of the whole image, and an entry
// without data is filled from the nearest entry of the whole row even when that lies in another
// strip (disparity 200.5 leaves the 300-px row's first 201 pixels without data).
TEST(CostFilter, WideRowsFilteredInStripsGiveTheWholeRowsResult) {
  const cv::Mat left = RandomImage(14, 300, CV_8UC3, 31);
  const cv::Mat right = RandomImage(14, 300, CV_8UC3, 32);
  const std::vector<double> d = {0, 3, 40, 150, 200.5};
  BirchfieldTomasiOptions options;
  options.truncation = 60;
  options.census_window_px = 5;
  options.census_weight = 2;
  options.window.window_px = 5;
  const cv::Rect full(0, 0, 300, 14);
  const CostVolume whole = ComputeBirchfieldTomasiCost(left, right, d, full, options);
  for (const cv::Rect tile : {cv::Rect(50, 2, 230, 10), cv::Rect(120, 0, 180, 14)}) {
    const CostVolume part = ComputeBirchfieldTomasiCost(left, right, d, tile, options);
    for (int r = 0; r < tile.height; ++r) {
      for (int c = 0; c < tile.width; ++c) {
        ASSERT_EQ(std::memcmp(part.PixelData(r, c), whole.PixelData(tile.y + r, tile.x + c),
                              sizeof(std::uint16_t) * d.size()),
                  0)
            << "tile (" << tile.x << "," << tile.y << ") pixel " << r << "," << c;
      }
    }
  }
  // Against the filter written out, at the seams of the whole image's strips and at the border.
  BirchfieldTomasiOptions pixelwise = options;
  pixelwise.window.window_px = 1;
  const CostVolume raw = ComputeBirchfieldTomasiCost(left, right, d, full, pixelwise);
  double worst = 0.0;
  int checked = 0;
  for (const int c : {0, 1, 2, 125, 126, 127, 128, 129, 130, 200, 201, 255, 256, 257, 299}) {
    for (const int r : {0, 6, 13}) {
      for (int l = 0; l < static_cast<int>(d.size()); ++l) {
        if (!raw.HasData(r, c, l)) {
          EXPECT_FALSE(whole.HasData(r, c, l));
          continue;
        }
        const double expected = std::clamp(
            ReferenceGuided(raw, left, l, 2, options.window.guided_epsilon, r, c, true), 0.0,
            double(raw.max_cost()));
        worst = std::max(worst, std::abs(whole.Cost(r, c, l) - expected));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_LE(worst, whole.cost_step() * 1.001);

  // An entry without data whose nearest entry lies in the strip before: columns 124–129 have no
  // data, the second strip's columns start at 128 and its span at 124, and 126's nearest entry
  // with data is 123, outside that span, which reaches the output at 130 through the windows.
  CostVolume gap(full, 2, 90.0f);
  std::mt19937 rng(41);
  std::uniform_int_distribution<int> stored(0, 65534);
  for (int r = 0; r < gap.height(); ++r) {
    for (int c = 0; c < gap.width(); ++c) {
      for (int l = 0; l < 2; ++l) {
        gap.MutablePixelData(r, c)[l] = (l == 0 && c >= 124 && c <= 129)
                                            ? CostVolume::kNoData
                                            : static_cast<std::uint16_t>(stored(rng));
      }
    }
  }
  const CostVolume filtered = FilterCostVolume(gap, left, full, options.window);
  worst = 0.0;
  for (int c = 116; c <= 136; ++c) {
    for (const int r : {0, 7, 13}) {
      if (c >= 124 && c <= 129) continue;
      const double expected = std::clamp(
          ReferenceGuided(gap, left, 0, 2, options.window.guided_epsilon, r, c, true), 0.0, 90.0);
      worst = std::max(worst, std::abs(filtered.Cost(r, c, 0) - expected));
    }
  }
  EXPECT_LE(worst, filtered.cost_step() * 1.001);
}

BirchfieldTomasiOptions CensusGuided() {
  BirchfieldTomasiOptions options;
  options.truncation = 60;
  options.census_window_px = 5;
  options.census_weight = 2;
  options.window.window_px = 5;
  return options;
}

// A tile's costs equal the same pixels' costs of the whole image (the filter's margin is computed
// from the image, not from the tile), for box and guided filters.
TEST(CostFilter, BirchfieldTomasiTileIsCropOfWholeImage) {
  const cv::Mat left = RandomImage(30, 40, CV_8UC3, 1);
  const cv::Mat right = RandomImage(30, 40, CV_8UC3, 2);
  const std::vector<double> d = {0, 1, 2.5, 4, 7};
  for (const std::string filter : {"guided", "box"}) {
    BirchfieldTomasiOptions options = CensusGuided();
    options.window.filter = filter;
    const cv::Rect full(0, 0, 40, 30);
    const CostVolume whole = ComputeBirchfieldTomasiCost(left, right, d, full, options);
    for (const cv::Rect tile : {cv::Rect(0, 0, 13, 11), cv::Rect(9, 6, 17, 12),
                                cv::Rect(31, 20, 9, 10), cv::Rect(3, 25, 30, 1)}) {
      const CostVolume part = ComputeBirchfieldTomasiCost(left, right, d, tile, options);
      ASSERT_EQ(part.max_cost(), whole.max_cost());
      for (int r = 0; r < tile.height; ++r) {
        for (int c = 0; c < tile.width; ++c) {
          ASSERT_EQ(std::memcmp(part.PixelData(r, c), whole.PixelData(tile.y + r, tile.x + c),
                                sizeof(std::uint16_t) * d.size()),
                    0)
              << filter << " tile (" << tile.x << "," << tile.y << ") pixel " << r << "," << c;
        }
      }
    }
  }
}

// Random label bands over a region's 8-pixel blocks: some blocks without labels, some with all,
// the others a few labels, partly beyond the label range.
LabelBands RandomBands(const cv::Size& size, int num_labels, unsigned seed) {
  LabelBands bands;
  bands.block_px = 8;
  const int bx = (size.width + 7) / 8, by = (size.height + 7) / 8;
  bands.lo.create(by, bx, CV_32S);
  bands.hi.create(by, bx, CV_32S);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> kind(0, 9), start(-3, num_labels), width(0, 6);
  for (int y = 0; y < by; ++y) {
    for (int x = 0; x < bx; ++x) {
      int lo = 0, hi = num_labels - 1;
      const int k = kind(rng);
      if (k == 0) {
        lo = 1, hi = 0;  // none
      } else if (k > 2) {
        lo = start(rng);
        hi = lo + width(rng);
      }
      bands.lo.at<int>(y, x) = lo;
      bands.hi.at<int>(y, x) = hi;
    }
  }
  return bands;
}

// A volume computed with label bands holds the full volume's entries inside them and, outside,
// kNoData where there is no data and the largest cost elsewhere: whole-pixel and fractional
// disparities, guided, box and no window, a tile at an offset and the whole image (the filter's
// row ranges cut inside the image, strips of 128 columns, groups of 32 labels).
TEST(CostFilter, LabelBandsHoldTheFullVolumesEntries) {
  const cv::Mat left = RandomImage(70, 300, CV_8UC3, 51);
  const cv::Mat right = RandomImage(70, 300, CV_8UC3, 52);
  std::vector<double> whole_pixels, fractional;
  for (int i = 0; i < 40; ++i) whole_pixels.push_back(i);
  // 11 labels: the last group of 4 labels side by side holds 3.
  for (int i = 0; i < 11; ++i) fractional.push_back(0.75 * i);
  int inside = 0, outside = 0;
  for (const std::vector<double>* d : {&whole_pixels, &fractional}) {
    const int num_labels = static_cast<int>(d->size());
    for (const int window : {5, 1}) {
      for (const std::string filter : {"guided", "box"}) {
        if (window == 1 && filter == "box") continue;
        BirchfieldTomasiOptions options = CensusGuided();
        options.window.window_px = window;
        options.window.filter = filter;
        for (const cv::Rect region : {cv::Rect(0, 0, 300, 70), cv::Rect(37, 5, 250, 60)}) {
          const LabelBands bands = RandomBands(region.size(), num_labels, 60 + region.x);
          const CostVolume full = ComputeBirchfieldTomasiCost(left, right, *d, region, options);
          const CostVolume banded =
              ComputeBirchfieldTomasiCost(left, right, *d, region, options, &bands);
          for (int r = 0; r < region.height; ++r) {
            for (int c = 0; c < region.width; ++c) {
              const int lo = bands.lo.at<int>(r / 8, c / 8), hi = bands.hi.at<int>(r / 8, c / 8);
              for (int l = 0; l < num_labels; ++l) {
                const std::uint16_t got = banded.PixelData(r, c)[l];
                const std::uint16_t expected = full.PixelData(r, c)[l];
                if (l >= lo && l <= hi) {
                  ++inside;
                  ASSERT_EQ(got, expected) << filter << " window " << window << " labels "
                                           << num_labels << " region x " << region.x << " pixel "
                                           << r << "," << c << " label " << l;
                } else {
                  ++outside;
                  // Not computed: the largest cost (kNoData reads as it too).
                  ASSERT_TRUE(got == 65534 || got == CostVolume::kNoData)
                      << filter << " window " << window << " pixel " << r << "," << c << " label "
                      << l << ": " << got;
                  ASSERT_EQ(banded.Cost(r, c, l), banded.max_cost());
                }
              }
            }
          }
        }
      }
    }
  }
  EXPECT_GT(inside, 100000);
  EXPECT_GT(outside, 100000);
}

TEST(CostFilter, LabelBandsMustFitTheRegion) {
  const cv::Mat image = RandomImage(20, 30, CV_8UC3, 5);
  LabelBands bands = RandomBands(cv::Size(30, 20), 4, 1);
  const std::vector<double> d = {0, 1, 2, 3};
  EXPECT_THROW(ComputeBirchfieldTomasiCost(image, image, d, cv::Rect(0, 0, 30, 12), {}, &bands),
               Error);
  LabelBands all;
  all.block_px = 16;
  all.lo = cv::Mat(2, 2, CV_32S, cv::Scalar(0));
  all.hi = cv::Mat(2, 2, CV_32S, cv::Scalar(3));
  EXPECT_DOUBLE_EQ(all.Fraction(cv::Size(30, 20), 4), 1.0);
  all.hi.setTo(1);
  EXPECT_DOUBLE_EQ(all.Fraction(cv::Size(30, 20), 4), 0.5);
  const CostVolume half = ComputeBirchfieldTomasiCost(image, image, d, cv::Rect(0, 0, 30, 20), {},
                                                      &all);
  EXPECT_EQ(half.PixelData(10, 10)[3], 65534);
  EXPECT_EQ(half.PixelData(10, 10)[0], 0);  // the image against itself at disparity 0
}

TEST(CostFilter, SameBytesForOneAndTwoThreads) {
  const cv::Mat left = RandomImage(40, 50, CV_8UC3, 3);
  const cv::Mat right = RandomImage(40, 50, CV_8UC3, 4);
  std::vector<double> d;
  for (int i = 0; i < 12; ++i) d.push_back(0.75 * i);
  const cv::Rect region(4, 3, 40, 30);
  CostVolume one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = ComputeBirchfieldTomasiCost(left, right, d, region, CensusGuided());
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = ComputeBirchfieldTomasiCost(left, right, d, region, CensusGuided());
  }
  EXPECT_TRUE(SameBytes(one, two));
}

// The plane sweep with a window: tile = crop, and with window 1 the pixel-wise sweep.
TEST(CostFilter, PlaneSweepWindowTileIsCropOfWholeImage) {
  const int w = 36, h = 24;
  const cv::Mat ref_image = RandomImage(h, w, CV_8UC3, 7);
  const cv::Mat other = RandomImage(h, w, CV_8UC3, 8);
  auto camera = [&](int index) {
    return RectifiedSequenceCamera(1.0, (w - 1) / 2.0, (h - 1) / 2.0, 1.0, index, w, h);
  };
  const View reference{"ref", ref_image, camera(0)};
  const std::vector<View> neighbors = {View{"n", other, camera(1)}};
  const LabelSpace labels(LabelSpaceKind::kDisparity, 6, 0.0, 5.0, 1.0);
  PlaneSweepOptions options;
  options.window.window_px = 3;
  const cv::Rect full(0, 0, w, h);
  const CostVolume whole = ComputePlaneSweepCost(reference, neighbors, labels, full, options);
  const cv::Rect tile(10, 5, 12, 9);
  const CostVolume part = ComputePlaneSweepCost(reference, neighbors, labels, tile, options);
  for (int r = 0; r < tile.height; ++r) {
    for (int c = 0; c < tile.width; ++c) {
      ASSERT_EQ(std::memcmp(part.PixelData(r, c), whole.PixelData(tile.y + r, tile.x + c),
                            sizeof(std::uint16_t) * 6),
                0);
    }
  }
  // A different window gives a different volume (the option is wired through).
  const CostVolume pixelwise =
      ComputePlaneSweepCost(reference, neighbors, labels, full, PlaneSweepOptions{});
  EXPECT_FALSE(SameBytes(pixelwise, whole));
}

TEST(CostFilter, BadOptionsNameTheKey) {
  auto message = [](const auto& check) -> std::string {
    try {
      check();
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "no error";
  };
  CostFilterOptions even;
  even.window_px = 4;
  EXPECT_NE(message([&] { even.Check("cost."); }).find("cost.window_px"), std::string::npos);
  EXPECT_NE(message([&] { even.Check("cost.sweep_"); }).find("cost.sweep_window_px"),
            std::string::npos);
  CostFilterOptions filter;
  filter.filter = "median";
  EXPECT_NE(message([&] { filter.Check(); }).find("cost.window_filter"), std::string::npos);
  CostFilterOptions epsilon;
  epsilon.guided_epsilon = 0;
  EXPECT_NE(message([&] { epsilon.Check(); }).find("cost.guided_epsilon"), std::string::npos);

  BirchfieldTomasiOptions bt;
  bt.window.window_px = 0;
  EXPECT_NE(message([&] { bt.Check(); }).find("cost.window_px"), std::string::npos);
  PlaneSweepOptions sweep;
  sweep.window.filter = "gauss";
  EXPECT_NE(message([&] { sweep.Check(); }).find("cost.sweep_window_filter"), std::string::npos);
  EXPECT_NE(message([&] { sweep.Check(); }).find("gauss"), std::string::npos);
}

TEST(CostFilter, RegionOutsideTheVolumeThrows) {
  CostVolume raw(cv::Rect(0, 0, 4, 4), 1, 10.0f);
  const cv::Mat guide(4, 4, CV_8UC1, cv::Scalar(0));
  CostFilterOptions options;
  options.window_px = 3;
  try {
    FilterCostVolume(raw, guide, cv::Rect(2, 2, 4, 4), options);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not inside the cost volume's region"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace gcpstereo::cost
