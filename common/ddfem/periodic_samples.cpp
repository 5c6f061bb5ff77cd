#include "ddfem/periodic_samples.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/anisotropy.hpp"
#include "ddfem/block_newton.hpp"
#include "fem/hex_element.hpp"

namespace msfab {
namespace {

// Largest |eigenvalue| of the small strain of the coarse element over its
// Gauss points for corner displacements u.
double coarse_peak_strain(const FineBlock& block, const Vec24& u) {
  const hex8::ElementGeometry geo = block.coarse_geometry();
  double peak = 0;
  for (int q = 0; q < geo.size(); ++q) {
    Mat3 G = Mat3::Zero();
    for (int c = 0; c < 8; ++c) G += u.segment<3>(3 * c) * geo.dNdX[q].row(c);
    peak = std::max(peak, largest_small_strain(G));
  }
  return peak;
}

// The shear modulus of the block's stiffest fine material (its children's
// at level 1, the palette's under its level-1 children at level 2).
double stiffest_point_mu(const FineBlock& block) {
  double mu = 0;
  for (double m : block.point_mu0) mu = std::max(mu, m);
  return mu;
}

}  // namespace

std::vector<ForcePattern> make_corner_displacement_patterns(const FineBlock& block,
                                                            const ForceSamplingOptions& options) {
  // Positions r from the centre in half-edges (voxels at level 1).
  const double h = 0.5 * block.edge();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const Vec3 center = Vec3::Constant(h);
  std::vector<ForcePattern> patterns;
  auto add = [&](ForceKind kind, const Vec3& d, const Vec3& t, auto field) {
    if (!options.kinds[int(kind)]) return;
    ForcePattern p;
    p.kind = kind, p.direction = d, p.second = t;
    Vec24 u;
    for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = h * field((X.row(c).transpose() - center) / h);
    const double peak = coarse_peak_strain(block, u);
    if (!(peak > 0)) return;
    p.force = u / peak;
    patterns.push_back(std::move(p));
  };
  for (const Vec3& d : sampling_directions(options.include_axes, options.sphere_directions, options.seed)) {
    const Vec3 t = sampling_transverse(d);
    for (ForceKind kind : kSmoothFamilies)
      add(kind, d, family_second(kind, t), [&](const Vec3& r) { return family_field(kind, d, t, r); });
  }
  for_each_cube_edge([&](int a, int b, const Vec3& e) {
    add(ForceKind::pinch, e, X.row(a).transpose(), [&](const Vec3& r) -> Vec3 {
      const Vec3 at = center + h * r;
      if ((at - X.row(a).transpose()).norm() < 1e-9 * h) return e;
      if ((at - X.row(b).transpose()).norm() < 1e-9 * h) return -e;
      return Vec3::Zero();
    });
  });
  return patterns;
}

PeriodicBlockSolver::PeriodicBlockSolver(const FineBlock& block, double newton_tolerance)
    : block_(block),
      assembler_(block.mesh()),
      tolerance_(newton_tolerance),
      force_round_off_(stiffest_point_mu(block) * block.voxel_size * block.voxel_size) {
  if (block.context != 0) throw std::invalid_argument("PeriodicBlockSolver: takes the isolated block (context 0)");
  // A void child is fine here: among periodic copies of a 2 x 2 x 2 block
  // every node class (corners included) is touched by all eight children,
  // so one solid child puts material at every class; the corners are
  // prescribed. A 4 x 4 x 4 block with a void child may leave a class
  // without a node; such a class has no unknown.
  const HexMesh& mesh = block.mesh();
  const int N = block.voxels_per_edge;
  rest_ = assembler_.rest_positions();
  node_class_.assign(mesh.num_nodes(), -1);
  node_weights_.resize(mesh.num_nodes());
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Vec3 s = mesh.nodes.row(n).transpose() / block.edge();  // in [0, 1]^3
    int lattice[3];
    for (int a = 0; a < 3; ++a) lattice[a] = static_cast<int>(std::lround(N * s[a])) % N;
    node_class_[n] = (lattice[0] * N + lattice[1]) * N + lattice[2];
    for (int c = 0; c < 8; ++c) {
      const double wx = (c >> 2 & 1) ? s.x() : 1 - s.x(), wy = (c >> 1 & 1) ? s.y() : 1 - s.y(),
                   wz = (c & 1) ? s.z() : 1 - s.z();
      node_weights_[n][c] = wx * wy * wz;
    }
  }
  // Number the classes that have nodes, the corners' class (0) excepted;
  // node_class_ then holds each node's unknown, -1 at the corners.
  std::vector<int> unknown_of_class(N * N * N, -1);
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (node_class_[n] > 0) unknown_of_class[node_class_[n]] = 0;
  int unknowns = 0;
  for (int& u : unknown_of_class)
    if (u == 0) u = unknowns++;
  for (int& c : node_class_) c = unknown_of_class[c];
  free_ = 3 * unknowns;
  // Reduction to the periodic unknowns: sum over each class's nodes.
  reduce_ = MatX::Zero(3 * mesh.num_nodes(), free_);
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (node_class_[n] >= 0) reduce_.block<3, 3>(3 * n, 3 * node_class_[n]).setIdentity();
  // Void corners: the nodal displacements are U(X) + w with U trilinear in
  // u1, so the least-squares corner values are u1 plus the fit of w by the
  // void corners' shape functions, (N_v^T N_v)^+ N_v^T w at the nodes.
  for (int c = 0; c < 8; ++c)
    if (block.corner_nodes[c] < 0) void_corners_.push_back(c);
  const int nv = static_cast<int>(void_corners_.size());
  if (nv > 0) {
    MatX N(mesh.num_nodes(), nv);
    for (int n = 0; n < mesh.num_nodes(); ++n)
      for (int i = 0; i < nv; ++i) N(n, i) = node_weights_[n][void_corners_[i]];
    const MatX fit = N.completeOrthogonalDecomposition().pseudoInverse();  // nv x nodes
    MatX per_dof = MatX::Zero(3 * nv, 3 * mesh.num_nodes());
    for (int i = 0; i < nv; ++i)
      for (int n = 0; n < mesh.num_nodes(); ++n) per_dof.block<3, 3>(3 * i, 3 * n) = fit(i, n) * Mat3::Identity();
    extrapolate_ = per_dof * reduce_;
  }
}

Vec24 PeriodicBlockSolver::corner_displacements(const Vec24& u1, const VecX& w) const {
  Vec24 u = u1;
  if (void_corners_.empty() || w.size() != free_) return u;
  const VecX correction = extrapolate_ * w;
  for (std::size_t i = 0; i < void_corners_.size(); ++i)
    u.segment<3>(3 * void_corners_[i]) += correction.segment<3>(3 * i);
  return u;
}

VecX PeriodicBlockSolver::positions(const Vec24& u1, const VecX& w) const {
  VecX x = rest_;
  for (int n = 0; n < static_cast<int>(node_class_.size()); ++n) {
    Vec3 u = Vec3::Zero();
    for (int c = 0; c < 8; ++c) u += node_weights_[n][c] * u1.segment<3>(3 * c);
    if (node_class_[n] >= 0) u += w.segment<3>(3 * node_class_[n]);
    x.segment<3>(3 * n) += u;
  }
  return x;
}

double PeriodicBlockSolver::relax(const Vec24& u1, VecX& w, int* iterations) const {
  if (w.size() != free_) w = VecX::Zero(free_);
  const int nodes = static_cast<int>(node_class_.size());
  SpMat K = assembler_.pattern();
  VecX g(3 * nodes);
  const MatX& P = reduce_;
  double E = assembler_.energy(positions(u1, w));
  if (!std::isfinite(E)) {
    w.setZero();
    E = assembler_.energy(positions(u1, w));
    if (!std::isfinite(E)) return kInfiniteEnergy;  // the trilinear field itself inverts a fine element
  }
  const double h = block_.voxel_size;
  // Level-1 blocks (27 nodes) reduce by the dense products, as they were
  // built with; larger blocks scatter K's entries by periodic class, a pass
  // over its nonzeros instead of two dense products with P.
  const bool scatter = block_.voxels_per_edge > 2;
  auto reduced_gradient = [&](const VecX& full) -> VecX {
    if (!scatter) return P.transpose() * full;
    VecX r = VecX::Zero(free_);
    for (int n = 0; n < nodes; ++n)
      if (node_class_[n] >= 0) r.segment<3>(3 * node_class_[n]) += full.segment<3>(3 * n);
    return r;
  };
  auto reduced_hessian = [&]() -> MatX {
    if (!scatter) return P.transpose() * (K * P);
    MatX H = MatX::Zero(free_, free_);
    for (int col = 0; col < K.outerSize(); ++col) {
      const int cc = node_class_[col / 3];
      if (cc < 0) continue;
      for (SpMat::InnerIterator it(K, col); it; ++it) {
        const int rc = node_class_[it.row() / 3];
        if (rc >= 0) H(3 * rc + it.row() % 3, 3 * cc + col % 3) += it.value();
      }
    }
    return H;
  };
  for (int it = 0; it < 100; ++it) {
    assembler_.evaluate(positions(u1, w), &g, &K);
    const VecX gw = reduced_gradient(g);
    // Converged when the fluctuation's forces are a small fraction of the
    // forces the block carries (the corner reactions), or at round-off:
    // relative to those forces, or absolute, at the nodal forces' own
    // round-off (mu h^2 eps for the stiffest child), which is what is left
    // when the block takes the deformation without strain and carries
    // nothing (void layers opening).
    const double scale = g.norm();
    const double round_off = 1e3 * std::numeric_limits<double>::epsilon() * std::max(scale, force_round_off_);
    if (gw.norm() <= std::max(tolerance_ * scale, round_off) || scale == 0.0) {
      if (iterations) *iterations = it;
      return E;
    }
    VecX step;
    if (!shifted_descent_step(reduced_hessian(), gw, step)) return kInfiniteEnergy;
    // A quarter voxel at most per step (inverted elements are +inf).
    double alpha = std::min(1.0, 0.25 * h / step.cwiseAbs().maxCoeff());
    const double slope = step.dot(gw);
    bool accepted = false;
    for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
      const VecX trial = w + alpha * step;
      const double E_trial = assembler_.energy(positions(u1, trial));
      if (energy_step_accepted(E_trial, E, alpha, slope, ls == 0)) {
        w = trial, E = E_trial, accepted = true;
        break;
      }
    }
    if (!accepted) return kInfiniteEnergy;
  }
  return kInfiniteEnergy;
}

ForceSampleSet sample_periodic(const FineBlock& block, const ForceSamplingOptions& options) {
  check_sampling_options(options);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<ForcePattern> patterns = make_corner_displacement_patterns(block, options);
  const PeriodicBlockSolver solver(block, options.newton_tolerance);
  // A deformation the block takes without strain (a slab's void layers
  // opening, children hinged at an edge) stores round-off, not energy: its
  // relative residual would be noise. Such samples are dropped when they
  // store less than 1e-8 of what the block's stiffest child would at the
  // same peak strain; an all-solid block stores at least its softest
  // child's share.
  const double mu_max = stiffest_point_mu(block);
  const double volume = std::pow(block.edge(), 3);
  const auto solve = [&](int p, double load, VecX& w, ForceSample& sample) {
    const Vec24 unit = patterns[p].force;
    VecX trial = w;
    int its = 0;
    const double E = solver.relax(load * unit, trial, &its);
    if (!std::isfinite(E) || !(E > 1e-8 * mu_max * volume * load * load)) return false;
    w = trial;
    sample.corner_displacement = solver.corner_displacements(load * unit, w);
    sample.energy = E;
    sample.newton_iterations = its;
    return true;
  };
  ForceSampleSet set = sample_patterns(
      patterns, options, [&](int) { return options.max_strain; }, solve);
  set.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return set;
}

Vec3 stiffest_periodic_direction(const FineBlock& block, int directions, double strain, std::uint64_t seed,
                                 double newton_tolerance) {
  const PeriodicBlockSolver solver(block, newton_tolerance);
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const Vec3 center = Vec3::Constant(0.5 * block.edge());
  Vec3 best = Vec3::UnitX();
  double best_energy = -1;
  for (const Vec3& d : sampling_directions(true, directions, seed)) {
    Vec24 u;
    for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = strain * d * d.dot(X.row(c).transpose() - center);
    VecX w;
    const double E = solver.relax(u, w);
    if (std::isfinite(E) && E > best_energy) best_energy = E, best = d;
  }
  return canonical_direction(best);
}

std::vector<Vec3> periodic_point_directions(const FineBlock& block, const AnisotropyOptions& options) {
  if (options.directions < 3) throw InputError("anisotropy: at least 3 stretching directions are needed");
  if (!(options.strain > 0.0)) throw InputError("anisotropy: strain must be > 0");
  const PeriodicBlockSolver solver(block, options.newton_tolerance);
  const HexMesh& mesh = block.mesh();
  const hex8::ElementGeometry coarse = block.coarse_geometry();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const Vec3 center = Vec3::Constant(0.5 * block.edge());
  // The element under each coarse point (-1 in a void voxel).
  std::vector<int> element_of_point(coarse.size(), -1);
  for (int q = 0; q < coarse.size(); ++q) element_of_point[q] = block.voxels.voxel_element[block.voxel_of_point(q)];
  std::vector<std::vector<Vec3>> cloud(coarse.size());
  int relaxed = 0;
  for (const Vec3& d : sampling_directions(false, options.directions, options.seed)) {
    Vec24 u;
    for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = options.strain * d * d.dot(X.row(c).transpose() - center);
    VecX w;
    if (!std::isfinite(solver.relax(u, w))) continue;
    ++relaxed;
    const VecX x = solver.positions(u, w);
    for (int q = 0; q < coarse.size(); ++q) {
      const int e = element_of_point[q];
      if (e < 0) continue;
      hex8::NodeMatrix xe;
      for (int a = 0; a < 8; ++a) xe.row(a) = x.segment<3>(3 * mesh.elements[e][a]).transpose();
      const double energy =
          hex_energy(mesh.geometries[mesh.element_geometry[e]], mesh.materials[mesh.element_material[e]], xe);
      if (!(energy > 0) || !std::isfinite(energy)) continue;
      const double l = 1.0 / std::sqrt(energy);
      cloud[q].push_back(l * d);
      cloud[q].push_back(-l * d);
    }
  }
  if (relaxed < 3) throw NumericalError("anisotropy: too few periodic stretches relaxed");
  std::vector<Vec3> direction(coarse.size(), Vec3::UnitX());
  for (int q = 0; q < coarse.size(); ++q) {
    if (cloud[q].empty()) continue;
    MatX M(cloud[q].size(), 3);
    for (size_t i = 0; i < cloud[q].size(); ++i) M.row(i) = cloud[q][i].transpose();
    Eigen::JacobiSVD<MatX> svd(M, Eigen::ComputeThinV);
    direction[q] = canonical_direction(svd.matrixV().col(2));
  }
  return direction;
}

}  // namespace msfab
