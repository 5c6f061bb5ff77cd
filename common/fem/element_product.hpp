#pragma once
// y_e += w K x_e for one 8-node hexahedron (K 24 x 24, column-major): the
// inner loop of every matrix-free voxel product (the Dirichlet grid
// multigrid of topology optimization and of the full-resolution check,
// the periodic one of homogenization), where it is most of the run time.
//
// The binary targets x86-64-v2 (SSE: two doubles per instruction) so that
// it runs on every node of a cluster; this one kernel is also compiled for
// AVX2 and AVX-512 and picked at run time by what the CPU supports. Every
// variant performs the same operations in the same order, a product then
// a sum per entry and column (no fused multiply-add), so all of them give
// the same bits, the same as Eigen's `ye += (w * xe[c]) * K.col(c)` in the
// default build (a build for a CPU with FMA lets the compiler fuse Eigen's).
#include <cstdint>
#include <string>

#include "fem/voxel_stiffness_field.hpp"

namespace msfab {

using ElementProductKernel = void (*)(const double* K, double w, const double* x, double* y);

// The widest variant this CPU runs (chosen once).
ElementProductKernel element_product_kernel();
// Its name: "avx512", "avx2" or "sse".
const char* element_product_kernel_name();
// A named variant, for tests and benchmarks; nullptr where the CPU lacks it
// or the name is unknown.
ElementProductKernel element_product_kernel(const std::string& name);

// y_e += K_v x_e for voxel v of `field`: its basis matrices with non-zero
// weight, in basis order, by `kernel` (element_product_kernel()).
inline void add_voxel_product(const VoxelStiffnessField& field, std::int64_t v, ElementProductKernel kernel,
                              const double* x, double* y) {
  for (int b = 0; b < field.basis_size(); ++b)
    if (const double w = field.weight(v, b); w != 0.0) kernel(field.basis[std::size_t(b)].data(), w, x, y);
}

}  // namespace msfab
