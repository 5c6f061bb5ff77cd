#pragma once
// Basic numeric types shared by every module.
#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace msfab {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
// A 3x3 tensor flattened column-major: index a = i + 3*j for entry (i, j).
// dP/dF is stored as Mat9 with H(a, b) = dP_a / dF_b in that flattening.
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec24 = Eigen::Matrix<double, 24, 1>;
using Mat24 = Eigen::Matrix<double, 24, 24>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;
// Sparse matrices are compressed column storage with 32-bit indices so they
// can be handed to CHOLMOD without a copy.
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

inline Eigen::Map<const Vec9> flat(const Mat3& m) { return Eigen::Map<const Vec9>(m.data()); }
inline Mat3 unflat(const Vec9& v) { return Eigen::Map<const Mat3>(v.data()); }

// Index i of a periodic axis of n cells, for any integer i (also negative).
inline int wrap_periodic(int i, int n) { return ((i % n) + n) % n; }

}  // namespace msfab
