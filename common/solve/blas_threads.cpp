#include "solve/blas_threads.hpp"

#include <dlfcn.h>
#include <omp.h>

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

SingleThreadedBlas::SingleThreadedBlas() : saved_(blas_threads()) { set_blas_threads(1); }
SingleThreadedBlas::~SingleThreadedBlas() { set_blas_threads(saved_); }

OmpThreads::OmpThreads(int threads) : saved_(omp_get_max_threads()) { omp_set_num_threads(threads); }
OmpThreads::~OmpThreads() { omp_set_num_threads(saved_); }

}  // namespace msfab
