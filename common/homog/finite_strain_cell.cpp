#include "homog/finite_strain_cell.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "fem/hex_element.hpp"
#include "homog/periodic_homogenization.hpp"
#include "solve/cholmod_solver.hpp"

namespace msfab {

namespace {

// Whether the solid (voxels sharing a node are connected, across the
// periodic boundary too) reaches its own periodic copy along each axis: a
// breadth-first search over voxels that keeps each voxel's unwrapped
// position; meeting a voxel again at another position is a path to a copy.
std::array<bool, 3> spans_periodically(const VoxelGrid& cell) {
  std::array<bool, 3> spans = {false, false, false};
  const int n[3] = {cell.nx, cell.ny, cell.nz};
  std::vector<std::array<int, 3>> position(cell.size());
  std::vector<char> seen(cell.size(), 0);
  std::vector<std::size_t> queue;
  for (std::size_t start = 0; start < cell.size() && queue.empty(); ++start)
    if (cell.ids[start] != 0) {
      queue.push_back(start), seen[start] = 1;
      position[start] = {static_cast<int>(start % n[0]), static_cast<int>((start / n[0]) % n[1]),
                         static_cast<int>(start / (std::size_t(n[0]) * n[1]))};
    }
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::array<int, 3> p = position[queue[head]];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::array<int, 3> q = {p[0] + dx, p[1] + dy, p[2] + dz};
          const std::size_t v =
              cell.index(((q[0] % n[0]) + n[0]) % n[0], ((q[1] % n[1]) + n[1]) % n[1], ((q[2] % n[2]) + n[2]) % n[2]);
          if (cell.ids[v] == 0) continue;
          if (!seen[v]) {
            seen[v] = 1, position[v] = q, queue.push_back(v);
          } else {
            for (int a = 0; a < 3; ++a) spans[a] = spans[a] || position[v][a] != q[a];
          }
        }
  }
  return spans;
}

// The lattice node at corner a (bits x, y, z as in voxel_corners) of voxel (i, j, k), wrapped periodically.
std::size_t corner_node(const VoxelGrid& cell, int i, int j, int k, int a) {
  return ((i + (a >> 2 & 1)) % cell.nx) +
         std::size_t(cell.nx) * (((j + (a >> 1 & 1)) % cell.ny) + std::size_t(cell.ny) * ((k + (a & 1)) % cell.nz));
}

}  // namespace

PeriodicFiniteStrainCell::PeriodicFiniteStrainCell(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                                   int axis)
    : cell_(cell), palette_(palette), axis_(axis) {
  if (axis < 0 || axis > 2) throw InputError("finite-strain cell: axis must be 0, 1 or 2");
  lateral_[0] = (axis + 1) % 3, lateral_[1] = (axis + 2) % 3;
  if (cell.nx < 2 || cell.ny < 2 || cell.nz < 2)
    throw InputError("finite-strain cell: needs at least 2 voxels along every axis (a 3D cell)");
  const std::size_t nodes = std::size_t(cell.nx) * cell.ny * cell.nz;
  std::vector<char> used(nodes, 0);
  double mu_max = 0;
  for (int k = 0; k < cell.nz; ++k)
    for (int j = 0; j < cell.ny; ++j)
      for (int i = 0; i < cell.nx; ++i) {
        const int id = cell.at(i, j, k);
        if (id == 0) continue;
        if (id < 0 || id >= static_cast<int>(palette.size()) || !palette[id])
          throw InputError("finite-strain cell: voxel id " + std::to_string(id) + " has no material");
        mu_max = std::max(mu_max, palette[id]->shear_modulus());
        solid_.push_back(cell.index(i, j, k));
        for (int a = 0; a < 8; ++a) used[corner_node(cell, i, j, k, a)] = 1;
      }
  if (solid_.empty()) throw InputError("finite-strain cell: the cell is all void");
  if (const int pieces = count_periodic_pieces(cell); pieces > 1)
    throw InputError("finite-strain cell: the solid is " + std::to_string(pieces) +
                     " pieces; a floating piece has no stiffness without ersatz void");
  const std::array<bool, 3> spans = spans_periodically(cell);
  for (int a = 0; a < 3; ++a)
    if (!spans[a])
      throw InputError(std::string("finite-strain cell: the solid does not reach its periodic copy along ") + "xyz"[a] +
                       ", so the cell carries no stress there");
  std::vector<int> node_unknown(nodes, -1);
  bool held = false;
  for (std::size_t n = 0; n < nodes; ++n) {
    if (!used[n]) continue;
    if (!held) {
      held = true;  // the first node holds the translation
      continue;
    }
    node_unknown[n] = 3 * free_nodes_++;
  }
  element_unknowns_.resize(solid_.size());
  for (std::size_t e = 0; e < solid_.size(); ++e) {
    const std::size_t v = solid_[e];
    const int i = static_cast<int>(v % cell.nx), j = static_cast<int>((v / cell.nx) % cell.ny),
              k = static_cast<int>(v / (std::size_t(cell.nx) * cell.ny));
    for (int a = 0; a < 8; ++a) element_unknowns_[e][a] = node_unknown[corner_node(cell, i, j, k, a)];
  }
  const double h = cell.voxel_size;
  corners_ = voxel_corners(h);
  geometry_ = hex8::element_geometry(corners_, hex8::gauss_rule(2));
  volume_ = h * h * h * double(nodes);
  energy_scale_ = std::max(mu_max, 1e-300) * h * h * h;
}

VecX PeriodicFiniteStrainCell::rest() const {
  VecX z = VecX::Zero(unknowns());
  z[unknowns() - 2] = z[unknowns() - 1] = 1;
  return z;
}

Vec3 PeriodicFiniteStrainCell::stretches(double s, const VecX& z) const {
  Vec3 S;
  S[axis_] = s;
  S[lateral_[0]] = z[unknowns() - 2];
  S[lateral_[1]] = z[unknowns() - 1];
  return S;
}

double PeriodicFiniteStrainCell::energy(double s, const VecX& z, VecX* gradient, SpMat* hessian, double* dE_ds) const {
  const int n = unknowns(), l0 = n - 2, l1 = n - 1;
  const Vec3 S = stretches(s, z);
  const double h = cell_.voxel_size;
  const int nx = cell_.nx, ny = cell_.ny;
  if (gradient) gradient->setZero(n);
  if (dE_ds) *dE_ds = 0;
  std::vector<Eigen::Triplet<double>> triplets;
  if (hessian) triplets.reserve(solid_.size() * (24 * 24 + 4 * 24 + 4));
  double total = 0;
  Vec24 g;
  Mat24 H;
  QuadratureMaterials mat;
  mat.at_point.resize(1);
  for (std::size_t el = 0; el < solid_.size(); ++el) {
    const std::size_t v = solid_[el];
    const int i = static_cast<int>(v % nx), j = static_cast<int>((v / nx) % ny),
              k = static_cast<int>(v / (std::size_t(nx) * ny));
    const std::array<int, 8>& unknown = element_unknowns_[el];
    hex8::NodeMatrix X, x;
    for (int a = 0; a < 8; ++a) {
      X.row(a) = corners_.row(a) + h * Vec3(i, j, k).transpose();
      for (int c = 0; c < 3; ++c) x(a, c) = S[c] * X(a, c) + (unknown[a] >= 0 ? z[unknown[a] + c] : 0.0);
    }
    mat.at_point[0] = palette_[cell_.ids[v]];
    const double e = hex_evaluate(geometry_, mat, x, (gradient || dE_ds) ? &g : nullptr, hessian ? &H : nullptr);
    if (!std::isfinite(e)) return kInfiniteEnergy;
    total += e;
    // dx/d(lateral stretch c) is X's c column on component c.
    Vec24 t0 = Vec24::Zero(), t1 = Vec24::Zero();
    for (int a = 0; a < 8; ++a)
      t0[3 * a + lateral_[0]] = X(a, lateral_[0]), t1[3 * a + lateral_[1]] = X(a, lateral_[1]);
    if (gradient) {
      for (int a = 0; a < 8; ++a)
        if (unknown[a] >= 0)
          for (int c = 0; c < 3; ++c) (*gradient)[unknown[a] + c] += g[3 * a + c];
      (*gradient)[l0] += t0.dot(g);
      (*gradient)[l1] += t1.dot(g);
    }
    if (dE_ds)
      for (int a = 0; a < 8; ++a) *dE_ds += g[3 * a + axis_] * X(a, axis_);
    if (hessian) {
      const Vec24 Ht0 = H * t0, Ht1 = H * t1;
      for (int a = 0; a < 8; ++a) {
        if (unknown[a] < 0) continue;
        for (int c = 0; c < 3; ++c) {
          const int r = unknown[a] + c;
          for (int b = 0; b < 8; ++b)
            if (unknown[b] >= 0)
              for (int d = 0; d < 3; ++d) triplets.emplace_back(r, unknown[b] + d, H(3 * a + c, 3 * b + d));
          triplets.emplace_back(r, l0, Ht0[3 * a + c]);
          triplets.emplace_back(l0, r, Ht0[3 * a + c]);
          triplets.emplace_back(r, l1, Ht1[3 * a + c]);
          triplets.emplace_back(l1, r, Ht1[3 * a + c]);
        }
      }
      const double c01 = t0.dot(Ht1);
      triplets.emplace_back(l0, l0, t0.dot(Ht0));
      triplets.emplace_back(l1, l1, t1.dot(Ht1));
      triplets.emplace_back(l0, l1, c01);
      triplets.emplace_back(l1, l0, c01);
    }
  }
  if (hessian) {
    hessian->resize(n, n);
    hessian->setFromTriplets(triplets.begin(), triplets.end());
  }
  return total;
}

namespace {

// Factorizes H, or H + shift I with the smallest shift of 1e-12 ... 1e2
// times H's largest diagonal entry that is positive definite; returns the
// shift used (0 for none). Two cases need one. Voxels that share only a
// node or an edge hinge about it at no energy: without ersatz void H is
// singular along that mechanism, but the energy does not depend on it
// either, and a tiny shift only damps it. A structure that buckles
// (slender beams in compression) has an indefinite H past the bifurcation:
// a larger shift gives a descent direction (Levenberg-Marquardt), and
// Newton continues into the buckled state, where H is positive again.
double factorize_shifted(CholmodSolver& solver, const SpMat& H, double s) {
  if (solver.factorize(H)) return 0;
  double scale = 0;
  for (int k = 0; k < H.outerSize(); ++k) scale = std::max(scale, H.coeff(k, k));
  for (int exponent = -12; exponent <= 2; exponent += 2)
    if (const double shift = std::pow(10.0, exponent) * scale; solver.factorize(H, shift)) return shift;
  throw NumericalError("finite-strain cell: at axial strain " + std::to_string(s - 1) +
                       " the stiffness is not positive definite even shifted by 100 times its diagonal");
}

// Newton on z at axial stretch s from the start z; returns the iterations
// and counts the shifted factorizations in `shifted`.
int relax(const PeriodicFiniteStrainCell& cell, double s, VecX& z, CholmodSolver& solver, bool& analyzed,
          const FiniteStrainOptions& options, double tolerance, int& shifted) {
  VecX g;
  SpMat H;
  double E = cell.energy(s, z, &g, &H);
  if (!std::isfinite(E)) throw NumericalError("finite-strain cell: the start of an increment is inverted");
  for (int it = 1; it <= options.max_newton_iterations; ++it) {
    if (!analyzed) solver.analyze(H), analyzed = true;
    if (factorize_shifted(solver, H, s) > 0) ++shifted;
    const VecX dz = -solver.solve(g);
    const double decrement = -g.dot(dz);
    if (decrement <= tolerance) {
      z += dz;  // the last full step is below round-off of the energy, not of z
      return it;
    }
    // Backtracking on the energy; below its round-off, on the directional derivative.
    double alpha = 1;
    for (int tries = 0;; ++tries) {
      if (tries == 40) throw NumericalError("finite-strain cell: line search failed");
      const VecX trial = z + alpha * dz;
      const double E_trial = cell.energy(s, trial, nullptr, nullptr);
      const double round_off = 1e-12 * std::abs(E) + 1e-300;
      bool descent = E_trial <= E - 1e-4 * alpha * decrement;
      if (!descent && std::isfinite(E_trial) && std::abs(E_trial - E) <= round_off) {
        VecX g_trial;  // energies within round-off: the directional derivative decides
        cell.energy(s, trial, &g_trial, nullptr);
        descent = g_trial.dot(dz) <= 0;
      }
      if (descent) {
        z = trial;
        break;
      }
      alpha *= 0.5;
    }
    E = cell.energy(s, z, &g, &H);
  }
  throw NumericalError("finite-strain cell: Newton did not converge in " +
                       std::to_string(options.max_newton_iterations) + " iterations at axial stretch " +
                       std::to_string(s));
}

}  // namespace

std::vector<UniaxialStrainPoint> uniaxial_finite_strain(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                                        int axis, const std::vector<double>& strains,
                                                        const FiniteStrainOptions& options) {
  for (double e : strains)
    if (!(std::isfinite(e) && e > -1 && e != 0))
      throw InputError("finite-strain cell: strains must be finite, nonzero and > -1");
  if (!(options.max_step > 0) || options.max_newton_iterations < 1 || !(options.newton_tolerance > 0))
    throw InputError("finite-strain cell: need max_step > 0, max_newton_iterations >= 1, newton_tolerance > 0");
  const PeriodicFiniteStrainCell model(cell, palette, axis);
  const double tolerance = options.newton_tolerance * model.energy_scale() * double(cell.count_solid());
  CholmodSolver solver;
  bool analyzed = false;
  std::vector<UniaxialStrainPoint> points(strains.size());
  // Each sign from rest, in increasing |strain|: every point continues from
  // the one before, and the first increment's start (rest) is exact.
  for (const double sign : {1.0, -1.0}) {
    std::vector<std::size_t> order;
    for (std::size_t p = 0; p < strains.size(); ++p)
      if (strains[p] * sign > 0) order.push_back(p);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return std::abs(strains[a]) < std::abs(strains[b]); });
    VecX z = model.rest(), z_previous = z;
    double reached = 0, step_before = 0;
    int iterations = 0, shifted = 0;
    for (const std::size_t p : order) {
      const double target = strains[p];
      const int increments =
          std::max(1, static_cast<int>(std::ceil(std::abs(target - reached) / options.max_step - 1e-9)));
      const double step = (target - reached) / increments;
      for (int inc = 0; inc < increments; ++inc) {
        // Start from the secant extrapolation of the last two states.
        VecX start = z;
        if (step_before != 0) start += (step / step_before) * (z - z_previous);
        z_previous = z;
        z = start;
        if (!std::isfinite(model.energy(1 + reached + step, z, nullptr, nullptr))) z = z_previous;
        iterations += relax(model, 1 + reached + step, z, solver, analyzed, options, tolerance, shifted);
        reached += step;
        step_before = step;
      }
      UniaxialStrainPoint& out = points[p];
      out.strain = target;
      out.stretch = model.stretches(1 + target, z);
      const int lat[2] = {(axis + 1) % 3, (axis + 2) % 3};
      for (int q = 0; q < 2; ++q) out.nu[q] = -(out.stretch[lat[q]] - 1) / target;
      double dE_ds = 0;
      model.energy(1 + target, z, nullptr, nullptr, &dE_ds);
      out.nominal_stress = dE_ds / model.volume();  // axial force times length, over length times section
      out.newton_iterations = iterations;
      out.shifted_factorizations = shifted;
    }
  }
  return points;
}

}  // namespace msfab
