// Constitutive models: derivatives against finite differences, symmetry,
// invariances, the Voigt convention, and parameter validation.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "material/anisotropic_spring.hpp"
#include "material/green_anisotropic.hpp"
#include "material/linear_anisotropic.hpp"
#include "material/linear_isotropic.hpp"
#include "material/material_sum.hpp"
#include "material/neo_hookean.hpp"
#include "material/scaled_material.hpp"
#include "material/voigt.hpp"

namespace msfab {
namespace {

constexpr double kE = 1.0e6;
constexpr double kNu = 0.45;  // nearly incompressible: large lambda stresses the checks
constexpr double kSpringC = 3.0e5;

Mat3 random_matrix(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat3 m;
  for (int i = 0; i < 9; ++i) m(i) = scale * u(rng);
  return m;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

Mat3 shear_xy(double g) {
  Mat3 F = Mat3::Identity();
  F(0, 1) = g;
  return F;
}

// Deformation gradients near identity and at large deformation.
std::vector<Mat3> test_deformations() {
  std::mt19937 rng(1234);
  std::vector<Mat3> Fs;
  for (int k = 0; k < 4; ++k) Fs.push_back(Mat3::Identity() + random_matrix(rng, 0.05));
  Fs.push_back(Eigen::Vector3d(1.5, 1.0, 1.0).asDiagonal());
  Fs.push_back(Eigen::Vector3d(0.6, 1.0, 1.0).asDiagonal());
  Fs.push_back(shear_xy(0.5));
  const Mat3 R = random_rotation(rng);
  Fs.push_back(R * Eigen::Vector3d(1.4, 0.7, 0.9).asDiagonal() * R.transpose() * random_rotation(rng));
  Fs.push_back(Mat3::Identity() + random_matrix(rng, 0.3));
  return Fs;
}

Vec3 spring_direction() { return Vec3(1.0, 2.0, -0.5).normalized(); }

Mat6 orthotropic_test_C() {
  OrthotropicConstants k{};
  k.Ex = 2.0e6;
  k.Ey = 1.0e6;
  k.Ez = 0.5e6;
  k.nu_xy = 0.3;
  k.nu_yz = 0.2;
  k.nu_zx = 0.1;
  k.Gxy = 0.6e6;
  k.Gyz = 0.3e6;
  k.Gzx = 0.4e6;
  return orthotropic_C(k);
}

struct NamedMaterial {
  std::string label;
  MaterialPtr material;
};

std::vector<NamedMaterial> all_models() {
  auto nh = std::make_shared<NeoHookean>(kE, kNu);
  auto spring = std::make_shared<AnisotropicSpring>(kSpringC, spring_direction());
  return {
      {"linear_isotropic", std::make_shared<LinearIsotropic>(kE, kNu)},
      {"linear_anisotropic", std::make_shared<LinearAnisotropic>(orthotropic_test_C())},
      {"neo_hookean", nh},
      {"anisotropic_spring", spring},
      {"neo_hookean+spring", std::make_shared<MaterialSum>(std::vector<MaterialPtr>{nh, spring})},
      {"green_anisotropic", std::make_shared<GreenAnisotropic>(orthotropic_test_C())},
      {"neo_hookean+green_anisotropic", std::make_shared<MaterialSum>(std::vector<MaterialPtr>{
                                            nh, std::make_shared<GreenAnisotropic>(orthotropic_test_C())})},
  };
}

// Central differences with a step relative to the size of F.
double fd_step(const Mat3& F) { return 1e-6 * std::max(1.0, F.norm()); }

Mat3 fd_stress(const Material& m, const Mat3& F) {
  const double h = fd_step(F);
  Mat3 P;
  for (int b = 0; b < 9; ++b) {
    Mat3 Fp = F, Fm = F;
    Fp(b) += h;
    Fm(b) -= h;
    P(b) = (m.energy(Fp) - m.energy(Fm)) / (2.0 * h);
  }
  return P;
}

Mat9 fd_stress_derivative(const Material& m, const Mat3& F) {
  const double h = fd_step(F);
  Mat9 H;
  for (int b = 0; b < 9; ++b) {
    Mat3 Fp = F, Fm = F;
    Fp(b) += h;
    Fm(b) -= h;
    H.col(b) = flat((m.stress(Fp) - m.stress(Fm)) / (2.0 * h));
  }
  return H;
}

// Relative tolerance for the derivative, plus an absolute floor scaled by the
// material stiffness so that near-zero stresses are compared sensibly.
constexpr double kFdRel = 1e-6;
constexpr double kFdAbs = 1e-8 * (kE + kSpringC);

TEST(MaterialDerivatives, StressMatchesFiniteDifferenceOfEnergy) {
  for (const auto& [label, m] : all_models())
    for (const Mat3& F : test_deformations()) {
      const Mat3 P = m->stress(F);
      const Mat3 fd = fd_stress(*m, F);
      EXPECT_LE((P - fd).norm(), kFdRel * P.norm() + kFdAbs) << label << "\nF=\n"
                                                             << F << "\nP=\n"
                                                             << P << "\nfd=\n"
                                                             << fd;
    }
}

TEST(MaterialDerivatives, StressDerivativeMatchesFiniteDifferenceOfStress) {
  for (const auto& [label, m] : all_models())
    for (const Mat3& F : test_deformations()) {
      const Mat9 H = m->stress_derivative(F);
      const Mat9 fd = fd_stress_derivative(*m, F);
      EXPECT_LE((H - fd).norm(), kFdRel * H.norm() + kFdAbs) << label << "\nF=\n" << F;
    }
}

TEST(MaterialDerivatives, StressDerivativeHasMajorSymmetry) {
  for (const auto& [label, m] : all_models())
    for (const Mat3& F : test_deformations()) {
      const Mat9 H = m->stress_derivative(F);
      EXPECT_LE((H - H.transpose()).norm(), 1e-12 * H.norm()) << label;
    }
}

TEST(MaterialDerivatives, EvaluateSubsetsAgreeWithFullEvaluation) {
  const Mat3 F = shear_xy(0.3) * Eigen::Vector3d(1.2, 0.9, 1.1).asDiagonal();
  for (const auto& [label, m] : all_models()) {
    double psi = 0;
    Mat3 P;
    Mat9 H;
    m->evaluate(F, &psi, &P, &H);
    EXPECT_EQ(psi, m->energy(F)) << label;
    EXPECT_EQ(P, m->stress(F)) << label;
    EXPECT_EQ(H, m->stress_derivative(F)) << label;
  }
}

// ---------------------------------------------------------------- Neo-Hookean

TEST(MaterialNeoHookean, RestStateHasZeroEnergyAndStress) {
  const NeoHookean nh(kE, kNu);
  EXPECT_EQ(nh.energy(Mat3::Identity()), 0.0);
  EXPECT_LE(nh.stress(Mat3::Identity()).norm(), 1e-12 * kE);
}

TEST(MaterialNeoHookean, RotationInvariance) {
  const NeoHookean nh(kE, kNu);
  std::mt19937 rng(7);
  for (int k = 0; k < 20; ++k) {
    const Mat3 R = random_rotation(rng);
    const Mat3 F = Mat3::Identity() + random_matrix(rng, 0.3);
    const double psi = nh.energy(F);
    EXPECT_NEAR(nh.energy(R * F), psi, 1e-12 * kE + 1e-12 * std::abs(psi));
    EXPECT_LE(nh.energy(R), 1e-9 * kE);
    EXPECT_LE(nh.stress(R).norm(), 1e-9 * kE);
    // Objectivity of the first Piola-Kirchhoff stress: P(R F) = R P(F).
    EXPECT_LE((nh.stress(R * F) - R * nh.stress(F)).norm(), 1e-9 * kE);
  }
}

TEST(MaterialNeoHookean, InvertedStatesGiveInfiniteEnergyAndFiniteStress) {
  const NeoHookean nh(kE, kNu);
  Mat3 singular = Mat3::Identity();
  singular.col(2).setZero();
  const std::vector<Mat3> inverted = {
      Eigen::Vector3d(-1.0, 1.0, 1.0).asDiagonal(),
      Eigen::Vector3d(0.5, -0.2, 1.3).asDiagonal(),
      -Mat3::Identity(),
      singular,
      Mat3::Zero(),
  };
  for (const Mat3& F : inverted) {
    double psi = 0;
    Mat3 P;
    Mat9 H;
    nh.evaluate(F, &psi, &P, &H);
    EXPECT_TRUE(std::isinf(psi) && psi > 0) << F;
    EXPECT_TRUE(P.allFinite()) << F;
    EXPECT_TRUE(H.allFinite()) << F;
  }
  // Energy grows without bound as J -> 0+ so line searches are pushed back.
  EXPECT_GT(nh.energy(Eigen::Vector3d(1e-8, 1.0, 1.0).asDiagonal()), 100.0 * kE);
}

// Lateral stretch b of F = diag(a, b, b) that makes the lateral stress zero.
double uniaxial_lateral_stretch(const NeoHookean& nh, double a) {
  double b = 1.0;
  for (int it = 0; it < 50; ++it) {
    const Mat3 F = Eigen::Vector3d(a, b, b).asDiagonal();
    double residual = 0;
    Mat3 P;
    Mat9 H;
    nh.evaluate(F, nullptr, &P, &H);
    residual = P(1, 1);
    // Both lateral entries move with b: dP22/db = dP22/dF22 + dP22/dF33.
    const double slope = H(4, 4) + H(4, 8);
    const double step = residual / slope;
    b -= step;
    if (std::abs(step) < 1e-15 * b) break;
  }
  return b;
}

TEST(MaterialNeoHookean, UniaxialStretchMatchesAnalyticStress) {
  const NeoHookean nh(kE, kNu);
  const double mu = nh.shear_modulus(), lambda = nh.lame_lambda();
  for (double a : {0.7, 1.1, 1.5}) {
    const double b = uniaxial_lateral_stretch(nh, a);
    const Mat3 P = nh.stress(Eigen::Vector3d(a, b, b).asDiagonal());
    const double J = a * b * b;
    EXPECT_LE(std::abs(P(1, 1)), 1e-9 * kE);
    EXPECT_LE(std::abs(P(2, 2)), 1e-9 * kE);
    EXPECT_NEAR(P(0, 0), mu * (a - 1.0 / a) + lambda * std::log(J) / a, 1e-9 * kE);
    // Lateral contraction under tension, expansion under compression.
    EXPECT_EQ(b<1.0, a> 1.0) << "a=" << a << " b=" << b;
    // The lateral balance itself, written out: mu (b - 1/b) + lambda log J / b = 0.
    EXPECT_NEAR(mu * (b - 1.0 / b) + lambda * std::log(J) / b, 0.0, 1e-9 * kE);
  }
}

TEST(MaterialNeoHookean, SmallStrainPoissonRatio) {
  for (double nu : {-0.3, 0.0, 0.25, 0.45}) {
    const NeoHookean nh(kE, nu);
    const double strain = 1e-5;
    const double b = uniaxial_lateral_stretch(nh, 1.0 + strain);
    EXPECT_NEAR((b - 1.0) / strain, -nu, 1e-3) << "nu=" << nu;
  }
}

TEST(MaterialNeoHookean, SmallStrainAgreesWithLinearIsotropic) {
  const NeoHookean nh(kE, kNu);
  const LinearIsotropic lin(kE, kNu);
  // Same tangent at the rest state.
  const Mat9 H_nh = nh.stress_derivative(Mat3::Identity());
  const Mat9 H_lin = lin.stress_derivative(Mat3::Identity());
  EXPECT_LE((H_nh - H_lin).norm(), 1e-12 * H_lin.norm());

  const double stiffness = nh.shear_modulus() + nh.lame_lambda();
  std::mt19937 rng(99);
  for (int k = 0; k < 5; ++k) {
    const Mat3 G = random_matrix(rng, 1.0);
    const double g = G.norm();
    auto stress_gap = [&](double s) {
      const Mat3 F = Mat3::Identity() + s * G;
      return (nh.stress(F) - lin.stress(F)).norm();
    };
    auto energy_gap = [&](double s) {
      const Mat3 F = Mat3::Identity() + s * G;
      return std::abs(nh.energy(F) - lin.energy(F));
    };
    // Stresses differ at second order, energies at third order in the strain.
    const double p1 = stress_gap(1e-3), p2 = stress_gap(1e-4);
    EXPECT_LE(p1, 10.0 * stiffness * std::pow(1e-3 * g, 2));
    EXPECT_NEAR(p1 / p2, 100.0, 15.0);
    const double e1 = energy_gap(1e-3), e2 = energy_gap(1e-4);
    EXPECT_LE(e1, 10.0 * stiffness * std::pow(1e-3 * g, 3));
    EXPECT_NEAR(e1 / e2, 1000.0, 150.0);
  }
}

// ------------------------------------------------------------ linear + Voigt

TEST(MaterialLinear, IsotropicStiffnessMatrixReproducesLinearIsotropic) {
  for (double nu : {-0.5, 0.0, 0.3, 0.49}) {
    const LinearIsotropic iso(kE, nu);
    const LinearAnisotropic aniso(isotropic_C(kE, nu));
    EXPECT_NEAR(aniso.shear_modulus(), iso.shear_modulus(), 1e-9 * kE);
    EXPECT_NEAR(aniso.lame_lambda(), iso.lame_lambda(), 1e-9 * std::abs(iso.lame_lambda()) + 1e-9 * kE);
    std::mt19937 rng(5);
    for (int k = 0; k < 10; ++k) {
      const Mat3 F = Mat3::Identity() + random_matrix(rng, 0.01);
      double psi_i = 0, psi_a = 0;
      Mat3 P_i, P_a;
      Mat9 H_i, H_a;
      iso.evaluate(F, &psi_i, &P_i, &H_i);
      aniso.evaluate(F, &psi_a, &P_a, &H_a);
      EXPECT_NEAR(psi_a, psi_i, 1e-10 * psi_i) << "nu=" << nu;
      EXPECT_LE((P_a - P_i).norm(), 1e-10 * P_i.norm()) << "nu=" << nu;
      EXPECT_LE((H_a - H_i).norm(), 1e-10 * H_i.norm()) << "nu=" << nu;
    }
  }
}

TEST(MaterialLinear, CubicMatrixFollowsThesisFormula) {
  const double E = 2.0e6, nu = 0.3, G = 0.4e6;
  const Mat6 C = cubic_C(E, nu, G);
  const double Ehat = E / ((1 - 2 * nu) * (1 + nu));
  EXPECT_DOUBLE_EQ(C(0, 0), (1 - nu) * Ehat);
  EXPECT_DOUBLE_EQ(C(2, 2), (1 - nu) * Ehat);
  EXPECT_DOUBLE_EQ(C(0, 1), nu * Ehat);
  EXPECT_DOUBLE_EQ(C(2, 1), nu * Ehat);
  EXPECT_DOUBLE_EQ(C(3, 3), G);
  EXPECT_DOUBLE_EQ(C(5, 5), G);
  EXPECT_EQ(C(0, 3), 0.0);
  EXPECT_EQ(C(3, 4), 0.0);
}

TEST(MaterialLinear, PureShearEnergyAndStressUseEngineeringStrain) {
  const Mat6 C = orthotropic_test_C();
  const LinearAnisotropic m(C);
  const double g = 1e-3;
  // Shear in plane (i, j) must load Voigt slot 3 + s with the order xy, yz, zx.
  const int planes[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  for (int s = 0; s < 3; ++s) {
    const int i = planes[s][0], j = planes[s][1];
    Mat3 F = Mat3::Identity();
    F(i, j) = g;
    const double G = C(3 + s, 3 + s);
    const Mat3 P = m.stress(F);
    EXPECT_NEAR(m.energy(F), 0.5 * G * g * g, 1e-12 * G * g * g) << "slot " << 3 + s;
    EXPECT_NEAR(P(i, j), G * g, 1e-12 * G * g) << "slot " << 3 + s;
    EXPECT_NEAR(P(j, i), G * g, 1e-12 * G * g) << "slot " << 3 + s;
    EXPECT_NEAR(P.trace(), 0.0, 1e-9 * G * g);
  }
  // The same holds for the cubic matrix of the thesis, where C(3,3) = mu.
  const LinearAnisotropic cubic(cubic_C(kE, kNu, 0.2 * kE));
  const double psi = cubic.energy(shear_xy(g));
  EXPECT_NEAR(psi, 0.5 * 0.2 * kE * g * g, 1e-12 * kE * g * g);
  EXPECT_NEAR(cubic.stress(shear_xy(g))(0, 1), 0.2 * kE * g, 1e-12 * kE * g);
}

TEST(MaterialVoigt, ConversionsRoundTripAndAreWorkConjugate) {
  Mat3 eps;
  eps << 0.1, 0.02, 0.03,  //
      0.02, 0.2, 0.04,     //
      0.03, 0.04, 0.3;
  const Vec6 e = strain_to_voigt(eps);
  Vec6 expected;
  expected << 0.1, 0.2, 0.3, 0.04, 0.08, 0.06;
  EXPECT_LE((e - expected).norm(), 1e-15);
  EXPECT_LE((voigt_to_strain(e) - eps).norm(), 1e-15);

  std::mt19937 rng(3);
  for (int k = 0; k < 5; ++k) {
    const Mat3 a = random_matrix(rng, 1.0), b = random_matrix(rng, 1.0);
    const Mat3 sym_a = 0.5 * (a + a.transpose()), sigma = 0.5 * (b + b.transpose());
    EXPECT_LE((voigt_to_stress(stress_to_voigt(sigma)) - sigma).norm(), 1e-14);
    // sigma : eps = s . e, which is what makes Psi = 1/2 e^T C e consistent.
    EXPECT_NEAR(stress_to_voigt(sigma).dot(strain_to_voigt(sym_a)), (sigma.array() * sym_a.array()).sum(), 1e-13);
    // The 6x9 operator maps any displacement gradient to its Voigt strain.
    EXPECT_LE((voigt_strain_operator() * flat(a) - strain_to_voigt(a)).norm(), 1e-14);
  }
}

TEST(MaterialVoigt, OrthotropicConstantsGiveExpectedCompliance) {
  // Isotropic constants reproduce the isotropic matrix.
  OrthotropicConstants k{kE, kE, kE, kNu, kNu, kNu, lame_mu(kE, kNu), lame_mu(kE, kNu), lame_mu(kE, kNu)};
  EXPECT_LE((orthotropic_C(k) - isotropic_C(kE, kNu)).norm(), 1e-9 * isotropic_C(kE, kNu).norm());
  // Uniaxial stress along x: strain = (1/Ex, -nu_xy/Ex, -nu_zx/Ez * ...) read off the compliance.
  const Mat6 C = orthotropic_test_C();
  Vec6 s = Vec6::Zero();
  s(0) = 1.0;
  const Vec6 e = C.ldlt().solve(s);
  EXPECT_NEAR(e(0), 1.0 / 2.0e6, 1e-15);
  EXPECT_NEAR(e(1), -0.3 / 2.0e6, 1e-15);
  EXPECT_NEAR(e(2), -0.1 / 0.5e6, 1e-15);
  EXPECT_NEAR(1.0 / C(3, 3), 1.0 / 0.6e6, 1e-15);
}

TEST(MaterialVoigt, IsotropicProjectionOfIsotropicMatrix) {
  double mu = 0, lambda = 0;
  isotropic_projection(isotropic_C(kE, 0.3), &mu, &lambda);
  EXPECT_NEAR(mu, lame_mu(kE, 0.3), 1e-9 * kE);
  EXPECT_NEAR(lambda, lame_lambda(kE, 0.3), 1e-9 * kE);
}

// --------------------------------------------------------- anisotropic spring

TEST(MaterialAnisotropicSpring, ZeroEnergyWhenFiberLengthIsKept) {
  const AnisotropicSpring spring(kSpringC, spring_direction());
  std::mt19937 rng(11);
  for (int k = 0; k < 5; ++k) {
    const Mat3 R = random_rotation(rng);
    EXPECT_LE(spring.energy(R), 1e-20 * kSpringC);
    EXPECT_LE(spring.stress(R).norm(), 1e-12 * kSpringC);
  }
  // Stretching across the fiber leaves it unloaded.
  const Vec3 v = spring_direction();
  const Vec3 n = v.unitOrthogonal();
  const Mat3 across = Mat3::Identity() + 0.4 * n * n.transpose();
  EXPECT_LE(spring.energy(across), 1e-20 * kSpringC);
  // Stretching along it by 1.2 costs C (0.2)^2.
  const Mat3 along = Mat3::Identity() + 0.2 * v * v.transpose();
  EXPECT_NEAR(spring.energy(along), kSpringC * 0.04, 1e-12 * kSpringC);
  EXPECT_EQ(spring.shear_modulus(), 0.0);
  EXPECT_EQ(spring.lame_lambda(), 0.0);
}

TEST(MaterialAnisotropicSpring, StifferAlongFiberThanAcross) {
  auto nh = std::make_shared<NeoHookean>(kE, kNu);
  const Vec3 v = spring_direction();
  const MaterialSum sum({nh, std::make_shared<AnisotropicSpring>(kSpringC, v)});
  const Vec3 n = v.unitOrthogonal();
  for (double stretch : {0.9, 1.1, 1.3}) {
    const Mat3 along = Mat3::Identity() + (stretch - 1.0) * v * v.transpose();
    const Mat3 across = Mat3::Identity() + (stretch - 1.0) * n * n.transpose();
    // Neo-Hookean alone is isotropic, the sum is not.
    EXPECT_NEAR(nh->energy(along), nh->energy(across), 1e-9 * nh->energy(along));
    EXPECT_GT(sum.energy(along), 1.05 * sum.energy(across)) << "stretch " << stretch;
  }
  // Rest tangent: the spring adds 2C to the axial stiffness along x only.
  const MaterialSum sum_x({nh, std::make_shared<AnisotropicSpring>(kSpringC, Vec3(2.0, 0.0, 0.0))});
  const Mat9 H = sum_x.stress_derivative(Mat3::Identity());
  const Mat9 H_nh = nh->stress_derivative(Mat3::Identity());
  EXPECT_NEAR(H(0, 0) - H_nh(0, 0), 2.0 * kSpringC, 1e-9 * kE);
  EXPECT_NEAR(H(4, 4), H_nh(4, 4), 1e-9 * kE);
  EXPECT_NEAR(H(8, 8), H_nh(8, 8), 1e-9 * kE);
}

TEST(MaterialAnisotropicSpring, CollapsedFiberGivesFiniteValues) {
  const Vec3 v = spring_direction();
  const AnisotropicSpring spring(kSpringC, v);
  for (double remaining : {0.0, 1e-12, 1e-9}) {
    const Mat3 F = Mat3::Identity() - (1.0 - remaining) * v * v.transpose();
    double psi = 0;
    Mat3 P;
    Mat9 H;
    spring.evaluate(F, &psi, &P, &H);
    EXPECT_NEAR(psi, kSpringC * (1 - remaining) * (1 - remaining), 1e-9 * kSpringC);
    EXPECT_TRUE(P.allFinite());
    EXPECT_TRUE(H.allFinite());
    EXPECT_LE(P.norm(), 2.0 * kSpringC * (1.0 + 1e-12));
  }
}

// ---------------------------------------------------------------- material sum

TEST(MaterialSum, AddsEnergiesStressesAndModuli) {
  auto nh = std::make_shared<NeoHookean>(kE, kNu);
  auto lin = std::make_shared<LinearIsotropic>(2.0 * kE, 0.2);
  auto spring = std::make_shared<AnisotropicSpring>(kSpringC, spring_direction());
  const MaterialSum sum({nh, lin, spring});
  const Mat3 F = shear_xy(0.2) * Eigen::Vector3d(1.1, 0.95, 1.0).asDiagonal();
  EXPECT_NEAR(sum.energy(F), nh->energy(F) + lin->energy(F) + spring->energy(F), 1e-9 * kE);
  EXPECT_LE((sum.stress(F) - nh->stress(F) - lin->stress(F) - spring->stress(F)).norm(), 1e-9 * kE);
  EXPECT_LE(
      (sum.stress_derivative(F) - nh->stress_derivative(F) - lin->stress_derivative(F) - spring->stress_derivative(F))
          .norm(),
      1e-9 * kE);
  EXPECT_DOUBLE_EQ(sum.shear_modulus(), nh->shear_modulus() + lin->shear_modulus());
  EXPECT_DOUBLE_EQ(sum.lame_lambda(), nh->lame_lambda() + lin->lame_lambda());
  EXPECT_EQ(sum.name(), "sum(neo_hookean+linear_isotropic+anisotropic_spring)");
  // An inverted Neo-Hookean term makes the whole sum infinite.
  EXPECT_TRUE(std::isinf(sum.energy(-Mat3::Identity())));
  EXPECT_TRUE(sum.stress(-Mat3::Identity()).allFinite());
}

// ------------------------------------------------------------ bad parameters

void materials_expect_input_error(const std::function<void()>& make, const std::string& must_mention) {
  try {
    make();
    ADD_FAILURE() << "no InputError; expected one mentioning '" << must_mention << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(must_mention), std::string::npos) << e.what();
  }
}

// The damping tangent that spares rigid motion (material/scaled_material.hpp):
// the full dP/dF maps a rigid velocity W F to W P (so a stressed body's b K
// brakes its spin), the material part maps it to zero, and the two agree
// where there is no stress.
TEST(ScaledTangent, MaterialPartVanishesOnRigidVelocitiesAndAgreesWithoutStress) {
  std::mt19937 rng(7);
  const double b = 1.64e-4;
  const auto neo = std::make_shared<NeoHookean>(kE, kNu);
  const auto spring = std::make_shared<AnisotropicSpring>(kSpringC, Vec3(1, 2, 0.5));
  const MaterialPtr sum = std::make_shared<MaterialSum>(std::vector<MaterialPtr>{neo, spring});
  for (const MaterialPtr& base : {MaterialPtr(neo), sum}) {
    ASSERT_TRUE(base->frame_indifferent());
    const ScaledMaterial full(base, b, ScaledTangent::full), psd(base, b, ScaledTangent::psd),
        material(base, b, ScaledTangent::material_psd);
    for (int trial = 0; trial < 20; ++trial) {
      const Mat3 F = random_rotation(rng) * (Mat3::Identity() + random_matrix(rng, 0.15));
      ASSERT_GT(F.determinant(), 0);
      const Mat3 W0 = random_matrix(rng, 1.0), W = W0 - W0.transpose();
      const Mat3 WF = W * F;
      const Eigen::Map<const Vec9> rigid(WF.data());
      Mat3 P;
      Mat9 Hf, Hm;
      full.evaluate(F, nullptr, &P, &Hf);
      material.evaluate(F, nullptr, nullptr, &Hm);
      const Mat3 WP = W * P;
      const double scale = Hf.norm() * rigid.norm();
      EXPECT_LT((Hf * rigid - Eigen::Map<const Vec9>(WP.data())).norm(), 1e-9 * scale) << base->name();
      EXPECT_GT(WP.norm(), 1e-3 * scale) << "the stress should be visible to the full tangent";
      EXPECT_LT((Hm * rigid).norm(), 1e-9 * scale) << base->name();
      EXPECT_LT((Hm - Hm.transpose()).norm(), 1e-12 * Hm.norm());
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat9>(Hm).eigenvalues().minCoeff(), -1e-9 * Hm.norm());
      // Without stress (a pure rotation) the material part is the whole PSD tangent.
      const Mat3 R = random_rotation(rng);
      Mat9 Hr_psd, Hr_material;
      psd.evaluate(R, nullptr, nullptr, &Hr_psd);
      material.evaluate(R, nullptr, nullptr, &Hr_material);
      EXPECT_LT((Hr_psd - Hr_material).norm(), 1e-9 * Hr_psd.norm()) << base->name();
    }
  }
  // A small-strain material has no such split and keeps the PSD tangent.
  const auto linear = std::make_shared<LinearIsotropic>(kE, kNu);
  EXPECT_FALSE(linear->frame_indifferent());
  EXPECT_FALSE(MaterialSum({neo, linear}).frame_indifferent());
  const Mat3 F = Mat3::Identity() + random_matrix(rng, 0.1);
  Mat9 Hp, Hm;
  ScaledMaterial(linear, b, ScaledTangent::psd).evaluate(F, nullptr, nullptr, &Hp);
  ScaledMaterial(linear, b, ScaledTangent::material_psd).evaluate(F, nullptr, nullptr, &Hm);
  EXPECT_EQ(Hp, Hm);
}

TEST(MaterialParameters, BadValuesThrowInputErrorNamingTheParameter) {
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  for (double E : {-1.0, 0.0, nan, inf}) {
    materials_expect_input_error([&] { LinearIsotropic m(E, 0.3); }, "Young's modulus E");
    materials_expect_input_error([&] { NeoHookean m(E, 0.3); }, "Young's modulus E");
  }
  for (double nu : {0.5, 0.7, -1.0, -2.0, nan}) {
    materials_expect_input_error([&] { LinearIsotropic m(kE, nu); }, "Poisson's ratio nu");
    materials_expect_input_error([&] { NeoHookean m(kE, nu); }, "Poisson's ratio nu");
  }
  materials_expect_input_error([&] { NeoHookean m(kE, 0.5); }, "0.5");
  materials_expect_input_error([&] { AnisotropicSpring m(-1.0, Vec3::UnitX()); }, "stiffness C");
  materials_expect_input_error([&] { AnisotropicSpring m(nan, Vec3::UnitX()); }, "stiffness C");
  materials_expect_input_error([&] { AnisotropicSpring m(1.0, Vec3::Zero()); }, "direction v");
  materials_expect_input_error([&] { AnisotropicSpring m(1.0, Vec3(nan, 0, 0)); }, "direction v");
  materials_expect_input_error([&] { cubic_C(kE, 0.3, 0.0); }, "shear modulus G");

  Mat6 nonsymmetric = isotropic_C(kE, 0.3);
  nonsymmetric(0, 3) = 0.1 * kE;
  materials_expect_input_error([&] { LinearAnisotropic m(nonsymmetric); }, "not symmetric");
  Mat6 indefinite = isotropic_C(kE, 0.3);
  indefinite(4, 4) = -1.0;
  materials_expect_input_error([&] { LinearAnisotropic m(indefinite); }, "not positive definite");
  materials_expect_input_error([&] { LinearAnisotropic m(Mat6::Zero()); }, "not positive definite");
  Mat6 with_nan = isotropic_C(kE, 0.3);
  with_nan(2, 2) = nan;
  materials_expect_input_error([&] { LinearAnisotropic m(with_nan); }, "non-finite");
  OrthotropicConstants k{kE, kE, kE, 0.9, 0.9, 0.9, kE, kE, kE};
  materials_expect_input_error([&] { orthotropic_C(k); }, "not positive definite");

  // Valid edge cases are accepted.
  EXPECT_NO_THROW(AnisotropicSpring(0.0, Vec3(0, 0, 5)));
  EXPECT_NO_THROW(NeoHookean(kE, 0.499));
  EXPECT_EQ(AnisotropicSpring(1.0, Vec3(0, 0, 5)).direction(), Vec3::UnitZ());
  EXPECT_THROW(MaterialSum(std::vector<MaterialPtr>{}), InputError);
  EXPECT_THROW(MaterialSum(std::vector<MaterialPtr>{nullptr}), InputError);
}

TEST(GreenAnisotropic, LinearizesToItsStiffnessAndIgnoresRotations) {
  const Mat6 C = orthotropic_test_C();
  const GreenAnisotropic green(C);
  const LinearAnisotropic linear(C);
  // Same tangent at the rest state, same energy to second order.
  EXPECT_LE((green.stress_derivative(Mat3::Identity()) - linear.stress_derivative(Mat3::Identity())).norm(),
            1e-12 * linear.stress_derivative(Mat3::Identity()).norm());
  Mat3 G;
  G << 1, -2, 0.5, 0.3, 0.7, -1, 2, 0.1, -0.4;
  for (double t : {1e-3, 1e-4}) {
    const Mat3 F = Mat3::Identity() + t * G;
    EXPECT_NEAR(green.energy(F) / linear.energy(F), 1.0, 20 * t);
  }
  // A rotation changes nothing (the small-strain model would store energy).
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Mat3 F = Mat3::Identity() + 0.05 * G;
  EXPECT_NEAR(green.energy(R * F), green.energy(F), 1e-12 * green.energy(F));
  EXPECT_LE(green.energy(R), 1e-20 * C.norm());
  EXPECT_GT(linear.energy(R), 1e-3 * C.norm());
  // Semidefinite stiffness is accepted, indefinite is not.
  Mat6 rank_one = Mat6::Zero();
  rank_one(0, 0) = 1e6;
  EXPECT_NO_THROW(GreenAnisotropic{rank_one});
  rank_one(1, 1) = -1e3;
  EXPECT_THROW(GreenAnisotropic{rank_one}, InputError);
}

}  // namespace
}  // namespace msfab
