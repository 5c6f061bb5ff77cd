#include "ddfem/force_samples.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"

namespace msfab {
namespace {

// Uniform double in [0, 1) from the standardized mt19937_64 sequence (the
// standard distributions are implementation-defined, this is portable).
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// A rotation drawn uniformly from a unit quaternion.
Mat3 seeded_rotation(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Eigen::Vector4d q;
  do {
    for (int i = 0; i < 4; ++i) q[i] = 2.0 * uniform01(rng) - 1.0;
  } while (q.squaredNorm() > 1.0 || q.squaredNorm() < 1e-6);
  q.normalize();
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
}

// A unit vector orthogonal to d, chosen deterministically.
Vec3 transverse(const Vec3& d) {
  const Vec3 trial = std::abs(d.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  // Axes map to the next axis (x -> y, y -> z, z -> x) so axis shears are the classic ones.
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(d[a]) - 1.0) < 1e-12) return Vec3::Unit((a + 1) % 3);
  return (trial - trial.dot(d) * d).normalized();
}

}  // namespace

std::string force_kind_name(ForceKind kind) {
  switch (kind) {
    case ForceKind::stretch: return "stretch";
    case ForceKind::shear: return "shear";
    case ForceKind::bend: return "bend";
    case ForceKind::twist: return "twist";
    case ForceKind::pinch: return "pinch";
  }
  return "unknown";
}

std::vector<Vec3> sampling_directions(bool include_axes, int sphere_directions, std::uint64_t seed) {
  if (sphere_directions < 0) throw InputError("force sampling: sphere_directions must be >= 0");
  std::vector<Vec3> dirs;
  if (include_axes)
    for (int a = 0; a < 3; ++a) dirs.push_back(Vec3::Unit(a));
  // A direction and its opposite give the same patterns (loads come in both
  // signs), so a hemisphere suffices.
  const Mat3 R = seeded_rotation(seed);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < sphere_directions; ++i) {
    const double z = (i + 0.5) / sphere_directions;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    dirs.push_back((R * Vec3(r * std::cos(phi), r * std::sin(phi), z)).normalized());
  }
  return dirs;
}

VecX self_equilibrate(const HexMesh& mesh, const VecX& force) {
  const int n = mesh.num_nodes();
  Vec3 centroid = Vec3::Zero();
  for (int i = 0; i < n; ++i) centroid += mesh.nodes.row(i).transpose();
  centroid /= n;
  Vec3 net = Vec3::Zero(), moment = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3 r = mesh.nodes.row(i).transpose() - centroid;
    const Vec3 f = force.segment<3>(3 * i);
    net += f;
    moment += r.cross(f);
    inertia += r.squaredNorm() * Mat3::Identity() - r * r.transpose();
  }
  // Subtracting a + w x r_i with a the mean force and J w = M (J the nodes'
  // inertia about the centroid) is the least-squares correction.
  const Vec3 a = net / n;
  const Vec3 w = inertia.ldlt().solve(moment);
  VecX out = force;
  for (int i = 0; i < n; ++i) {
    const Vec3 r = mesh.nodes.row(i).transpose() - centroid;
    out.segment<3>(3 * i) -= a + w.cross(r);
  }
  return out;
}

std::vector<ForcePattern> make_force_patterns(const FineBlock& block, const ForceSamplingOptions& options) {
  const HexMesh& mesh = block.mesh();
  const int n = mesh.num_nodes();
  const double h = block.voxel_size;
  const Vec3 center = Vec3::Constant(h);
  // Each node carries the field times its lumped volume (an eighth of every
  // incident element). For a field linear in position this is the consistent
  // load of a surface traction, so a homogeneous block deforms smoothly, as
  // it would inside a larger body; equal nodal weights would overload the
  // corners, whose displacements are exactly what the coarse element sees.
  std::vector<double> lumped(n, 0.0);
  for (const auto& element : mesh.elements)
    for (int node : element) lumped[node] += 0.125;
  std::vector<ForcePattern> patterns;
  auto add = [&](ForceKind kind, const Vec3& d, const Vec3& t, auto field) {
    ForcePattern p;
    p.kind = kind;
    p.direction = d;
    p.second = t;
    p.force.setZero(3 * n);
    for (int i = 0; i < n; ++i)
      p.force.segment<3>(3 * i) = lumped[i] * field((mesh.nodes.row(i).transpose() - center) / h);
    p.force = self_equilibrate(mesh, p.force);
    const double norm = p.force.norm();
    if (norm > 0) {
      p.force /= norm;
      patterns.push_back(std::move(p));
    }
  };
  for (const Vec3& d : sampling_directions(options.include_axes, options.sphere_directions, options.seed)) {
    const Vec3 t = transverse(d);
    // Stretch: traction along d growing linearly towards the two ends.
    add(ForceKind::stretch, d, Vec3::Zero(), [&](const Vec3& r) -> Vec3 { return d * d.dot(r); });
    // Simple shear (symmetric, so it carries no net moment).
    add(ForceKind::shear, d, t, [&](const Vec3& r) -> Vec3 { return d * t.dot(r) + t * d.dot(r); });
    // Bending about the axis d x t: axial forces proportional to the
    // distance from the neutral plane, opposite at the two ends.
    add(ForceKind::bend, d, t, [&](const Vec3& r) -> Vec3 { return d * (d.dot(r) * t.dot(r)); });
    // Twisting about d: tangential forces, opposite torques at the two ends.
    add(ForceKind::twist, d, Vec3::Zero(), [&](const Vec3& r) -> Vec3 { return d.cross(r) * d.dot(r); });
  }
  // Pinching: the two corners of each cube edge pushed towards each other.
  for (int a = 0; a < 8; ++a)
    for (int bit = 0; bit < 3; ++bit) {
      const int b = a | (1 << bit);
      if (b == a) continue;
      ForcePattern p;
      p.kind = ForceKind::pinch;
      p.direction = Vec3::Unit(2 - bit);  // bit 2 is x, bit 0 is z
      p.second = block.coarse_rest_positions().row(a).transpose();
      p.force.setZero(3 * n);
      p.force.segment<3>(3 * block.corner_nodes[a]) = p.direction / std::sqrt(2.0);
      p.force.segment<3>(3 * block.corner_nodes[b]) = -p.direction / std::sqrt(2.0);
      patterns.push_back(std::move(p));
    }
  return patterns;
}

namespace {
// Dense copy of a sparse Hessian projected on the null space: Z^T K Z.
MatX project(const SpMat& K, const MatX& Z) { return Z.transpose() * (K * Z); }
}  // namespace

BlockSolver::BlockSolver(const FineBlock& block, double newton_tolerance)
    : block_(block), assembler_(block.mesh()), tolerance_(newton_tolerance) {
  if (!block.has_all_corners())
    throw std::invalid_argument("BlockSolver: the block lacks a corner node (a child is void)");
  const HexMesh& mesh = block.mesh();
  const int nodes = mesh.num_nodes(), n = mesh.num_dofs();
  rest_ = assembler_.rest_positions();
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < nodes; ++i) c += mesh.nodes.row(i).transpose();
  c /= nodes;
  G_.setZero(6, n);
  for (int i = 0; i < nodes; ++i) {
    const Vec3 r = mesh.nodes.row(i).transpose() - c;
    G_.block<3, 3>(0, 3 * i).setIdentity();
    // (r x u) = [r]_x u
    G_.block<3, 3>(3, 3 * i) << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  }
  // Null space from the full QR of G^T: the last n - 6 columns of Q.
  Eigen::HouseholderQR<MatX> qr(G_.transpose());
  const MatX Q = qr.householderQ() * MatX::Identity(n, n);
  Z_ = Q.rightCols(n - 6);
  SpMat K = assembler_.pattern();
  assembler_.evaluate(rest_, nullptr, &K);
  const MatX K0 = project(K, Z_);
  stiffness_scale_ = K0.diagonal().cwiseAbs().maxCoeff();
  rest_stiffness_.compute(K0);
}

double BlockSolver::linear_peak_strain(const VecX& force) const {
  const VecX u = Z_ * rest_stiffness_.solve(Z_.transpose() * force);
  const HexMesh& mesh = block_.mesh();
  double peak = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    hex8::NodeMatrix ue;
    for (int c = 0; c < 8; ++c) ue.row(c) = u.segment<3>(3 * mesh.elements[e][c]).transpose();
    const auto& geo = mesh.geometries[mesh.element_geometry[e]];
    for (int q = 0; q < geo.size(); ++q) {
      const Mat3 G = hex8::deformation_gradient(ue, geo.dNdX[q]);
      const Mat3 eps = 0.5 * (G + G.transpose());
      peak = std::max(peak, Eigen::SelfAdjointEigenSolver<Mat3>(eps).eigenvalues().cwiseAbs().maxCoeff());
    }
  }
  return peak;
}

// A dense Newton in the null-space coordinates: at ~80 unknowns a dense
// LDLT costs microseconds, whereas a sparse factorization's analysis and
// allocations would dominate. Thousands of these solves make a database.
BlockSolver::Solution BlockSolver::solve(const VecX& force, const VecX& x0) const {
  Solution s;
  const int n = static_cast<int>(force.size());
  const int m = static_cast<int>(Z_.cols());
  VecX x = x0.size() == n ? x0 : rest_;
  auto potential = [&](const VecX& y) { return assembler_.energy(y) - force.dot(y - rest_); };
  // Below this the residual is round-off: forces of the stiffest element
  // at a displacement of 100 ulp of the block size.
  const double roundoff = 100 * std::numeric_limits<double>::epsilon() * stiffness_scale_ * block_.voxel_size;
  const double target = std::max(tolerance_ * force.norm(), roundoff);
  double phi = potential(x);
  if (!std::isfinite(phi)) {
    x = rest_;
    phi = potential(x);
  }
  SpMat K = assembler_.pattern();
  VecX g(n), step(m);
  for (int it = 0; it < max_iterations_; ++it) {
    assembler_.evaluate(x, &g, &K);
    const VecX gz = Z_.transpose() * (g - force);
    if (gz.norm() <= target) {
      s.converged = true;
      break;
    }
    const MatX H = project(K, Z_);
    // Shift towards a descent direction where the tangent is indefinite.
    double shift = 0;
    const double diag = H.diagonal().cwiseAbs().maxCoeff();
    step.setZero();
    for (int attempt = 0; attempt < 12; ++attempt) {
      Eigen::LDLT<MatX> ldlt(H + shift * MatX::Identity(m, m));
      if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
        step = -ldlt.solve(gz);
        if (step.allFinite() && step.dot(gz) < 0) break;
      }
      shift = shift == 0 ? 1e-8 * diag : shift * 10;
      step.setZero();
    }
    if (step.squaredNorm() == 0) break;
    const VecX dx = Z_ * step;
    // Cap the largest nodal move of one step at a quarter voxel: the energy
    // is +inf on inverted elements, and a long step could leap across that
    // barrier into a reflected state.
    const double largest = dx.cwiseAbs().maxCoeff();
    double alpha = std::min(1.0, 0.25 * block_.voxel_size / largest);
    const double slope = step.dot(gz);
    bool accepted = false;
    VecX trial;
    for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
      trial = x + alpha * dx;
      const double phi_trial = potential(trial);
      // Near convergence the decrease drowns in round-off; accept a first
      // trial whose energy is unchanged to machine precision.
      if (std::isfinite(phi_trial) &&
          (phi_trial <= phi + 1e-4 * alpha * slope ||
           (ls == 0 && std::abs(phi_trial - phi) <= 1e-13 * std::max(1.0, std::abs(phi))))) {
        accepted = true;
        phi = phi_trial;
        break;
      }
    }
    if (!accepted) break;
    x = trial;
    s.iterations = it + 1;
  }
  s.x = x;
  s.energy = s.converged ? assembler_.energy(x) : kInfiniteEnergy;
  if (!std::isfinite(s.energy)) s.converged = false;
  return s;
}

Vec24 BlockSolver::corner_displacements(const VecX& x) const {
  Vec24 u;
  for (int c = 0; c < 8; ++c) {
    const int node = block_.corner_nodes[c];
    u.segment<3>(3 * c) = x.segment<3>(3 * node) - rest_.segment<3>(3 * node);
  }
  return u;
}

ForceSampleSet sample_force_space(const FineBlock& block, const ForceSamplingOptions& options) {
  if (options.magnitudes < 1) throw InputError("force sampling: magnitudes must be >= 1");
  if (!(options.max_strain > 0.0)) throw InputError("force sampling: max_strain must be > 0");
  const auto t0 = std::chrono::steady_clock::now();
  ForceSampleSet set;
  set.patterns = make_force_patterns(block, options);
  const BlockSolver solver(block, options.newton_tolerance);
  for (int p = 0; p < static_cast<int>(set.patterns.size()); ++p) {
    const VecX& unit = set.patterns[p].force;
    const double peak = solver.linear_peak_strain(unit);
    if (!(peak > 0.0)) continue;
    const double full = options.max_strain / peak;
    for (int sign : {1, -1}) {
      // Magnitudes in increasing order, each started from the previous
      // converged state: a continuation that keeps Newton short.
      VecX start;
      for (int m = 1; m <= options.magnitudes; ++m) {
        const double load = sign * full * m / options.magnitudes;
        ++set.attempted;
        const BlockSolver::Solution s = solver.solve(load * unit, start);
        if (!s.converged) {
          ++set.dropped;  // the next magnitude starts again from the last converged state
          continue;
        }
        start = s.x;
        ForceSample sample;
        sample.pattern = p;
        sample.load = load;
        sample.corner_displacement = solver.corner_displacements(s.x);
        sample.energy = s.energy;
        sample.newton_iterations = s.iterations;
        set.samples.push_back(sample);
      }
    }
  }
  set.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return set;
}

}  // namespace msfab
