#include "fem/elastic_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace msfab {

ElasticAssembler::ElasticAssembler(const HexMesh& mesh) : mesh_(mesh) {
  // A state only for the elements with bubble modes (about 2.3 kB each): a
  // mixed mesh's fine elements have none.
  bubble_slot_.assign(mesh.num_elements(), -1);
  int with_bubbles = 0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    if (mesh.geometries[mesh.element_geometry[e]].has_enhanced_modes()) bubble_slot_[e] = with_bubbles++;
  if (with_bubbles == 0) bubble_slot_.clear();
  bubbles_.assign(with_bubbles, BubbleState{});
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

ElasticAssembler::ElasticAssembler(const HexMesh& mesh, std::shared_ptr<const NodeConstraints> constraints)
    : ElasticAssembler(mesh) {
  if (!constraints) return;
  const SpMat& T = constraints->node_map;
  if (T.rows() != mesh.num_nodes() || T.cols() != constraints->unknown_rest.rows())
    throw std::invalid_argument("ElasticAssembler: the node constraints do not match the mesh");
  constraints_ = std::move(constraints);
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(3 * size_t(T.nonZeros()));
  for (int j = 0; j < T.outerSize(); ++j)
    for (SpMat::InnerIterator it(T, j); it; ++it)
      for (int a = 0; a < 3; ++a) trip.emplace_back(3 * int(it.row()) + a, 3 * j + a, it.value());
  dof_map_.resize(3 * T.rows(), 3 * T.cols());
  dof_map_.setFromTriplets(trip.begin(), trip.end());
  dof_map_.makeCompressed();
  dof_map_t_ = dof_map_.transpose();
  // The symbolic product of the pattern: ones, so that no entry cancels.
  SpMat ones = mesh_pattern();
  std::fill(ones.valuePtr(), ones.valuePtr() + ones.nonZeros(), 1.0);
  SpMat abs_map = dof_map_.cwiseAbs(), abs_map_t = dof_map_t_.cwiseAbs();
  reduced_pattern_ = SpMat(abs_map_t * ones * abs_map);
  reduced_pattern_.makeCompressed();
  std::fill(reduced_pattern_.valuePtr(), reduced_pattern_.valuePtr() + reduced_pattern_.nonZeros(), 0.0);
  // The reduction plan: mesh entry (i, j) adds T(i, a) T(j, b) into (a, b).
  const SpMat map_rows = SpMat(dof_map_t_);  // column i: the unknowns of mesh DOF i
  const int* rp = reduced_pattern_.outerIndexPtr();
  const int* ri = reduced_pattern_.innerIndexPtr();
  for (int j = 0; j < ones.outerSize(); ++j)
    for (int k = ones.outerIndexPtr()[j]; k < ones.outerIndexPtr()[j + 1]; ++k) {
      const int i = ones.innerIndexPtr()[k];
      for (SpMat::InnerIterator b(map_rows, j); b; ++b)
        for (SpMat::InnerIterator a(map_rows, i); a; ++a) {
          const int col = static_cast<int>(b.row()), row = static_cast<int>(a.row());
          const int* pos = std::lower_bound(ri + rp[col], ri + rp[col + 1], row);
          reduce_from_.push_back(k);
          reduce_to_.push_back(static_cast<int>(pos - ri));
          reduce_weight_.push_back(a.value() * b.value());
        }
    }
}

int ElasticAssembler::num_dofs() const {
  return constraints_ ? 3 * static_cast<int>(constraints_->unknown_rest.rows()) : mesh_.num_dofs();
}

const NodeArray& ElasticAssembler::unknown_rest_nodes() const {
  return constraints_ ? constraints_->unknown_rest : mesh_.nodes;
}

SpMat ElasticAssembler::pattern() const { return constraints_ ? reduced_pattern_ : mesh_pattern(); }

SpMat ElasticAssembler::mesh_pattern() const {
  const int n = mesh_.num_dofs();
  SpMat A(n, n);
  A.resizeNonZeros(static_cast<Eigen::Index>(row_idx_.size()));
  std::copy(col_ptr_.begin(), col_ptr_.end(), A.outerIndexPtr());
  std::copy(row_idx_.begin(), row_idx_.end(), A.innerIndexPtr());
  std::fill(A.valuePtr(), A.valuePtr() + row_idx_.size(), 0.0);
  return A;
}

VecX ElasticAssembler::rest_positions() const {
  const NodeArray& nodes = unknown_rest_nodes();
  VecX x(3 * nodes.rows());
  for (int i = 0; i < nodes.rows(); ++i) x.segment<3>(3 * i) = nodes.row(i).transpose();
  return x;
}

VecX ElasticAssembler::mesh_positions(const VecX& x) const { return constraints_ ? VecX(dof_map_ * x) : x; }

hex8::NodeMatrix ElasticAssembler::gather(const VecX& x, int e) const {
  hex8::NodeMatrix xe;
  for (int i = 0; i < 8; ++i) xe.row(i) = x.segment<3>(3 * mesh_.elements[e][i]).transpose();
  return xe;
}

double ElasticAssembler::energy(const VecX& x) const { return evaluate(x, nullptr, nullptr); }

double ElasticAssembler::evaluate(const VecX& x, VecX* gradient, SpMat* hessian) const {
  if (!constraints_) return evaluate_mesh(x, gradient, hessian);
  if (x.size() != num_dofs()) throw std::invalid_argument("ElasticAssembler: x does not match the unknowns");
  VecX mesh_gradient;
  SpMat mesh_hessian;
  if (hessian) mesh_hessian = mesh_pattern();
  const double E = evaluate_mesh(dof_map_ * x, gradient ? &mesh_gradient : nullptr, hessian ? &mesh_hessian : nullptr);
  if (!std::isfinite(E)) return E;
  if (gradient) *gradient = dof_map_t_ * mesh_gradient;
  if (hessian) {
    if (hessian->nonZeros() != reduced_pattern_.nonZeros())
      throw std::invalid_argument("ElasticAssembler: the Hessian does not carry the constrained pattern");
    double* out = hessian->valuePtr();
    std::fill(out, out + hessian->nonZeros(), 0.0);
    const double* in = mesh_hessian.valuePtr();
    for (size_t k = 0; k < reduce_from_.size(); ++k) out[reduce_to_[k]] += reduce_weight_[k] * in[reduce_from_[k]];
  }
  return E;
}

double ElasticAssembler::evaluate_mesh(const VecX& x, VecX* gradient, SpMat* hessian) const {
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
      // Static: a dynamic or guided schedule was measured slower on every
      // mesh tried, coarse meshes with bubbles included (neighbouring
      // elements' entries then change threads and their cache lines bounce).
#pragma omp for schedule(static)
      for (int c = 0; c < nc; ++c) {
        const int e = color[c];
        const auto& geo = mesh_.geometries[mesh_.element_geometry[e]];
        const auto& mat = mesh_.materials[mesh_.element_material[e]];
        const int slot = bubble_slot_.empty() ? -1 : bubble_slot_[e];
        const double E = hex_evaluate(geo, mat, gather(x, e), gradient ? &ge : nullptr, hessian ? &Ke : nullptr,
                                      slot < 0 ? nullptr : &bubbles_[slot]);
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
