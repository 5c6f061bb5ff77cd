#pragma once
// The MPI lifetime of a stage that fans out over ranks. The constructor
// initializes MPI and the destructor finalizes it, so every way out of
// main (an InputError that StageApp turns into exit code 2 included)
// finalizes exactly once. Declare it before the StageApp and give the app
// its rank (StageApp::set_rank), which makes rank 0 the job's one voice.
//
// Defined in fan_out_mpi.cpp's library (msfab_mpi), which only the stages
// that fan out link (common/CMakeLists.txt says why).
namespace msfab {

class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace msfab
