// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

// A thin, SuiteSparse-free interface to the sparse direct solvers used by the propagation stage.
// Public so that tests can drive the failure paths (singular / indefinite systems) directly; the
// SuiteSparse headers stay in the .cc file.

#include <string>
#include <vector>

namespace gcpstereo::propagation {

// Which SuiteSparse backend solves the linear system (configuration key propagation.solver).
enum class SparseSolverKind {
  kUmfpack,  // UMFPACK sparse LU of the general (unsymmetric) matrix, as in the paper
  kCholmod,  // CHOLMOD sparse Cholesky; the matrix must be symmetric positive definite
};
const char* SparseSolverKindName(SparseSolverKind kind);
// Parses "umfpack" or "cholmod"; throws ConfigError naming propagation.solver otherwise.
SparseSolverKind ParseSparseSolverKind(const std::string& name);

// A square sparse matrix in compressed-column form (0-based, row indices sorted and unique within
// each column). For kCholmod only the lower triangle (row >= col) is stored and read.
struct CscMatrix {
  int size = 0;                  // number of rows = number of columns
  std::vector<int> col_starts;   // size + 1 entries
  std::vector<int> row_indices;  // col_starts[size] entries
  std::vector<double> values;    // col_starts[size] entries
};

// Solves A x = b. `fill_reducing_order` (optional) is the elimination order to use instead of the
// backend's own (AMD): order[k] = the index eliminated k-th; it must be a permutation of 0..size−1.
// Throws Error when the matrix is malformed (naming the broken invariant) or the
// factorisation fails; the message carries the backend's status code and its meaning, e.g.
// "UMFPACK numeric factorisation failed: status 1 (UMFPACK_WARNING_singular_matrix: the matrix is
// singular)" or "CHOLMOD factorisation failed: the matrix is not positive definite (column 3)".
std::vector<double> SolveSparseLinearSystem(const CscMatrix& a, const std::vector<double>& b,
                                            SparseSolverKind kind,
                                            const std::vector<int>& fill_reducing_order = {});

// Makes SuiteSparse allocate through core/huge_page_allocator.h (SuiteSparse_config's memory
// functions): CHOLMOD's supernodal factor and UMFPACK's numeric object are written whole as soon
// as they are allocated, and on 4 KiB pages that is one page fault per 4 KiB (Aloe two-view: a
// fifth of the run's page faults). Same results, fewer faults. SuiteSparse's rule for its
// configuration applies: call it at the start of the program, before threads use SuiteSparse
// (gcpstereo's main does); later calls do nothing.
void UseHugePagesInSuiteSparse();

}  // namespace gcpstereo::propagation
