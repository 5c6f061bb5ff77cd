#include "fem/elastic_assembler.hpp"

#include <algorithm>
#include <cmath>

namespace msfab {

ElasticAssembler::ElasticAssembler(const HexMesh& mesh) : mesh_(mesh) {
  const int n = mesh.num_nodes();
  std::vector<std::vector<int>> adjacent(n);
  for (const auto& el : mesh.elements)
    for (int a : el)
      for (int b : el) adjacent[a].push_back(b);
  for (auto& adj : adjacent) {
    std::sort(adj.begin(), adj.end());
    adj.erase(std::unique(adj.begin(), adj.end()), adj.end());
  }
  col_ptr_.assign(3 * size_t(n) + 1, 0);
  for (int node = 0; node < n; ++node)
    for (int b = 0; b < 3; ++b) col_ptr_[3 * node + b + 1] = col_ptr_[3 * node + b] + 3 * int(adjacent[node].size());
  row_idx_.resize(col_ptr_.back());
  for (int node = 0; node < n; ++node)
    for (int b = 0; b < 3; ++b) {
      int p = col_ptr_[3 * node + b];
      for (int m : adjacent[node])
        for (int a = 0; a < 3; ++a) row_idx_[p++] = 3 * m + a;
    }
  block_offset_.resize(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& el = mesh.elements[e];
    for (int j = 0; j < 8; ++j) {
      const auto& adj = adjacent[el[j]];
      for (int i = 0; i < 8; ++i) {
        const auto pos = std::lower_bound(adj.begin(), adj.end(), el[i]) - adj.begin();
        block_offset_[e][8 * j + i] = static_cast<uint16_t>(3 * pos);
      }
    }
  }
}

SpMat ElasticAssembler::pattern() const {
  const int n = mesh_.num_dofs();
  SpMat A(n, n);
  A.resizeNonZeros(static_cast<Eigen::Index>(row_idx_.size()));
  std::copy(col_ptr_.begin(), col_ptr_.end(), A.outerIndexPtr());
  std::copy(row_idx_.begin(), row_idx_.end(), A.innerIndexPtr());
  std::fill(A.valuePtr(), A.valuePtr() + row_idx_.size(), 0.0);
  return A;
}

VecX ElasticAssembler::rest_positions() const {
  VecX x(mesh_.num_dofs());
  for (int i = 0; i < mesh_.num_nodes(); ++i) x.segment<3>(3 * i) = mesh_.nodes.row(i).transpose();
  return x;
}

hex8::NodeMatrix ElasticAssembler::gather(const VecX& x, int e) const {
  hex8::NodeMatrix xe;
  for (int i = 0; i < 8; ++i) xe.row(i) = x.segment<3>(3 * mesh_.elements[e][i]).transpose();
  return xe;
}

double ElasticAssembler::energy(const VecX& x) const {
  return evaluate(x, nullptr, nullptr);
}

double ElasticAssembler::evaluate(const VecX& x, VecX* gradient, SpMat* hessian) const {
  const int ne = mesh_.num_elements();
  std::vector<double> element_energy(ne, 0.0);
  if (gradient) gradient->setZero(mesh_.num_dofs());
  if (hessian) std::fill(hessian->valuePtr(), hessian->valuePtr() + hessian->nonZeros(), 0.0);
  double* values = hessian ? hessian->valuePtr() : nullptr;
  const int* col = hessian ? hessian->outerIndexPtr() : nullptr;

  // Colours are processed one after the other; inside a colour no two
  // elements share a node, so scatters never collide and every matrix entry
  // receives its contributions in colour order whatever the thread count.
  for (const auto& color : mesh_.colors) {
    const int nc = static_cast<int>(color.size());
#pragma omp parallel
    {
      Vec24 ge;
      Mat24 Ke;
#pragma omp for schedule(static)
      for (int c = 0; c < nc; ++c) {
        const int e = color[c];
        const auto& geo = mesh_.geometries[mesh_.element_geometry[e]];
        const auto& mat = mesh_.materials[mesh_.element_material[e]];
        const double E = hex_evaluate(geo, mat, gather(x, e), gradient ? &ge : nullptr, hessian ? &Ke : nullptr);
        element_energy[e] = E;
        if (!std::isfinite(E)) continue;
        const auto& el = mesh_.elements[e];
        if (gradient)
          for (int i = 0; i < 8; ++i) gradient->segment<3>(3 * el[i]) += ge.segment<3>(3 * i);
        if (hessian) {
          const auto& off = block_offset_[e];
          for (int j = 0; j < 8; ++j)
            for (int b = 0; b < 3; ++b) {
              const int start = col[3 * el[j] + b];
              for (int i = 0; i < 8; ++i) {
                double* v = values + start + off[8 * j + i];
                v[0] += Ke(3 * i, 3 * j + b);
                v[1] += Ke(3 * i + 1, 3 * j + b);
                v[2] += Ke(3 * i + 2, 3 * j + b);
              }
            }
        }
      }
    }
  }
  double total = 0;
  for (double E : element_energy) {
    if (!std::isfinite(E)) return kInfiniteEnergy;
    total += E;
  }
  return total;
}

}  // namespace msfab
