#include "ddfem/periodic_samples.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/anisotropy.hpp"
#include "ddfem/block_newton.hpp"

namespace msfab {
namespace {

constexpr int kFree = 21;  // 7 periodic node classes x 3 (the corners' class is prescribed)

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
  const double h = block.voxel_size;
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const Vec3 center = Vec3::Constant(h);
  std::vector<ForcePattern> patterns;
  auto add = [&](ForceKind kind, const Vec3& d, const Vec3& t, auto field) {
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
  for (int a = 0; a < 8; ++a)
    for (int bit = 0; bit < 3; ++bit) {
      const int b = a | (1 << bit);
      if (b == a) continue;
      const Vec3 e = Vec3::Unit(2 - bit);  // bit 2 is x, bit 0 is z
      add(ForceKind::pinch, e, X.row(a).transpose(), [&](const Vec3& r) -> Vec3 {
        const Vec3 at = center + h * r;
        if ((at - X.row(a).transpose()).norm() < 1e-9 * h) return e;
        if ((at - X.row(b).transpose()).norm() < 1e-9 * h) return -e;
        return Vec3::Zero();
      });
    }
  return patterns;
}

PeriodicBlockSolver::PeriodicBlockSolver(const FineBlock& block, double newton_tolerance)
    : block_(block),
      assembler_(block.mesh()),
      tolerance_(newton_tolerance),
      force_round_off_(stiffest_point_mu(block) * block.voxel_size * block.voxel_size) {
  if (block.context != 0) throw std::invalid_argument("PeriodicBlockSolver: takes the isolated block (context 0)");
  // A void child is fine here: among periodic copies every node class
  // (corners included) is touched by all eight children, so one solid child
  // puts material at every class; the corners are prescribed.
  const HexMesh& mesh = block.mesh();
  rest_ = assembler_.rest_positions();
  node_class_.assign(mesh.num_nodes(), -1);
  node_weights_.resize(mesh.num_nodes());
  const double h = block.voxel_size;
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Vec3 s = mesh.nodes.row(n).transpose() / (2 * h);  // in [0, 1]^3
    int lattice[3];
    for (int a = 0; a < 3; ++a) lattice[a] = static_cast<int>(std::lround(2 * s[a]));
    node_class_[n] = 4 * (lattice[0] % 2) + 2 * (lattice[1] % 2) + (lattice[2] % 2);
    for (int c = 0; c < 8; ++c) {
      const double wx = (c >> 2 & 1) ? s.x() : 1 - s.x(), wy = (c >> 1 & 1) ? s.y() : 1 - s.y(),
                   wz = (c & 1) ? s.z() : 1 - s.z();
      node_weights_[n][c] = wx * wy * wz;
    }
  }
  // Reduction to the periodic unknowns: sum over each class's nodes.
  reduce_ = MatX::Zero(3 * mesh.num_nodes(), kFree);
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (node_class_[n] > 0) reduce_.block<3, 3>(3 * n, 3 * (node_class_[n] - 1)).setIdentity();
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
      for (int n = 0; n < mesh.num_nodes(); ++n)
        per_dof.block<3, 3>(3 * i, 3 * n) = fit(i, n) * Mat3::Identity();
    extrapolate_ = per_dof * reduce_;
  }
}

Vec24 PeriodicBlockSolver::corner_displacements(const Vec24& u1, const VecX& w) const {
  Vec24 u = u1;
  if (void_corners_.empty() || w.size() != kFree) return u;
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
    if (node_class_[n] > 0) u += w.segment<3>(3 * (node_class_[n] - 1));
    x.segment<3>(3 * n) += u;
  }
  return x;
}

double PeriodicBlockSolver::relax(const Vec24& u1, VecX& w, int* iterations) const {
  if (w.size() != kFree) w = VecX::Zero(kFree);
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
  for (int it = 0; it < 100; ++it) {
    assembler_.evaluate(positions(u1, w), &g, &K);
    const VecX gw = P.transpose() * g;
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
    if (!shifted_descent_step(P.transpose() * (K * P), gw, step)) return kInfiniteEnergy;
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
  ForceSampleSet set;
  set.patterns = make_corner_displacement_patterns(block, options);
  const PeriodicBlockSolver solver(block, options.newton_tolerance);
  // A deformation the block takes without strain (a slab's void layers
  // opening, children hinged at an edge) stores round-off, not energy: its
  // relative residual would be noise. Such samples are dropped when they
  // store less than 1e-8 of what the block's stiffest child would at the
  // same peak strain; an all-solid block stores at least its softest
  // child's share.
  const double mu_max = stiffest_point_mu(block);
  const double volume = std::pow(2 * block.voxel_size, 3);
  for (int p = 0; p < static_cast<int>(set.patterns.size()); ++p) {
    const Vec24 unit = set.patterns[p].force;
    for (int sign : {1, -1}) {
      VecX w;  // continuation in the magnitude
      for (int m = 1; m <= options.magnitudes; ++m) {
        const double load = sign * options.max_strain * m / options.magnitudes;
        ++set.attempted;
        VecX trial = w;
        int its = 0;
        const double E = solver.relax(load * unit, trial, &its);
        if (!std::isfinite(E) || !(E > 1e-8 * mu_max * volume * load * load)) {
          ++set.dropped;
          continue;
        }
        w = trial;
        ForceSample s;
        s.pattern = p;
        s.load = load;
        s.corner_displacement = solver.corner_displacements(load * unit, w);
        s.energy = E;
        s.newton_iterations = its;
        set.samples.push_back(s);
      }
    }
  }
  set.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return set;
}

Vec3 stiffest_periodic_direction(const FineBlock& block, int directions, double strain, std::uint64_t seed,
                                 double newton_tolerance) {
  const PeriodicBlockSolver solver(block, newton_tolerance);
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const Vec3 center = Vec3::Constant(block.voxel_size);
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

}  // namespace msfab
