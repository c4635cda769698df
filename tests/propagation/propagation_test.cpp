// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/propagation/propagation.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "gcpstereo/core/error.h"
#include "test_data.h"

namespace gcpstereo::propagation {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat NoGcps(int rows, int cols) { return cv::Mat(rows, cols, CV_32F, cv::Scalar(kNaN)); }

// The tests are built around the paper's γ = 1.25 and links cut below 1e-8 (the defaults are
// γ = 4 and no cut, measured on Middlebury; see propagation.h), so they set them explicitly.
PropagationOptions WithSolver(const std::string& solver) {
  PropagationOptions options;
  options.gamma = 1.25;
  options.min_weight = 1e-8;
  options.solver = solver;
  return options;
}

// A smooth colour gradient with mild noise and a few uniform blobs: realistic affinities, few cut
// links. Deterministic (fixed seed).
cv::Mat TexturedImage(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-1, 1);
  cv::Mat image(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int base_b = 40 + (100 * c) / cols;
      const int base_g = 60 + (80 * r) / rows;
      const int base_r = 120 + ((r / 8 + c / 8) % 2) * 3;
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(cv::saturate_cast<uchar>(base_b + noise(rng)),
                                            cv::saturate_cast<uchar>(base_g + noise(rng)),
                                            cv::saturate_cast<uchar>(base_r + noise(rng)));
    }
  }
  return image;
}

cv::Mat GridGcps(const cv::Mat& dense, int step) {
  cv::Mat sparse = NoGcps(dense.rows, dense.cols);
  for (int r = step / 2; r < dense.rows; r += step) {
    for (int c = step / 2; c < dense.cols; c += step)
      sparse.at<float>(r, c) = dense.at<float>(r, c);
  }
  return sparse;
}

class PropagationSolverTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PropagationSolverTest, ConstantGcpsGiveTheConstantEverywhere) {
  const cv::Mat image = TexturedImage(40, 50, 7);
  cv::Mat dense(40, 50, CV_32F, cv::Scalar(3.25f));
  const PropagationResult result = Propagate(image, GridGcps(dense, 9), WithSolver(GetParam()));
  ASSERT_EQ(result.num_unreached_pixels, 0);
  for (int r = 0; r < 40; ++r) {
    for (int c = 0; c < 50; ++c)
      EXPECT_NEAR(result.values.at<float>(r, c), 3.25f, 1e-6) << r << "," << c;
  }
  EXPECT_EQ(result.solver, GetParam());
  EXPECT_LT(result.residual, 1e-9);
}

TEST_P(PropagationSolverTest, PlaneFromBorderAndInteriorGcpsIsExactOnUniformImage) {
  // Uniform colour: w = 1, α = 1/8, so an interior pixel is the mean of its 8 neighbours, which a
  // linear function satisfies exactly. With the whole border fixed (plus a few interior GCPs) the
  // discrete harmonic problem has the plane as its unique solution.
  const int rows = 30, cols = 41;
  const cv::Mat image(rows, cols, CV_8UC3, cv::Scalar(90, 120, 150));
  auto plane = [](int r, int c) { return 2.0 + 0.37 * c - 0.21 * r; };
  cv::Mat sparse = NoGcps(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const bool border = r == 0 || c == 0 || r == rows - 1 || c == cols - 1;
      if (border || (r == 10 && c == 12) || (r == 20 && c == 30)) {
        sparse.at<float>(r, c) = static_cast<float>(plane(r, c));
      }
    }
  }
  const PropagationResult result = Propagate(image, sparse, WithSolver(GetParam()));
  EXPECT_EQ(result.num_gcps, 2 * rows + 2 * cols - 4 + 2);
  double max_error = 0.0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      max_error = std::max(max_error, std::abs(result.values.at<float>(r, c) - plane(r, c)));
    }
  }
  EXPECT_LE(max_error, 1e-6);  // float output of values up to ~17
}

TEST_P(PropagationSolverTest, StopsAtColourEdges) {
  // Left half dark, right half bright: links across the edge are exp(−260/1.25) ≈ 1e-90. Even
  // without cutting them (min_weight = 0) each side keeps its own GCP value, not a blend.
  const int rows = 24, cols = 40;
  cv::Mat image(rows, cols, CV_8UC3, cv::Scalar(50, 50, 50));
  image(cv::Rect(cols / 2, 0, cols / 2, rows)).setTo(cv::Scalar(200, 200, 200));
  cv::Mat sparse = NoGcps(rows, cols);
  sparse.at<float>(5, 3) = 1.0f;
  sparse.at<float>(18, 36) = 5.0f;
  for (double min_weight : {1e-8, 0.0}) {
    PropagationOptions options = WithSolver(GetParam());
    options.min_weight = min_weight;
    const PropagationResult result = Propagate(image, sparse, options);
    EXPECT_EQ(result.num_unreached_pixels, 0);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        EXPECT_NEAR(result.values.at<float>(r, c), c < cols / 2 ? 1.0 : 5.0, 1e-3)
            << "min_weight " << min_weight << " at " << r << "," << c;
      }
    }
  }
}

TEST_P(PropagationSolverTest, IslandWithoutGcpIsReportedUnreached) {
  const int rows = 20, cols = 30;
  cv::Mat image(rows, cols, CV_8UC3, cv::Scalar(100, 100, 100));
  image(cv::Rect(10, 6, 5, 4)).setTo(cv::Scalar(10, 220, 30));  // 20 pixels
  cv::Mat sparse = NoGcps(rows, cols);
  sparse.at<float>(2, 2) = 4.0f;
  sparse.at<float>(17, 27) = 4.0f;
  const PropagationResult result = Propagate(image, sparse, WithSolver(GetParam()));
  EXPECT_EQ(result.num_unreached_regions, 1);
  EXPECT_EQ(result.num_unreached_pixels, 20);
  EXPECT_EQ(result.num_unknowns, GetParam() == "umfpack" ? rows * cols - 20 : rows * cols - 22);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const bool island = c >= 10 && c < 15 && r >= 6 && r < 10;
      EXPECT_EQ(std::isnan(result.values.at<float>(r, c)), island) << r << "," << c;
      EXPECT_EQ(result.reached.at<uchar>(r, c), island ? 0 : 255) << r << "," << c;
      if (!island) {
        EXPECT_NEAR(result.values.at<float>(r, c), 4.0f, 1e-6);
      }
    }
  }
  // With a positive ε every link survives: the island is reached and takes the surrounding value.
  PropagationOptions floored = WithSolver(GetParam());
  floored.epsilon = 1e-3;
  const PropagationResult reached = Propagate(image, sparse, floored);
  EXPECT_EQ(reached.num_unreached_pixels, 0);
  EXPECT_NEAR(reached.values.at<float>(7, 12), 4.0f, 1e-5);
}

TEST_P(PropagationSolverTest, WithoutGcpsEverythingIsUnreached) {
  cv::Mat image(10, 12, CV_8UC3, cv::Scalar(100, 100, 100));
  image(cv::Rect(0, 0, 6, 10)).setTo(cv::Scalar(0, 0, 0));
  const PropagationResult result = Propagate(image, NoGcps(10, 12), WithSolver(GetParam()));
  EXPECT_EQ(result.num_gcps, 0);
  EXPECT_EQ(result.num_unknowns, 0);
  EXPECT_EQ(result.num_unreached_regions, 2);
  EXPECT_EQ(result.num_unreached_pixels, 120);
  EXPECT_EQ(cv::countNonZero(result.reached), 0);
}

INSTANTIATE_TEST_SUITE_P(Backends, PropagationSolverTest, ::testing::Values("umfpack", "cholmod"));

// Brute force: build eq. 5 as a dense matrix straight from the paper's formulas and solve it with
// Eigen; both backends must match on a tiny random-colour image (no cut links: min_weight = 0,
// moderate colour noise so the system is well conditioned).
TEST(PropagationTest, MatchesDenseSolveOfEquation5) {
  const int rows = 7, cols = 6, n = rows * cols;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> colour(100, 104);
  cv::Mat image(rows, cols, CV_8UC3);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(colour(rng), colour(rng), colour(rng));
    }
  }
  cv::Mat sparse = NoGcps(rows, cols);
  sparse.at<float>(1, 1) = 2.0f;
  sparse.at<float>(5, 4) = 7.0f;
  sparse.at<float>(3, 0) = -1.5f;
  const double gamma = 1.25;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int p = r * cols + c;
      a(p, p) = 1.0;
      if (std::isfinite(sparse.at<float>(r, c))) {
        b(p) = sparse.at<float>(r, c);
        continue;
      }
      double sum = 0.0;
      for (int pass = 0; pass < 2; ++pass) {
        for (int dr = -1; dr <= 1; ++dr) {
          for (int dc = -1; dc <= 1; ++dc) {
            const int rq = r + dr, cq = c + dc;
            if ((dr == 0 && dc == 0) || rq < 0 || cq < 0 || rq >= rows || cq >= cols) continue;
            const cv::Vec3d diff =
                cv::Vec3d(image.at<cv::Vec3b>(r, c)) - cv::Vec3d(image.at<cv::Vec3b>(rq, cq));
            const double w = std::exp(-cv::norm(diff) / gamma);
            if (pass == 0) {
              sum += w;
            } else {
              a(p, rq * cols + cq) = -w / sum;
            }
          }
        }
      }
    }
  }
  const Eigen::VectorXd expected = a.fullPivLu().solve(b);
  for (const std::string solver : {"umfpack", "cholmod"}) {
    PropagationOptions options = WithSolver(solver);
    options.min_weight = 0.0;
    const PropagationResult result = Propagate(image, sparse, options);
    for (int p = 0; p < n; ++p) {
      EXPECT_NEAR(result.values.at<float>(p / cols, p % cols), expected(p), 1e-5)
          << solver << " " << p;
    }
  }
}

TEST(PropagationTest, UmfpackAndCholmodAgreeOnTexturedImage) {
  const cv::Mat image = TexturedImage(90, 120, 3);
  cv::Mat dense(90, 120, CV_32F);
  for (int r = 0; r < 90; ++r) {
    for (int c = 0; c < 120; ++c)
      dense.at<float>(r, c) = 5.0f + 3.0f * std::sin(0.1f * c) + 0.05f * r;
  }
  const cv::Mat sparse = GridGcps(dense, 16);
  const PropagationResult lu = Propagate(image, sparse, WithSolver("umfpack"));
  const PropagationResult chol = Propagate(image, sparse, WithSolver("cholmod"));
  ASSERT_EQ(lu.num_unreached_pixels, chol.num_unreached_pixels);
  cv::Mat diff;
  cv::absdiff(lu.values, chol.values, diff);
  cv::patchNaNs(diff, 0.0);
  double max_diff = 0.0;
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LE(max_diff, 1e-6);
  EXPECT_LT(lu.residual, 1e-9);
  EXPECT_LT(chol.residual, 1e-9);
  // The elimination order changes the speed, not the solution.
  PropagationOptions amd = WithSolver("cholmod");
  amd.ordering = "amd";
  const PropagationResult chol_amd = Propagate(image, sparse, amd);
  cv::absdiff(chol_amd.values, chol.values, diff);
  cv::patchNaNs(diff, 0.0);
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LE(max_diff, 1e-6);
}

TEST(PropagationTest, UmfpackAndCholmodAgreeOnTsukuba) {
  GCPSTEREO_REQUIRE_SHARED_DATA(path, "middlebury/tsukuba/scene1.row3.col3.ppm");
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  // GCP values: a smooth field sampled every 16 px (what matters here is the solver agreement).
  cv::Mat dense(image.size(), CV_32F);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) dense.at<float>(r, c) = 4.0f + 0.02f * c + 0.01f * r;
  }
  const cv::Mat sparse = GridGcps(dense, 16);
  const PropagationResult lu = Propagate(image, sparse, WithSolver("umfpack"));
  const PropagationResult chol = Propagate(image, sparse, WithSolver("cholmod"));
  cv::Mat diff;
  cv::absdiff(lu.values, chol.values, diff);
  cv::patchNaNs(diff, 0.0);
  double max_diff = 0.0;
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LE(max_diff, 1e-6);
  std::cout << "[ tsukuba  ] unreached " << lu.num_unreached_pixels << " px in "
            << lu.num_unreached_regions << " regions; umfpack " << lu.solve_seconds
            << " s, cholmod " << chol.solve_seconds << " s, max |diff| " << max_diff << "\n";
}

TEST(PropagationTest, OptionsCheckNamesTheKey) {
  PropagationOptions options;
  options.gamma = 0.0;
  try {
    options.Check();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "propagation.gamma = 0. Violated constraint: gamma > 0");
  }
  options = PropagationOptions();
  options.epsilon = 1.0;
  EXPECT_THROW(options.Check(), ConfigError);
  options = PropagationOptions();
  options.min_weight = 0.5;
  EXPECT_THROW(options.Check(), ConfigError);
  options = PropagationOptions();
  options.ordering = "metis";
  EXPECT_THROW(options.Check(), ConfigError);
  options = PropagationOptions();
  options.solver = "lu";
  try {
    options.Check();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "propagation.solver = 'lu'. Violated constraint: one of 'umfpack', 'cholmod'");
  }
}

TEST(PropagationTest, BadInputsThrow) {
  const cv::Mat grey(10, 10, CV_8U, cv::Scalar(0));
  try {
    Propagate(grey, NoGcps(10, 10), PropagationOptions());
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Propagate: the image must be a non-empty CV_8UC3 (BGR) image");
  }
  const cv::Mat colour(10, 10, CV_8UC3, cv::Scalar(0, 0, 0));
  try {
    Propagate(colour, NoGcps(10, 11), PropagationOptions());
    FAIL() << "expected Error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Propagate: sparse_values must be CV_32F of the image size 10x10");
  }
}

}  // namespace
}  // namespace gcpstereo::propagation
