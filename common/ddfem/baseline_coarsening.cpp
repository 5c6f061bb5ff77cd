#include "ddfem/baseline_coarsening.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "core/errors.hpp"
#include "ddfem/galerkin_quadrature.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/green_anisotropic.hpp"
#include "material/material_sum.hpp"
#include "material/neo_hookean.hpp"
#include "material/voigt.hpp"

namespace msfab {
namespace {

const MaterialPtr& palette_material_checked(const std::vector<MaterialPtr>& palette, int id) {
  if (id <= 0 || id >= static_cast<int>(palette.size()) || !palette[id]) {
    std::ostringstream msg;
    msg << "coarsening baseline: fine material id " << id << " is not in the palette (ids 1.."
        << static_cast<int>(palette.size()) - 1 << ")";
    throw InputError(msg.str());
  }
  return palette[id];
}

}  // namespace

std::vector<int> block_level1(const ChildIds& child) { return std::vector<int>(child.begin(), child.end()); }

std::vector<int> block_level2(const ChildIds& child, const std::vector<ChildIds>& level1) {
  std::vector<int> ids(64, 0);
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      for (int c = 0; c < 4; ++c) {
        const int outer = 4 * (a >> 1) + 2 * (b >> 1) + (c >> 1);
        const int inner = 4 * (a & 1) + 2 * (b & 1) + (c & 1);
        const int comb = child[outer];
        if (comb < 0 || comb > static_cast<int>(level1.size()))
          throw InputError("coarsening baseline: level-2 child id " + std::to_string(comb) +
                           " is not a level-1 combination");
        ids[(a * 4 + b) * 4 + c] = comb == 0 ? 0 : level1[comb - 1][inner];
      }
  return ids;
}

bool solid_mixed_block(const std::vector<int>& ids) {
  return std::find(ids.begin(), ids.end(), 0) == ids.end() &&
         std::any_of(ids.begin(), ids.end(), [&](int id) { return id != ids[0]; });
}

QuadratureMaterials naive_block(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n) {
  QuadratureMaterials m;
  m.at_point.resize(ids.size());
  auto coords = [n](int p, int out[3]) {
    out[0] = p / (n * n);
    out[1] = (p / n) % n;
    out[2] = p % n;
  };
  for (int p = 0; p < static_cast<int>(ids.size()); ++p) {
    if (ids[p] != 0) {
      m.at_point[p] = palette_material_checked(palette, ids[p]);
      continue;
    }
    int cp[3];
    coords(p, cp);
    int best = -1, best_dist = 0;
    for (int s = 0; s < static_cast<int>(ids.size()); ++s) {
      if (ids[s] == 0) continue;
      int cs[3];
      coords(s, cs);
      const int dist = std::abs(cs[0] - cp[0]) + std::abs(cs[1] - cp[1]) + std::abs(cs[2] - cp[2]);
      const bool better = best < 0 || dist < best_dist ||
                          (dist == best_dist && palette_material_checked(palette, ids[s])->shear_modulus() <
                                                    palette_material_checked(palette, ids[best])->shear_modulus());
      if (better) {
        best = s;
        best_dist = dist;
      }
    }
    if (best < 0) throw InputError("coarsening baseline: every voxel of the block is void");
    m.at_point[p] = palette_material_checked(palette, ids[best]);
  }
  return m;
}

namespace {

QuadratureMaterials averaged_block(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids) {
  double mu = 0, lambda = 0;
  average_lame(palette, ids, &mu, &lambda);
  if (!(mu > 0)) throw InputError("coarsening baseline: averaged shear modulus is not positive");
  // Engineering constants of the averaged Lame pair.
  const double E = mu * (3 * lambda + 2 * mu) / (lambda + mu);
  const double nu = lambda / (2 * (lambda + mu));
  return QuadratureMaterials{{std::make_shared<NeoHookean>(E, nu)}};
}

// Each voxel's material (none for void) at its 8 points of the composite
// rule of the n x n x n block; reduced: at the points of the rule that
// integrates each material's stiffness monomials as the composite rule does
// (ddfem/galerkin_quadrature.hpp).
QuadratureMaterials galerkin_block(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n,
                                   bool reduced) {
  if (std::all_of(ids.begin(), ids.end(), [](int id) { return id == 0; }))
    throw InputError("coarsening baseline: every voxel of the block is void");
  QuadratureMaterials m;
  m.at_point.reserve(8 * ids.size());
  for (int id : ids)
    m.at_point.insert(m.at_point.end(), 8, id == 0 ? MaterialPtr() : palette_material_checked(palette, id));
  if (!reduced) return m;
  std::vector<int> group;
  group.reserve(m.at_point.size());
  for (int id : ids) group.insert(group.end(), 8, id == 0 ? -1 : id);
  const ReducedRule r = reduced_stiffness_rule(hex8::composite_gauss_rule(n, 2), group);
  QuadratureMaterials kept;
  kept.at_point.reserve(r.source.size());
  for (int q : r.source) kept.at_point.push_back(m.at_point[q]);
  kept.rule = std::make_shared<const hex8::QuadratureRule>(r.rule);
  return kept;
}

QuadratureMaterials homogenized_block(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n) {
  if (std::find(ids.begin(), ids.end(), 0) != ids.end()) return naive_block(palette, ids, n);
  return QuadratureMaterials{{homogenized_block_material(block_homogenized_stiffness(palette, ids, n))}};
}

}  // namespace

Mat6 block_homogenized_stiffness(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n) {
  VoxelGrid cell(n, n, n, 1.0, 0);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int c = 0; c < n; ++c) cell.at(a, b, c) = ids.at((a * n + b) * n + c);
  for (int id : ids)
    if (id != 0) palette_material_checked(palette, id);  // a clear error for an unknown id
  HomogenizationOptions options;
  options.solver = "cholmod";
  options.threads = 1;
  return to_material_voigt_order(homogenize(cell, palette, options).C);
}

MaterialPtr homogenized_block_material(const Mat6& C) {
  double mu = 0, lambda = 0;
  isotropic_projection(C, &mu, &lambda);
  // A strongly anisotropic C (a stiff direction beside soft ones) can
  // project to lambda < 0, which no Neo-Hookean part may have; lambda = 0
  // keeps the split exact (t below is then taken against that part).
  lambda = std::max(lambda, 0.0);
  const Mat6 iso = lame_C(mu, lambda);
  // The largest t with C - t iso >= 0: the smallest generalized eigenvalue.
  const double t = std::clamp(
      Eigen::GeneralizedSelfAdjointEigenSolver<Mat6>(C, iso, Eigen::EigenvaluesOnly).eigenvalues()[0], 0.0, 1.0);
  Eigen::SelfAdjointEigenSolver<Mat6> rest(C - t * iso);
  const Mat6 remainder =
      rest.eigenvectors() * rest.eigenvalues().cwiseMax(0.0).asDiagonal() * rest.eigenvectors().transpose();
  auto green = std::make_shared<GreenAnisotropic>(0.5 * (remainder + remainder.transpose()));
  if (!(t * mu > 0)) return green;
  return std::make_shared<MaterialSum>(std::vector<MaterialPtr>{NeoHookean::from_lame(t * mu, t * lambda), green});
}

void average_lame(const std::vector<MaterialPtr>& palette, const std::vector<int>& fine_ids, double* mu,
                  double* lambda) {
  double sm = 0, sl = 0;
  for (int id : fine_ids) {
    if (id == 0) continue;
    const MaterialPtr& m = palette_material_checked(palette, id);
    sm += m->shear_modulus();
    sl += m->lame_lambda();
  }
  const double n = fine_ids.empty() ? 1.0 : double(fine_ids.size());
  *mu = sm / n;
  *lambda = sl / n;
}

CoarseMaterialLookup naive_coarsening(const std::vector<MaterialPtr>& palette) {
  return [palette](const ChildIds& child) { return naive_block(palette, block_level1(child), 2); };
}

CoarseMaterialLookup averaged_coarsening(const std::vector<MaterialPtr>& palette) {
  return [palette](const ChildIds& child) { return averaged_block(palette, block_level1(child)); };
}

CoarseMaterialLookup naive_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1) {
  if (level1.level != 1) throw InputError("naive level-2 coarsening needs a level-1 grid");
  return [palette, combos = level1.combinations](const ChildIds& child) {
    return naive_block(palette, block_level2(child, combos), 4);
  };
}

CoarseMaterialLookup averaged_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1) {
  if (level1.level != 1) throw InputError("averaged level-2 coarsening needs a level-1 grid");
  return [palette, combos = level1.combinations](const ChildIds& child) {
    return averaged_block(palette, block_level2(child, combos));
  };
}

CoarseMaterialLookup galerkin_coarsening(const std::vector<MaterialPtr>& palette, bool reduced) {
  return [palette, reduced](const ChildIds& child) { return galerkin_block(palette, block_level1(child), 2, reduced); };
}

CoarseMaterialLookup galerkin_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1,
                                         bool reduced) {
  if (level1.level != 1) throw InputError("Galerkin level-2 coarsening needs a level-1 grid");
  return [palette, combos = level1.combinations, reduced](const ChildIds& child) {
    return galerkin_block(palette, block_level2(child, combos), 4, reduced);
  };
}

CoarseMaterialLookup homogenized_coarsening(const std::vector<MaterialPtr>& palette) {
  return [palette](const ChildIds& child) { return homogenized_block(palette, block_level1(child), 2); };
}

CoarseMaterialLookup homogenized_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1) {
  if (level1.level != 1) throw InputError("homogenized level-2 coarsening needs a level-1 grid");
  return [palette, combos = level1.combinations](const ChildIds& child) {
    return homogenized_block(palette, block_level2(child, combos), 4);
  };
}

}  // namespace msfab
