#include "verify/comparison.hpp"

#include <cmath>
#include <stdexcept>

namespace msfab {

DisplacementComparison compare_displacements(const CellRefinement& refinement, const VecX& u_homogenized,
                                             const VecX& u_full, const std::vector<char>& fine_node_material,
                                             const std::vector<char>& coarse_active) {
  const CellGrid& coarse = refinement.coarse();
  const CellGrid& fine = refinement.fine();
  if (u_homogenized.size() != coarse.unknowns() || u_full.size() != fine.unknowns() ||
      std::int64_t(fine_node_material.size()) != fine.nodes() || std::int64_t(coarse_active.size()) != coarse.nodes())
    throw std::invalid_argument("compare_displacements: sizes do not match the grids");
  DisplacementComparison out;
  out.sampled = MatX::Zero(coarse.nodes(), 3);
  out.kind.assign(std::size_t(coarse.nodes()), SampleKind::skipped);
  double sum_hom = 0, sum_full = 0, sum_diff = 0;
  for (std::int64_t n = 0; n < coarse.nodes(); ++n) {
    if (!coarse_active[std::size_t(n)]) continue;
    const std::vector<std::int64_t> near =
        refinement.nearest_material(n, fine_node_material, refinement.resolution() / 2);
    if (near.empty()) continue;
    Vec3 u = Vec3::Zero();
    for (std::int64_t x : near) u += u_full.segment<3>(x * 3);
    u /= double(near.size());
    const bool coincident = near.size() == 1 && near[0] == refinement.fine_node_of(n);
    out.kind[std::size_t(n)] = coincident ? SampleKind::coincident : SampleKind::nearest;
    out.sampled.row(n) = u.transpose();
    const Vec3 uh = u_homogenized.segment<3>(n * 3);
    sum_hom += uh.norm();
    sum_full += u.norm();
    sum_diff += (u - uh).norm();
    ++out.compared;
    if (!coincident) ++out.nearest;
  }
  if (out.compared > 0) {
    out.mean_homogenized = sum_hom / double(out.compared);
    out.mean_full = sum_full / double(out.compared);
    out.mean_difference = sum_diff / double(out.compared);
  }
  out.relative = out.mean_homogenized > 0 ? out.mean_difference / out.mean_homogenized : 0.0;
  return out;
}

double relative_difference(double homogenized, double full) {
  if (homogenized == 0 && full == 0) return 0.0;
  return std::abs(full - homogenized) / std::abs(homogenized);
}

}  // namespace msfab
