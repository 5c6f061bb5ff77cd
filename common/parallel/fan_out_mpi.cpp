#include <mpi.h>
#include <spdlog/spdlog.h>

#include <exception>

#include "parallel/fan_out.hpp"

namespace msfab {

int mpi_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int mpi_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

void mpi_barrier() { MPI_Barrier(MPI_COMM_WORLD); }

std::vector<double> fan_out(int count, int record_size, const std::function<void(int, double*)>& work) {
  const int rank = mpi_rank(), size = mpi_size();
  std::vector<double> mine(static_cast<std::size_t>(count) * record_size, 0.0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < count; ++i) {
    if (i % size != rank) continue;
    try {
      work(i, &mine[static_cast<std::size_t>(i) * record_size]);
    } catch (const std::exception& e) {  // must not escape the parallel region; the row stays zero (= failed)
      std::fill_n(&mine[static_cast<std::size_t>(i) * record_size], record_size, 0.0);
      spdlog::warn("item {}: {}", i, e.what());
    }
  }
  std::vector<double> all(mine.size());
  if (!mine.empty())
    MPI_Allreduce(mine.data(), all.data(), static_cast<int>(mine.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return all;
}

}  // namespace msfab
