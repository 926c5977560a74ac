#pragma once
// Internal to the solve module: OpenBLAS held to one thread while CHOLMOD factors
// (connection_laplacian.cpp's DirichletSolver, dirichlet_frames.cpp's blocks).
#include <cblas.h>

#include <mutex>

namespace tvf::detail {

// OpenBLAS (the pthreads build) runs a large BLAS call on its own threads, which spin
// while they wait for work. The generators factor frames in parallel, a solver per TBB
// worker, and CHOLMOD's supernodal kernels called from both workers at once then had
// OpenBLAS's threads fight the workers for the two cores: 3× the CPU time of the same
// factorizations with OpenBLAS on one thread (measured, docs/benchmarks.md). So while any
// CHOLMOD factorization or solve runs, OpenBLAS is held to one thread, and the last one to
// finish gives it back its threads (the space-time solver's dense products use them). A
// BLAS call made elsewhere meanwhile runs on one thread: slower, never wrong.
class OneBlasThread {
public:
  OneBlasThread() {
    std::lock_guard lock(mutex_);
    if (users_++ == 0) {
      saved_ = openblas_get_num_threads();
      if (saved_ != 1) openblas_set_num_threads(1);
    }
  }
  ~OneBlasThread() {
    std::lock_guard lock(mutex_);
    if (--users_ == 0 && saved_ != 1) openblas_set_num_threads(saved_);
  }
  OneBlasThread(const OneBlasThread&) = delete;
  OneBlasThread& operator=(const OneBlasThread&) = delete;

private:
  static inline std::mutex mutex_;
  static inline int users_ = 0;
  static inline int saved_ = 1;
};

}  // namespace tvf::detail
