#pragma once
// Work spread over MPI ranks (item i on rank i mod size, threads within a
// rank) with every record gathered on every rank, so all ranks hold the
// same state afterwards. Records are fixed-size rows of doubles; rows a
// rank does not own stay zero and a sum over ranks assembles them exactly,
// hence results do not depend on the rank count.
#include <functional>
#include <vector>

namespace msfab {

std::vector<double> fan_out(int count, int record_size, const std::function<void(int item, double* record)>& work);

int mpi_rank();
int mpi_size();
// Returns once every rank has called it.
void mpi_barrier();

}  // namespace msfab
