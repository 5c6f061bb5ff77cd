#include "ddfem/windowed_stiffness.hpp"

#include <Eigen/Eigenvalues>
#include <map>

#include "core/errors.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/voigt.hpp"

namespace msfab {
namespace {

// Mirror an index into [0, n): ... 1 0 | 0 1 ... n-1 | n-1 n-2 ...
int mirrored(int i, int n) {
  const int period = 2 * n;
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - 1 - i;
}

// The cell's mean strain conditions A: below this reciprocal condition
// number the cell deforms in some case almost only through its margin.
constexpr double kMinStrainConditioning = 1e-8;

}  // namespace

std::vector<int> cell_window(const VoxelGrid& fine, int i0, int j0, int k0, int n, int margin) {
  const int w = n + 2 * margin;
  std::vector<int> ids;
  ids.reserve(size_t(w) * w * w);
  for (int a = 0; a < w; ++a)
    for (int b = 0; b < w; ++b)
      for (int c = 0; c < w; ++c)
        ids.push_back(fine.at(mirrored(i0 - margin + a, fine.nx), mirrored(j0 - margin + b, fine.ny),
                              mirrored(k0 - margin + c, fine.nz)));
  return ids;
}

Mat6 windowed_stiffness(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette, int i0, int j0, int k0, int n,
                        int margin) {
  if (n < 1 || margin < 0) throw std::invalid_argument("windowed_stiffness: n >= 1 and margin >= 0 expected");
  const int w = n + 2 * margin;
  const double h = fine.voxel_size;
  VoxelGrid cell(w, w, w, h, 0);
  const std::vector<int> window = cell_window(fine, i0, j0, k0, n, margin);
  for (int a = 0; a < w; ++a)
    for (int b = 0; b < w; ++b)
      for (int c = 0; c < w; ++c) cell.at(a, b, c) = window[(size_t(a) * w + b) * w + c];
  for (int a = margin; a < margin + n; ++a)
    for (int b = margin; b < margin + n; ++b)
      for (int c = margin; c < margin + n; ++c)
        if (cell.at(a, b, c) == 0) throw InputError("windowed stiffness: the cell has a void voxel");
  // Void in the margin is a free surface of the body, which a periodic
  // window turns into a crack across it: loaded across, the void takes the
  // strain, the cell's mean strain nearly vanishes and A = E^-T W E^-1 is
  // ill-determined (measured: replacing the skeleton's fits near its outline
  // by such stiffnesses tripled its level-1 error). Such a cell has no
  // windowed stiffness.
  for (int id : cell.ids)
    if (id == 0) throw NumericalError("windowed stiffness: the window holds void (a free surface of the body)");
  HomogenizationOptions options;
  options.threads = 1;  // called per cell; the caller owns the parallelism
  const HomogenizationResult r = homogenize(cell, palette, options);
  std::map<int, Mat24> K;
  Mat6 W = Mat6::Zero(), E = Mat6::Zero();
  for (int a = margin; a < margin + n; ++a)
    for (int b = margin; b < margin + n; ++b)
      for (int c = margin; c < margin + n; ++c) {
        const int id = cell.at(a, b, c);
        const Eigen::Matrix<double, 24, 6> U = total_element_displacements(r, w, w, w, h, cell.index(a, b, c));
        if (!K.count(id)) K[id] = voxel_stiffness(palette[id], h);
        W += U.transpose() * K[id] * U;
        // The voxel's mean displacement gradient: sum_q u_q (x) s_q / (4 h),
        // s_q the corner's signs (the integral of grad N_q over the cube).
        for (int m = 0; m < 6; ++m) {
          Mat3 G = Mat3::Zero();
          for (int q = 0; q < 8; ++q)
            G += U.col(m).segment<3>(3 * q) *
                 Vec3(2.0 * (q >> 2 & 1) - 1, 2.0 * (q >> 1 & 1) - 1, 2.0 * (q & 1) - 1).transpose() / (4 * h);
          E.col(m) += strain_to_voigt(G);
        }
      }
  const double voxels = double(n) * n * n;
  E /= voxels;
  W /= voxels * h * h * h;
  const Eigen::JacobiSVD<Mat6> svd(E);
  if (!(svd.singularValues()(5) > kMinStrainConditioning * svd.singularValues()(0)))
    throw NumericalError("windowed stiffness: the cell's mean strains do not determine its stiffness");
  const Mat6 Einv = E.inverse();
  Mat6 A = Einv.transpose() * W * Einv;
  A = 0.5 * (A + A.transpose());
  if (!A.allFinite() || !(Eigen::SelfAdjointEigenSolver<Mat6>(A).eigenvalues()(0) > 0))
    throw NumericalError("windowed stiffness: the cell's apparent stiffness is not positive definite");
  return A;
}

}  // namespace msfab
