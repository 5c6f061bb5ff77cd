#pragma once
// OpenBLAS's own thread count, and OpenMP's, set for a scope.
//
// The direct solvers we call (CHOLMOD, and MUMPS inside Ipopt) spend most
// of their time in BLAS on small dense fronts. With the OpenMP build of
// OpenBLAS each call opens its own thread team: on two cores shared with
// our element loops that is slower than one thread (Ipopt on the 2D
// cantilever: 4x slower per iteration under load), and CHOLMOD's factors
// would depend on the thread count. Found at run time, so another BLAS (or
// none with these entry points) still works.
namespace msfab {

class SingleThreadedBlas {
 public:
  SingleThreadedBlas();
  ~SingleThreadedBlas();
  SingleThreadedBlas(const SingleThreadedBlas&) = delete;
  SingleThreadedBlas& operator=(const SingleThreadedBlas&) = delete;
};

// OpenMP's thread count for a scope (the calling thread's setting), e.g.
// one thread for a direct solver, the caller's again inside its callbacks.
class OmpThreads {
 public:
  explicit OmpThreads(int threads);
  ~OmpThreads();
  OmpThreads(const OmpThreads&) = delete;
  OmpThreads& operator=(const OmpThreads&) = delete;

 private:
  int saved_;
};

}  // namespace msfab
