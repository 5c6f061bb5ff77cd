#include <mpi.h>

#include "parallel/fan_out.hpp"
#include "parallel/mpi_session.hpp"

namespace msfab {

MpiSession::MpiSession(int* argc, char*** argv) {
  MPI_Init(argc, argv);
  rank_ = mpi_rank();
  size_ = mpi_size();
}

MpiSession::~MpiSession() { MPI_Finalize(); }

}  // namespace msfab
