// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/propagation/sparse_solver.h"

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
