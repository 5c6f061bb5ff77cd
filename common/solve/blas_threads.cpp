#include "solve/blas_threads.hpp"

#include <dlfcn.h>
#include <omp.h>

#include <mutex>

namespace msfab {

namespace {

void set_blas_threads(int threads) {
  using SetThreads = void (*)(int);
  if (void* symbol = dlsym(RTLD_DEFAULT, "openblas_set_num_threads")) reinterpret_cast<SetThreads>(symbol)(threads);
}

int blas_threads() {
  using GetThreads = int (*)();
  if (void* symbol = dlsym(RTLD_DEFAULT, "openblas_get_num_threads")) return reinterpret_cast<GetThreads>(symbol)();
  return 1;
}

}  // namespace

// OpenBLAS's thread count is one setting for the process, and scopes
// open on several threads at once (the checked coarsening homogenizes
// blocks in parallel, each with CHOLMOD): the first scope in saves it, the
// last one out restores it. Saving and restoring per scope let a scope
// restore two threads while another was still inside CHOLMOD.
namespace {
std::mutex blas_scope_mutex;
int blas_scopes = 0;
int blas_saved = 1;
}  // namespace

SingleThreadedBlas::SingleThreadedBlas() {
  const std::lock_guard<std::mutex> lock(blas_scope_mutex);
  if (blas_scopes++ == 0) {
    blas_saved = blas_threads();
    set_blas_threads(1);
  }
}
SingleThreadedBlas::~SingleThreadedBlas() {
  const std::lock_guard<std::mutex> lock(blas_scope_mutex);
  if (--blas_scopes == 0) set_blas_threads(blas_saved);
}

OmpThreads::OmpThreads(int threads) : saved_(omp_get_max_threads()) { omp_set_num_threads(threads); }
OmpThreads::~OmpThreads() { omp_set_num_threads(saved_); }

}  // namespace msfab
