#include "ddfem/force_samples.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/block_newton.hpp"

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

}  // namespace

Vec3 sampling_transverse(const Vec3& d) {
  const Vec3 trial = std::abs(d.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  // Axes map to the next axis (x -> y, y -> z, z -> x) so axis shears are the classic ones.
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(d[a]) - 1.0) < 1e-12) return Vec3::Unit((a + 1) % 3);
  return (trial - trial.dot(d) * d).normalized();
}

Vec3 family_field(ForceKind kind, const Vec3& d, const Vec3& t, const Vec3& r) {
  switch (kind) {
    case ForceKind::stretch: return d * d.dot(r);
    case ForceKind::shear: return d * t.dot(r) + t * d.dot(r);  // symmetric: no net moment
    case ForceKind::bend: return d * (d.dot(r) * t.dot(r));
    case ForceKind::twist: return d.cross(r) * d.dot(r);
    case ForceKind::pinch: break;
  }
  throw std::invalid_argument("family_field: pinching is not a smooth family");
}

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

std::string sampling_mode_name(ForceSamplingOptions::Mode mode) {
  switch (mode) {
    case ForceSamplingOptions::Mode::isolated: return "isolated";
    case ForceSamplingOptions::Mode::patch: return "patch";
    case ForceSamplingOptions::Mode::periodic: return "periodic";
  }
  return "unknown";
}

ForceSamplingOptions::Mode parse_sampling_mode(const std::string& name) {
  for (auto m :
       {ForceSamplingOptions::Mode::isolated, ForceSamplingOptions::Mode::patch, ForceSamplingOptions::Mode::periodic})
    if (sampling_mode_name(m) == name) return m;
  throw InputError("unknown sampling mode '" + name + "' (isolated, patch or periodic)");
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

namespace {

// Consistent nodal loads of the traction sigma(r) n on the outer faces of a
// block in context (the faces on the bounding box of its mesh), r the
// position from the block centre in voxels. 2 x 2 Gauss points per face are
// exact for the at most linear stress fields used here. Faces of void
// voxels are absent, as in a body; interior surfaces next to void are free.
template <typename StressField>
VecX outer_face_loads(const FineBlock& block, const Vec3& center, StressField sigma) {
  const HexMesh& mesh = block.mesh();
  const double h = block.voxel_size;
  const Vec3 lo = mesh.bbox_min(), hi = mesh.bbox_max();
  const double gauss = 1.0 / std::sqrt(3.0);
  VecX f = VecX::Zero(mesh.num_dofs());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const hex8::NodeMatrix X = mesh.element_rest_positions(e);
    const Vec3 mid = 0.5 * (X.row(0) + X.row(7)).transpose();
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const double plane = side ? hi[axis] : lo[axis];
        if (std::abs(mid[axis] + (side ? 0.5 : -0.5) * h - plane) > 1e-9 * h) continue;
        const int b = (axis + 1) % 3, c = (axis + 2) % 3;
        const Vec3 normal = (side ? 1.0 : -1.0) * Vec3::Unit(axis);
        for (int gb = 0; gb < 2; ++gb)
          for (int gc = 0; gc < 2; ++gc) {
            const double xb = gb ? gauss : -gauss, xc = gc ? gauss : -gauss;
            Vec3 point = mid;
            point[axis] = plane;
            point[b] += 0.5 * h * xb, point[c] += 0.5 * h * xc;
            const Vec3 traction = sigma((point - center) / h) * normal;
            const double area = 0.25 * h * h;  // Gauss weight 1 times the Jacobian (h/2)^2
            for (int node = 0; node < 8; ++node) {
              const int bits[3] = {node >> 2 & 1, node >> 1 & 1, node & 1};  // x, y, z
              if (bits[axis] != side) continue;
              const double N = 0.25 * (1 + (bits[b] ? xb : -xb)) * (1 + (bits[c] ? xc : -xc));
              f.segment<3>(3 * mesh.elements[e][node]) += area * N * traction;
            }
          }
      }
  }
  return f;
}

Mat3 outer(const Vec3& a, const Vec3& b) { return a * b.transpose(); }

}  // namespace

std::vector<ForcePattern> make_force_patterns(const FineBlock& block, const ForceSamplingOptions& options) {
  const HexMesh& mesh = block.mesh();
  const int n = mesh.num_nodes();
  const double h = block.voxel_size;
  const Vec3 center = Vec3::Constant(h);
  // Isolated block: each node carries the field times its lumped volume (an
  // eighth of every incident element). For a field linear in position this
  // is the consistent load of a surface traction, so a homogeneous block
  // deforms smoothly, as it would inside a larger body; equal nodal weights
  // would overload the corners, whose displacements are exactly what the
  // coarse element sees.
  std::vector<double> lumped(n, 0.0);
  for (const auto& element : mesh.elements)
    for (int node : element) lumped[node] += 0.125;
  std::vector<ForcePattern> patterns;
  auto keep = [&](ForcePattern p) {
    p.force = self_equilibrate(mesh, p.force);
    const double norm = p.force.norm();
    if (norm > 0) {
      p.force /= norm;
      patterns.push_back(std::move(p));
    }
  };
  auto add = [&](ForceKind kind, const Vec3& d, const Vec3& t, auto field) {
    ForcePattern p;
    p.kind = kind;
    p.direction = d;
    p.second = t;
    p.force.setZero(3 * n);
    for (int i = 0; i < n; ++i)
      p.force.segment<3>(3 * i) = lumped[i] * field((mesh.nodes.row(i).transpose() - center) / h);
    keep(std::move(p));
  };
  // Block in context: each kind is a divergence-free stress field whose
  // tractions load the outer faces of the patch, as a body is loaded at its
  // surface; nothing acts inside. Under the constant fields (stretch,
  // shear) a homogeneous patch deforms affinely, so its block is exactly a
  // coarse element under that deformation.
  auto add_stress = [&](ForceKind kind, const Vec3& d, const Vec3& t, auto sigma) {
    ForcePattern p;
    p.kind = kind;
    p.direction = d;
    p.second = t;
    p.force = outer_face_loads(block, center, sigma);
    keep(std::move(p));
  };
  for (const Vec3& d : sampling_directions(options.include_axes, options.sphere_directions, options.seed)) {
    const Vec3 t = sampling_transverse(d);
    if (block.context > 0) {
      add_stress(ForceKind::stretch, d, Vec3::Zero(), [&](const Vec3&) -> Mat3 { return outer(d, d); });
      add_stress(ForceKind::shear, d, t, [&](const Vec3&) -> Mat3 { return outer(d, t) + outer(t, d); });
      // Pure bending: axial stress linear across the neutral plane t.r = 0.
      add_stress(ForceKind::bend, d, t, [&](const Vec3& r) -> Mat3 { return t.dot(r) * outer(d, d); });
      // Torsion about d: shear stress growing with the distance from the axis.
      add_stress(ForceKind::twist, d, Vec3::Zero(), [&](const Vec3& r) -> Mat3 {
        const Vec3 w = d.cross(r);
        return outer(w, d) + outer(d, w);
      });
      continue;
    }
    for (ForceKind kind : kSmoothFamilies)
      add(kind, d, family_second(kind, t), [&](const Vec3& r) { return family_field(kind, d, t, r); });
  }
  // Pinching: the two corners of each cube edge pushed towards each other.
  for_each_cube_edge([&](int a, int b, const Vec3& e) {
    ForcePattern p;
    p.kind = ForceKind::pinch;
    p.direction = e;
    p.second = block.coarse_rest_positions().row(a).transpose();
    p.force.setZero(3 * n);
    p.force.segment<3>(3 * block.corner_nodes[a]) = p.direction / std::sqrt(2.0);
    p.force.segment<3>(3 * block.corner_nodes[b]) = -p.direction / std::sqrt(2.0);
    patterns.push_back(std::move(p));
  });
  return patterns;
}

namespace {
// Dense copy of a sparse Hessian projected on the null space: Z^T K Z.
MatX project(const SpMat& K, const MatX& Z) { return Z.transpose() * (K * Z); }

// Above this many DOFs the Newton steps use the sparse KKT path; the
// isolated block has 81.
constexpr int kDenseDofLimit = 120;
// The identity shift that makes K's rigid modes invertible on the sparse
// path, relative to the largest diagonal entry of the rest stiffness. It
// perturbs the Newton step by about this relative amount (a Newton
// iteration then contracts the error by ~1e-8 near the solution) and
// amplifies the rigid components of the back-solves by its inverse, which
// the Schur correction removes.
constexpr double kRigidShift = 1e-8;
}  // namespace

// K + sigma I factored once per Newton iteration (symbolic analysis once),
// with the Schur complement S = G (K + sigma I)^{-1} G^T of the six
// constraints.
struct BlockSolver::SparseKkt {
  Eigen::SimplicialLDLT<SpMat> ldlt;
  MatX Gt;                 // G^T
  Eigen::LDLT<MatX> gram;  // G G^T, for the exact projection on G d = 0
  MatX Y;                  // (K + sigma I)^{-1} G^T
  Eigen::LDLT<MatX> schur;
  bool positive_on_null_space = false;

  // Factors K + shift I; false if the factorization failed.
  bool factor(const SpMat& K, double shift) {
    SpMat A = K;
    for (int i = 0; i < A.rows(); ++i) A.coeffRef(i, i) += shift;
    ldlt.factorize(A);
    if (ldlt.info() != Eigen::Success) return false;
    Y = ldlt.solve(Gt);
    const MatX S = Gt.transpose() * Y;
    schur.compute(S);
    // Haynsworth: inertia [A G^T; G 0] = inertia(A) + inertia(-S); the
    // reduced Hessian Z^T A Z is positive definite exactly when the KKT
    // matrix has n positive eigenvalues, i.e. when S has as many negative
    // eigenvalues as A.
    int negative_A = 0;
    for (int i = 0; i < ldlt.vectorD().size(); ++i) negative_A += ldlt.vectorD()[i] < 0;
    const VecX s_eig = Eigen::SelfAdjointEigenSolver<MatX>(S, Eigen::EigenvaluesOnly).eigenvalues();
    int negative_S = 0;
    for (int i = 0; i < s_eig.size(); ++i) negative_S += s_eig[i] < 0;
    positive_on_null_space = Y.allFinite() && negative_A == negative_S && negative_A <= 6;
    return positive_on_null_space;
  }
  // argmin 1/2 d^T A d + r^T d subject to G d = 0.
  VecX solve(const VecX& r) const {
    const VecX z = ldlt.solve(r);
    const VecX mu = schur.solve(Gt.transpose() * z);
    VecX d = -(z - Y * mu);
    d -= Gt * gram.solve(Gt.transpose() * d);  // round-off in the rigid components
    return d;
  }
};

BlockSolver::~BlockSolver() = default;

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
  if (static_cast<int>(block.core_element.size()) != mesh.num_elements())
    throw std::invalid_argument("BlockSolver: the block has no core-element mask (use make_fine_block)");
  if (std::find(block.core_element.begin(), block.core_element.end(), 0) != block.core_element.end()) {
    core_mesh_ = mesh;
    core_mesh_.elements.clear(), core_mesh_.element_geometry.clear();
    core_mesh_.element_material.clear(), core_mesh_.element_tag.clear();
    for (int e = 0; e < mesh.num_elements(); ++e)
      if (block.core_element[e]) {
        core_mesh_.elements.push_back(mesh.elements[e]);
        core_mesh_.element_geometry.push_back(mesh.element_geometry[e]);
        core_mesh_.element_material.push_back(mesh.element_material[e]);
        core_mesh_.element_tag.push_back(mesh.element_tag[e]);
      }
    core_mesh_.colors = greedy_element_coloring(core_mesh_);
    core_assembler_ = std::make_unique<ElasticAssembler>(core_mesh_);
  }
  SpMat K = assembler_.pattern();
  assembler_.evaluate(rest_, nullptr, &K);
  if (n <= kDenseDofLimit) {
    // Null space from the full QR of G^T: the last n - 6 columns of Q.
    Eigen::HouseholderQR<MatX> qr(G_.transpose());
    const MatX Q = qr.householderQ() * MatX::Identity(n, n);
    Z_ = Q.rightCols(n - 6);
    const MatX K0 = project(K, Z_);
    stiffness_scale_ = K0.diagonal().cwiseAbs().maxCoeff();
    rest_stiffness_.compute(K0);
    return;
  }
  stiffness_scale_ = K.diagonal().cwiseAbs().maxCoeff();
  for (auto* kkt : {&sparse_, &sparse_rest_}) {
    *kkt = std::make_unique<SparseKkt>();
    (*kkt)->Gt = G_.transpose();
    (*kkt)->gram.compute(G_ * G_.transpose());
    (*kkt)->ldlt.analyzePattern(K);
  }
  if (!sparse_rest_->factor(K, kRigidShift * stiffness_scale_))
    throw NumericalError("BlockSolver: the rest stiffness of the block in context is not positive definite");
}

double BlockSolver::block_energy(const VecX& x) const {
  return core_assembler_ ? core_assembler_->energy(x) : assembler_.energy(x);
}

double BlockSolver::linear_peak_strain(const VecX& force) const {
  VecX u;
  if (sparse_)
    u = sparse_rest_->solve(-force);
  else
    u = Z_ * rest_stiffness_.solve(Z_.transpose() * force);
  const HexMesh& mesh = block_.mesh();
  double peak = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (!block_.core_element[e]) continue;
    hex8::NodeMatrix ue;
    for (int c = 0; c < 8; ++c) ue.row(c) = u.segment<3>(3 * mesh.elements[e][c]).transpose();
    const auto& geo = mesh.geometries[mesh.element_geometry[e]];
    for (int q = 0; q < geo.size(); ++q)
      peak = std::max(peak, largest_small_strain(hex8::deformation_gradient(ue, geo.dNdX[q])));
  }
  return peak;
}

bool BlockSolver::newton_step(const SpMat& K, const VecX& r, VecX& step) const {
  // Shift towards a descent direction where the tangent is indefinite.
  if (!sparse_) {
    VecX y;
    if (!shifted_descent_step(project(K, Z_), Z_.transpose() * r, y)) return false;
    step = Z_ * y;
    return true;
  }
  const double base = kRigidShift * stiffness_scale_;
  double shift = 0;
  for (int attempt = 0; attempt < 12; ++attempt) {
    if (sparse_->factor(K, base + shift)) {
      step = sparse_->solve(r);
      if (step.allFinite() && step.dot(r) < 0) return true;
    }
    shift = shift == 0 ? 1e-8 * stiffness_scale_ : shift * 10;
  }
  return false;
}

// A dense Newton in the null-space coordinates for the isolated block: at
// ~80 unknowns a dense LDLT costs microseconds, whereas a sparse
// factorization's analysis and allocations would dominate. Thousands of
// these solves make a database. A block in context takes the sparse path.
BlockSolver::Solution BlockSolver::solve(const VecX& force, const VecX& x0) const {
  Solution s;
  const int n = static_cast<int>(force.size());
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
  VecX g(n), dx(n);
  for (int it = 0; it < max_iterations_; ++it) {
    assembler_.evaluate(x, &g, &K);
    const VecX r = g - force;
    // |Z^T r| = |P r| with P the projection on the constraints' null space.
    const double residual =
        sparse_ ? (r - sparse_->Gt * sparse_->gram.solve(G_ * r)).norm() : (Z_.transpose() * r).norm();
    if (residual <= target) {
      s.converged = true;
      break;
    }
    if (!newton_step(K, r, dx)) break;
    // Cap the largest nodal move of one step at a quarter voxel: the energy
    // is +inf on inverted elements, and a long step could leap across that
    // barrier into a reflected state.
    const double largest = dx.cwiseAbs().maxCoeff();
    double alpha = std::min(1.0, 0.25 * block_.voxel_size / largest);
    const double slope = dx.dot(r);
    bool accepted = false;
    VecX trial;
    for (int ls = 0; ls < 40; ++ls, alpha *= 0.5) {
      trial = x + alpha * dx;
      const double phi_trial = potential(trial);
      if (energy_step_accepted(phi_trial, phi, alpha, slope, ls == 0)) {
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
  s.energy = s.converged ? block_energy(x) : kInfiniteEnergy;
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

void check_sampling_options(const ForceSamplingOptions& options) {
  if (options.magnitudes < 1) throw InputError("force sampling: magnitudes must be >= 1");
  if (!(options.max_strain > 0.0)) throw InputError("force sampling: max_strain must be > 0");
}

ForceSampleSet sample_patterns(std::vector<ForcePattern> patterns, const ForceSamplingOptions& options,
                               const std::function<double(int pattern)>& scale, const PatternSolve& solve) {
  check_sampling_options(options);
  ForceSampleSet set;
  set.patterns = std::move(patterns);
  for (int p = 0; p < static_cast<int>(set.patterns.size()); ++p) {
    const double full = scale(p);
    if (!(full > 0.0)) continue;
    for (int sign : {1, -1}) {
      VecX state;
      for (int m = 1; m <= options.magnitudes; ++m) {
        ForceSample sample;
        sample.pattern = p;
        sample.load = sign * full * m / options.magnitudes;
        ++set.attempted;
        if (solve(p, sample.load, state, sample))
          set.samples.push_back(sample);
        else
          ++set.dropped;  // the next magnitude starts again from the last kept state
      }
    }
  }
  return set;
}

ForceSampleSet sample_force_space(const FineBlock& block, const ForceSamplingOptions& options) {
  check_sampling_options(options);
  const auto t0 = std::chrono::steady_clock::now();
  const BlockSolver solver(block, options.newton_tolerance);
  std::vector<ForcePattern> patterns = make_force_patterns(block, options);
  // Each pattern's largest load makes its linear response peak at max_strain.
  const auto scale = [&](int p) {
    const double peak = solver.linear_peak_strain(patterns[p].force);
    return peak > 0.0 ? options.max_strain / peak : 0.0;
  };
  const auto solve = [&](int p, double load, VecX& start, ForceSample& sample) {
    const BlockSolver::Solution s = solver.solve(load * patterns[p].force, start);
    if (!s.converged) return false;
    start = s.x;
    sample.corner_displacement = solver.corner_displacements(s.x);
    sample.energy = s.energy;
    sample.newton_iterations = s.iterations;
    return true;
  };
  ForceSampleSet set = sample_patterns(patterns, options, scale, solve);
  set.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return set;
}

}  // namespace msfab
