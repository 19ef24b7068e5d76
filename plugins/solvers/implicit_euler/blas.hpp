// The dense kernels of implicit_euler's direct solve: a BLAS and LAPACK
// bound at run time (dlopen), the first time a matrix is factorised.
//
// Not linked: the registry loads every plugin to read its descriptor, so a
// linked OpenBLAS (and its start-up: 5 to 9 ms of dlopen, measured) was
// paid by every pdyn process, implicit or not, as h5md's HDF5 was
// (plugins/writers/h5md/h5md.cpp). The routines are the reference
// interface (Fortran calling convention, the hidden lengths of the
// character arguments last), so any BLAS serves; Debian's OpenBLAS
// (BSD-3-Clause) is tried first, for its kernels chosen for the CPU.
// PDYN_BLAS, when set, names the library (a path or a soname) and nothing
// else is tried.
#pragma once

#include <cstddef>

namespace pdyn::solvers::detail {

/// The six routines SupernodalCholesky calls (supernodal_cholesky.hpp), as
/// the reference BLAS and LAPACK declare them: column-major double
/// matrices, every argument by pointer, then the lengths of the character
/// arguments.
struct Blas {
  void (*dgemm)(const char* transa, const char* transb, const int* m, const int* n, const int* k,
                const double* alpha, const double* a, const int* lda, const double* b,
                const int* ldb, const double* beta, double* c, const int* ldc, std::size_t,
                std::size_t) = nullptr;
  void (*dsyrk)(const char* uplo, const char* trans, const int* n, const int* k,
                const double* alpha, const double* a, const int* lda, const double* beta, double* c,
                const int* ldc, std::size_t, std::size_t) = nullptr;
  void (*dtrsm)(const char* side, const char* uplo, const char* transa, const char* diag,
                const int* m, const int* n, const double* alpha, const double* a, const int* lda,
                double* b, const int* ldb, std::size_t, std::size_t, std::size_t,
                std::size_t) = nullptr;
  void (*dtrsv)(const char* uplo, const char* trans, const char* diag, const int* n,
                const double* a, const int* lda, double* x, const int* incx, std::size_t,
                std::size_t, std::size_t) = nullptr;
  void (*dgemv)(const char* trans, const int* m, const int* n, const double* alpha, const double* a,
                const int* lda, const double* x, const int* incx, const double* beta, double* y,
                const int* incy, std::size_t) = nullptr;
  void (*dpotrf)(const char* uplo, const int* n, double* a, const int* lda, int* info,
                 std::size_t) = nullptr;
};

/// The loaded routines, loaded at the first call (and kept for good). Throws
/// pdyn::Error, naming what was tried, when no library has them all; a
/// failed load is tried again at the next call.
const Blas& blas();

}  // namespace pdyn::solvers::detail
