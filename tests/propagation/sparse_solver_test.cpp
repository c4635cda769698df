// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/propagation/sparse_solver.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gcpstereo/core/error.h"

namespace gcpstereo::propagation {
namespace {

std::string ErrorOf(const CscMatrix& a, const std::vector<double>& b, SparseSolverKind kind) {
  try {
    SolveSparseLinearSystem(a, b, kind);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SparseSolverTest, SolvesSmallSystems) {
  // Full 3×3 SPD matrix [[4,1,0],[1,3,1],[0,1,2]] with x = (1, 2, 3): b = (6, 10, 8).
  CscMatrix full{3, {0, 2, 5, 7}, {0, 1, 0, 1, 2, 1, 2}, {4, 1, 1, 3, 1, 1, 2}};
  CscMatrix lower{3, {0, 2, 4, 5}, {0, 1, 1, 2, 2}, {4, 1, 3, 1, 2}};
  const std::vector<double> b = {6, 10, 8};
  const std::vector<double> x_lu = SolveSparseLinearSystem(full, b, SparseSolverKind::kUmfpack);
  const std::vector<double> x_ch = SolveSparseLinearSystem(lower, b, SparseSolverKind::kCholmod);
  const std::vector<int> order = {2, 0, 1};
  const std::vector<double> y_lu =
      SolveSparseLinearSystem(full, b, SparseSolverKind::kUmfpack, order);
  const std::vector<double> y_ch =
      SolveSparseLinearSystem(lower, b, SparseSolverKind::kCholmod, order);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(x_lu[i], i + 1.0, 1e-12);
    EXPECT_NEAR(x_ch[i], i + 1.0, 1e-12);
    EXPECT_NEAR(y_lu[i], i + 1.0, 1e-12);
    EXPECT_NEAR(y_ch[i], i + 1.0, 1e-12);
  }
  EXPECT_THROW(SolveSparseLinearSystem(full, b, SparseSolverKind::kUmfpack, {0, 0, 1}), Error);
}

// SuiteSparse allocating on huge pages (what gcpstereo's main sets) solves to the same bits: a
// tridiagonal system whose factors are megabytes, before and after the switch.
TEST(SparseSolverTest, HugePagesInSuiteSparseGiveTheSameSolution) {
  const int n = 200000;
  CscMatrix full{n, {0}, {}, {}};
  CscMatrix lower{n, {0}, {}, {}};
  for (int col = 0; col < n; ++col) {
    for (int row = std::max(0, col - 1); row <= std::min(n - 1, col + 1); ++row) {
      const double value = row == col ? 2.5 + 0.001 * (col % 7) : -1.0;
      full.row_indices.push_back(row);
      full.values.push_back(value);
      if (row >= col) {
        lower.row_indices.push_back(row);
        lower.values.push_back(value);
      }
    }
    full.col_starts.push_back(static_cast<int>(full.row_indices.size()));
    lower.col_starts.push_back(static_cast<int>(lower.row_indices.size()));
  }
  std::vector<double> b(n);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.01 * i);
  const std::vector<double> lu = SolveSparseLinearSystem(full, b, SparseSolverKind::kUmfpack);
  const std::vector<double> ch = SolveSparseLinearSystem(lower, b, SparseSolverKind::kCholmod);
  UseHugePagesInSuiteSparse();
  UseHugePagesInSuiteSparse();  // a second call does nothing
  EXPECT_EQ(SolveSparseLinearSystem(full, b, SparseSolverKind::kUmfpack), lu);
  EXPECT_EQ(SolveSparseLinearSystem(lower, b, SparseSolverKind::kCholmod), ch);
  double residual = 0.0;
  for (int i = 0; i < n; ++i) {
    double ax = (2.5 + 0.001 * (i % 7)) * ch[i];
    if (i > 0) ax -= ch[i - 1];
    if (i + 1 < n) ax -= ch[i + 1];
    residual = std::max(residual, std::abs(ax - b[i]));
  }
  EXPECT_LT(residual, 1e-9);
}

TEST(SparseSolverTest, SingularMatrixFailsWithUmfpackStatus) {
  CscMatrix singular{2, {0, 2, 4}, {0, 1, 0, 1}, {1, 1, 1, 1}};  // [[1,1],[1,1]]
  EXPECT_EQ(ErrorOf(singular, {1, 2}, SparseSolverKind::kUmfpack),
            "UMFPACK numeric factorisation failed: status 1 (UMFPACK_WARNING_singular_matrix: "
            "the matrix is singular)");
  // A structurally empty column is singular as well.
  CscMatrix empty_column{2, {0, 1, 1}, {0}, {1}};
  EXPECT_EQ(ErrorOf(empty_column, {1, 2}, SparseSolverKind::kUmfpack),
            "UMFPACK numeric factorisation failed: status 1 (UMFPACK_WARNING_singular_matrix: "
            "the matrix is singular)");
}

TEST(SparseSolverTest, IndefiniteMatrixFailsWithCholmod) {
  CscMatrix indefinite{2, {0, 2, 3}, {0, 1, 1}, {1, 2, 1}};  // [[1,2],[2,1]], eigenvalues 3, −1
  EXPECT_EQ(ErrorOf(indefinite, {1, 1}, SparseSolverKind::kCholmod),
            "CHOLMOD factorisation failed: the matrix is not positive definite (column 1)");
  CscMatrix singular{2, {0, 2, 3}, {0, 1, 1}, {1, 1, 1}};  // [[1,1],[1,1]]
  EXPECT_EQ(ErrorOf(singular, {1, 1}, SparseSolverKind::kCholmod),
            "CHOLMOD factorisation failed: the matrix is not positive definite (column 1)");
}

TEST(SparseSolverTest, MalformedInputIsRejected) {
  CscMatrix upper{2, {0, 1, 3}, {0, 0, 1}, {2, 1, 2}};
  EXPECT_EQ(ErrorOf(upper, {1, 1}, SparseSolverKind::kCholmod),
            "SolveSparseLinearSystem: CHOLMOD input must hold only the lower triangle; entry "
            "(0, 1) is above the diagonal");
  CscMatrix unsorted{2, {0, 2, 3}, {1, 0, 1}, {1, 2, 1}};
  EXPECT_EQ(ErrorOf(unsorted, {1, 1}, SparseSolverKind::kUmfpack),
            "SolveSparseLinearSystem: row indices of column 0 are out of range or not strictly "
            "increasing");
  CscMatrix ok{2, {0, 1, 2}, {0, 1}, {1, 1}};
  EXPECT_EQ(ErrorOf(ok, {1}, SparseSolverKind::kUmfpack),
            "SolveSparseLinearSystem: right-hand side has 1 entries, expected 2");
  CscMatrix empty{0, {0}, {}, {}};
  EXPECT_EQ(ErrorOf(empty, {}, SparseSolverKind::kUmfpack),
            "SolveSparseLinearSystem: matrix size 0 is not > 0");
}

TEST(SparseSolverTest, ParsesSolverNames) {
  EXPECT_EQ(ParseSparseSolverKind("umfpack"), SparseSolverKind::kUmfpack);
  EXPECT_EQ(ParseSparseSolverKind("cholmod"), SparseSolverKind::kCholmod);
  EXPECT_THROW(ParseSparseSolverKind("UMFPACK"), ConfigError);
}

}  // namespace
}  // namespace gcpstereo::propagation
