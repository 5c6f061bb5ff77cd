// Hexahedron kinematics: shape functions, quadrature, deformation gradient.
#include <gtest/gtest.h>

#include <random>

#include "fem/hex8.hpp"

using namespace msfab;

TEST(Hex8, ShapeFunctionsAreNodalAndPartitionUnity) {
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) EXPECT_DOUBLE_EQ(hex8::shape(i, hex8::natural_node(j)), i == j ? 1.0 : 0.0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 20; ++t) {
    const Vec3 chi(u(rng), u(rng), u(rng));
    EXPECT_NEAR(hex8::shapes(chi).sum(), 1.0, 1e-14);
    EXPECT_NEAR(hex8::shape_gradients(chi).colwise().sum().norm(), 0.0, 1e-14);
  }
}

TEST(Hex8, NodeOrderMatchesThesisTable) {
  // Table 2.1: node 2 (1-based) is (-1,-1,1), node 5 is (1,-1,-1).
  EXPECT_EQ(hex8::natural_node(1), Vec3(-1, -1, 1));
  EXPECT_EQ(hex8::natural_node(4), Vec3(1, -1, -1));
  EXPECT_EQ(hex8::natural_node(7), Vec3(1, 1, 1));
}

TEST(Hex8, ShapeGradientsMatchFiniteDifferences) {
  const Vec3 chi(0.3, -0.7, 0.2);
  const double h = 1e-6;
  const auto D = hex8::shape_gradients(chi);
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) {
      Vec3 p = chi, m = chi;
      p[a] += h;
      m[a] -= h;
      EXPECT_NEAR(D(i, a), (hex8::shape(i, p) - hex8::shape(i, m)) / (2 * h), 1e-9);
    }
}

TEST(Hex8, GaussRulesIntegratePolynomialsExactly) {
  // n points per axis integrate degree 2n-1 exactly; x^2 y^2 z^2 over [-1,1]^3 = (2/3)^3.
  for (int n = 2; n <= 4; ++n) {
    const auto rule = hex8::gauss_rule(n);
    double vol = 0, m = 0;
    for (int q = 0; q < rule.size(); ++q) {
      vol += rule.weights[q];
      const Vec3& p = rule.points[q];
      m += rule.weights[q] * p.x() * p.x() * p.y() * p.y() * p.z() * p.z();
    }
    EXPECT_NEAR(vol, 8.0, 1e-13);
    EXPECT_NEAR(m, 8.0 / 27.0, 1e-13);
  }
  EXPECT_EQ(hex8::gauss_rule(4).size(), 64);
}

TEST(Hex8, DeformationGradientOfAffineMapIsExactOnDistortedHex) {
  // Arbitrary non-cubic hex; positions x = A X + b must give F = A everywhere.
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = hex8::natural_node(i).transpose();
  X(7, 0) += 0.3;
  X(3, 1) -= 0.2;
  X(5, 2) += 0.25;
  X(0, 0) -= 0.1;
  Mat3 A;
  A << 1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2;
  const Vec3 b(0.5, -1, 2);
  hex8::NodeMatrix x = (X * A.transpose()).rowwise() + b.transpose();
  const auto geo = hex8::element_geometry(X, hex8::gauss_rule(2));
  double vol = 0;
  for (int q = 0; q < geo.size(); ++q) {
    EXPECT_NEAR((hex8::deformation_gradient(x, geo.dNdX[q]) - A).norm(), 0.0, 1e-13);
    vol += geo.weight[q];
  }
  EXPECT_GT(vol, 0);
}

TEST(Hex8, InvertedReferenceElementIsRejected) {
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = hex8::natural_node(i).transpose();
  X.col(0) *= -1;  // mirror: negative Jacobian
  EXPECT_ANY_THROW(hex8::element_geometry(X, hex8::gauss_rule(2)));
}
