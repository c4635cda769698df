// Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
#include "gcpstereo/propagation/sparse_solver.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>

#include <cholmod.h>
#include <umfpack.h>

#include "gcpstereo/core/error.h"
#include "gcpstereo/core/huge_page_allocator.h"

namespace gcpstereo::propagation {
namespace {

const char* UmfpackStatusMeaning(int status) {
  switch (status) {
    case UMFPACK_OK:
      return "UMFPACK_OK";
    case UMFPACK_WARNING_singular_matrix:
      return "UMFPACK_WARNING_singular_matrix: the matrix is singular";
    case UMFPACK_WARNING_determinant_underflow:
      return "UMFPACK_WARNING_determinant_underflow";
    case UMFPACK_WARNING_determinant_overflow:
      return "UMFPACK_WARNING_determinant_overflow";
    case UMFPACK_ERROR_out_of_memory:
      return "UMFPACK_ERROR_out_of_memory: out of memory";
    case UMFPACK_ERROR_invalid_Numeric_object:
      return "UMFPACK_ERROR_invalid_Numeric_object";
    case UMFPACK_ERROR_invalid_Symbolic_object:
      return "UMFPACK_ERROR_invalid_Symbolic_object";
    case UMFPACK_ERROR_argument_missing:
      return "UMFPACK_ERROR_argument_missing";
    case UMFPACK_ERROR_n_nonpositive:
      return "UMFPACK_ERROR_n_nonpositive";
    case UMFPACK_ERROR_invalid_matrix:
      return "UMFPACK_ERROR_invalid_matrix: malformed compressed-column matrix";
    case UMFPACK_ERROR_different_pattern:
      return "UMFPACK_ERROR_different_pattern";
    case UMFPACK_ERROR_invalid_system:
      return "UMFPACK_ERROR_invalid_system";
    case UMFPACK_ERROR_invalid_permutation:
      return "UMFPACK_ERROR_invalid_permutation";
    case UMFPACK_ERROR_ordering_failed:
      return "UMFPACK_ERROR_ordering_failed";
    case UMFPACK_ERROR_internal_error:
      return "UMFPACK_ERROR_internal_error";
    default:
      return "unknown UMFPACK status";
  }
}

void ThrowUmfpack(const char* step, int status) {
  throw Error(std::string("UMFPACK ") + step + " failed: status " + std::to_string(status) + " (" +
              UmfpackStatusMeaning(status) + ")");
}

void CheckMatrix(const CscMatrix& a, const std::vector<double>& b, bool lower_only) {
  const std::string context = "SolveSparseLinearSystem: ";
  if (a.size <= 0) throw Error(context + "matrix size " + std::to_string(a.size) + " is not > 0");
  if (static_cast<int>(a.col_starts.size()) != a.size + 1) {
    throw Error(context + "col_starts has " + std::to_string(a.col_starts.size()) +
                " entries, expected size + 1 = " + std::to_string(a.size + 1));
  }
  if (b.size() != static_cast<size_t>(a.size)) {
    throw Error(context + "right-hand side has " + std::to_string(b.size()) +
                " entries, expected " + std::to_string(a.size));
  }
  const int nnz = a.col_starts.back();
  if (a.col_starts.front() != 0 || nnz < 0 || a.row_indices.size() != static_cast<size_t>(nnz) ||
      a.values.size() != static_cast<size_t>(nnz)) {
    throw Error(context + "col_starts/row_indices/values sizes are inconsistent");
  }
  for (int col = 0; col < a.size; ++col) {
    if (a.col_starts[col] > a.col_starts[col + 1]) {
      throw Error(context + "col_starts decreases at column " + std::to_string(col));
    }
    for (int k = a.col_starts[col]; k < a.col_starts[col + 1]; ++k) {
      const int row = a.row_indices[k];
      if (row < 0 || row >= a.size || (k > a.col_starts[col] && row <= a.row_indices[k - 1])) {
        throw Error(context + "row indices of column " + std::to_string(col) +
                    " are out of range or not strictly increasing");
      }
      if (lower_only && row < col) {
        throw Error(context + "CHOLMOD input must hold only the lower triangle; entry (" +
                    std::to_string(row) + ", " + std::to_string(col) + ") is above the diagonal");
      }
      if (!std::isfinite(a.values[k])) {
        throw Error(context + "non-finite matrix entry in column " + std::to_string(col));
      }
    }
  }
}

std::vector<double> SolveUmfpack(const CscMatrix& a, const std::vector<double>& b,
                                 const std::vector<int>& order) {
  double control[UMFPACK_CONTROL];
  double info[UMFPACK_INFO];
  umfpack_di_defaults(control);
  void* symbolic = nullptr;
  void* numeric = nullptr;
  int status = UMFPACK_OK;
  if (order.empty()) {
    status = umfpack_di_symbolic(a.size, a.size, a.col_starts.data(), a.row_indices.data(),
                                 a.values.data(), &symbolic, control, info);
  } else {
    // The given column preorder replaces AMD/COLAMD; the symmetric strategy then keeps it for
    // the rows too (eq. 5 has a symmetric pattern and a unit diagonal).
    control[UMFPACK_STRATEGY] = UMFPACK_STRATEGY_SYMMETRIC;
    status = umfpack_di_qsymbolic(a.size, a.size, a.col_starts.data(), a.row_indices.data(),
                                  a.values.data(), order.data(), &symbolic, control, info);
  }
  if (status != UMFPACK_OK) {
    umfpack_di_free_symbolic(&symbolic);
    ThrowUmfpack("symbolic analysis", status);
  }
  status = umfpack_di_numeric(a.col_starts.data(), a.row_indices.data(), a.values.data(), symbolic,
                              &numeric, control, info);
  umfpack_di_free_symbolic(&symbolic);
  // A singular matrix is only a warning for UMFPACK (it still factorises); for us it is a failure.
  if (status != UMFPACK_OK) {
    umfpack_di_free_numeric(&numeric);
    ThrowUmfpack("numeric factorisation", status);
  }
  std::vector<double> x(a.size, 0.0);
  status = umfpack_di_solve(UMFPACK_A, a.col_starts.data(), a.row_indices.data(), a.values.data(),
                            x.data(), b.data(), numeric, control, info);
  umfpack_di_free_numeric(&numeric);
  if (status != UMFPACK_OK) ThrowUmfpack("solve", status);
  return x;
}

// RAII for cholmod_common and the objects allocated from it.
struct CholmodContext {
  cholmod_common common;
  cholmod_sparse* matrix = nullptr;
  cholmod_factor* factor = nullptr;
  cholmod_dense* rhs = nullptr;
  cholmod_dense* solution = nullptr;
  CholmodContext() {
    cholmod_start(&common);
    common.print = 0;  // no messages on stdout
    common.error_handler = nullptr;
    // Always the supernodal LLᵀ: a simplicial LDLᵀ would silently factorise indefinite matrices,
    // and positive definiteness is what certifies the system (every region reaches a GCP).
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~CholmodContext() {
    if (solution) cholmod_free_dense(&solution, &common);
    if (rhs) cholmod_free_dense(&rhs, &common);
    if (factor) cholmod_free_factor(&factor, &common);
    if (matrix) cholmod_free_sparse(&matrix, &common);
    cholmod_finish(&common);
  }
};

std::vector<double> SolveCholmod(const CscMatrix& a, const std::vector<double>& b,
                                 const std::vector<int>& order) {
  CholmodContext ctx;
  const int nnz = a.col_starts.back();
  ctx.matrix = cholmod_allocate_sparse(a.size, a.size, nnz, /*sorted=*/1, /*packed=*/1,
                                       /*stype=*/-1, CHOLMOD_REAL, &ctx.common);
  if (ctx.matrix == nullptr) {
    throw Error("CHOLMOD could not allocate the matrix: status " +
                std::to_string(ctx.common.status));
  }
  std::copy(a.col_starts.begin(), a.col_starts.end(), static_cast<int*>(ctx.matrix->p));
  std::copy(a.row_indices.begin(), a.row_indices.end(), static_cast<int*>(ctx.matrix->i));
  std::copy(a.values.begin(), a.values.end(), static_cast<double*>(ctx.matrix->x));

  if (order.empty()) {
    ctx.factor = cholmod_analyze(ctx.matrix, &ctx.common);
  } else {
    ctx.common.nmethods = 1;
    ctx.common.method[0].ordering = CHOLMOD_GIVEN;
    std::vector<int> user_order(order);  // CHOLMOD takes a non-const pointer
    ctx.factor = cholmod_analyze_p(ctx.matrix, user_order.data(), nullptr, 0, &ctx.common);
  }
  if (ctx.factor == nullptr || ctx.common.status < CHOLMOD_OK) {
    throw Error("CHOLMOD analysis failed: status " + std::to_string(ctx.common.status) +
                (ctx.common.status == CHOLMOD_OUT_OF_MEMORY ? " (out of memory)" : ""));
  }
  cholmod_factorize(ctx.matrix, ctx.factor, &ctx.common);
  if (ctx.common.status == CHOLMOD_NOT_POSDEF || ctx.factor->minor < ctx.factor->n) {
    throw Error("CHOLMOD factorisation failed: the matrix is not positive definite (column " +
                std::to_string(ctx.factor->minor) + ")");
  }
  if (ctx.common.status < CHOLMOD_OK) {
    throw Error("CHOLMOD factorisation failed: status " + std::to_string(ctx.common.status) +
                (ctx.common.status == CHOLMOD_OUT_OF_MEMORY ? " (out of memory)" : ""));
  }
  ctx.rhs = cholmod_allocate_dense(a.size, 1, a.size, CHOLMOD_REAL, &ctx.common);
  if (ctx.rhs == nullptr) throw Error("CHOLMOD could not allocate the right-hand side");
  std::copy(b.begin(), b.end(), static_cast<double*>(ctx.rhs->x));
  ctx.solution = cholmod_solve(CHOLMOD_A, ctx.factor, ctx.rhs, &ctx.common);
  if (ctx.solution == nullptr || ctx.common.status < CHOLMOD_OK) {
    throw Error("CHOLMOD solve failed: status " + std::to_string(ctx.common.status));
  }
  const double* x = static_cast<const double*>(ctx.solution->x);
  return std::vector<double>(x, x + a.size);
}

}  // namespace

void UseHugePagesInSuiteSparse() {
  static std::once_flag once;
  std::call_once(once, [] {
    SuiteSparse_config.malloc_func = MallocHugePageBacked;
    SuiteSparse_config.calloc_func = CallocHugePageBacked;
    SuiteSparse_config.realloc_func = ReallocHugePageBacked;
    SuiteSparse_config.free_func = FreeHugePageBacked;
  });
}

const char* SparseSolverKindName(SparseSolverKind kind) {
  return kind == SparseSolverKind::kUmfpack ? "umfpack" : "cholmod";
}

SparseSolverKind ParseSparseSolverKind(const std::string& name) {
  if (name == "umfpack") return SparseSolverKind::kUmfpack;
  if (name == "cholmod") return SparseSolverKind::kCholmod;
  throw ConfigError(
      ViolatedConstraint("propagation.solver", "'" + name + "'", "one of 'umfpack', 'cholmod'"));
}

std::vector<double> SolveSparseLinearSystem(const CscMatrix& a, const std::vector<double>& b,
                                            SparseSolverKind kind,
                                            const std::vector<int>& fill_reducing_order) {
  CheckMatrix(a, b, kind == SparseSolverKind::kCholmod);
  if (!fill_reducing_order.empty()) {
    if (fill_reducing_order.size() != static_cast<size_t>(a.size)) {
      throw Error("SolveSparseLinearSystem: fill_reducing_order has " +
                  std::to_string(fill_reducing_order.size()) + " entries, expected " +
                  std::to_string(a.size));
    }
    std::vector<char> seen(a.size, 0);
    for (int index : fill_reducing_order) {
      if (index < 0 || index >= a.size || seen[index]) {
        throw Error("SolveSparseLinearSystem: fill_reducing_order is not a permutation of 0.." +
                    std::to_string(a.size - 1));
      }
      seen[index] = 1;
    }
  }
  std::vector<double> x = kind == SparseSolverKind::kUmfpack
                              ? SolveUmfpack(a, b, fill_reducing_order)
                              : SolveCholmod(a, b, fill_reducing_order);
  for (int i = 0; i < a.size; ++i) {
    if (!std::isfinite(x[i])) {
      throw Error(std::string(SparseSolverKindName(kind)) +
                  " returned a non-finite solution (entry " + std::to_string(i) +
                  "): the system is numerically singular");
    }
  }
  return x;
}

}  // namespace gcpstereo::propagation
