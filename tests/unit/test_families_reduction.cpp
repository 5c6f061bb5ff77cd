// Family selection and reduced template parameters (thesis §3.3, Appendix A).
#include <gtest/gtest.h>

#include <random>

#include "core/errors.hpp"
#include "families/family_selection.hpp"
#include "families/template_reduction.hpp"

using namespace msfab;

namespace {

// Members whose 6 parameters are driven by two hidden knobs: a moves log E
// along one parameter direction, b moves ν along another, plus a third
// direction that changes neither property (a nuisance spread).
struct Synthetic {
  MatX parameters, properties;
  VecX dir_a, dir_b, dir_c;
};

Synthetic synthetic_family(int members, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53 * 2.0 - 1.0; };
  Synthetic s;
  s.dir_a = (VecX(6) << 1, 1, 0, 0, 0, 0).finished().normalized();
  s.dir_b = (VecX(6) << 0, 0, 1, -1, 0, 0).finished().normalized();
  s.dir_c = (VecX(6) << 0, 0, 0, 0, 1, 0).finished();
  const VecX base = (VecX(6) << 0.2, 0.3, 0.4, 0.5, 0.6, 0.7).finished();
  s.parameters.resize(members, 6);
  s.properties.resize(members, 2);
  for (int i = 0; i < members; ++i) {
    const double a = uniform(), b = uniform(), c = uniform();
    s.parameters.row(i) = (base + 0.05 * a * s.dir_a + 0.03 * b * s.dir_b + 0.04 * c * s.dir_c).transpose();
    s.properties(i, 0) = -1.0 + 0.8 * a;  // log10 E
    s.properties(i, 1) = -0.3 - 0.2 * b;  // ν
  }
  return s;
}

}  // namespace

TEST(FamilyReduction, DirectionsFollowThePropertiesNotTheNuisance) {
  const Synthetic s = synthetic_family(60, 7);
  const ReducedTemplate r = reduce_template_parameters(s.parameters, s.properties);
  ASSERT_EQ(r.plus.size(), 2u);
  const VecX d0 = (r.plus[0] - r.base).normalized(), d1 = (r.plus[1] - r.base).normalized();
  // The first reduced direction is the one that moves E, the second ν; the
  // nuisance direction is in neither.
  EXPECT_GT(std::abs(d0.dot(s.dir_a)), 0.999);
  EXPECT_GT(std::abs(d1.dot(s.dir_b)), 0.999);
  EXPECT_LT(std::abs(d0.dot(s.dir_c)), 1e-3);
  EXPECT_LT(std::abs(d1.dot(s.dir_c)), 1e-3);
  EXPECT_NEAR(r.regression_r2[0], 1.0, 1e-9);
  EXPECT_NEAR(r.regression_r2[1], 1.0, 1e-9);
  // Reported slopes: r_1 = +1 raises log E by about the members' half range
  // (0.8), leaves ν; r_2 = +1 changes ν by about 0.2, leaves E.
  EXPECT_NEAR(std::abs(r.property_slope(0, 0)), 0.8, 0.08);
  EXPECT_LT(std::abs(r.property_slope(1, 0)), 1e-6);
  EXPECT_NEAR(std::abs(r.property_slope(1, 1)), 0.2, 0.02);
  EXPECT_LT(std::abs(r.property_slope(0, 1)), 1e-6);
}

TEST(FamilyReduction, AppendixAInterpolation) {
  const Synthetic s = synthetic_family(30, 3);
  const ReducedTemplate r = reduce_template_parameters(s.parameters, s.properties);
  EXPECT_LT((reduced_to_parameters(r, {0.0, 0.0}) - r.base).norm(), 1e-15);
  EXPECT_LT((reduced_to_parameters(r, {1.0, 0.0}) - r.plus[0]).norm(), 1e-15);
  EXPECT_LT((reduced_to_parameters(r, {0.0, -1.0}) - r.minus[1]).norm(), 1e-15);
  const VecX half = reduced_to_parameters(r, {0.5, -0.5});
  EXPECT_LT((half - (r.base + 0.5 * (r.plus[0] - r.base) + 0.5 * (r.minus[1] - r.base))).norm(), 1e-14);
  EXPECT_THROW(reduced_to_parameters(r, {1.5}), InputError);
  EXPECT_THROW(reduced_to_parameters(r, {0, 0, 0}), InputError);
}

TEST(FamilyReduction, BadInput) {
  EXPECT_THROW(reduce_template_parameters(MatX::Zero(2, 4), MatX::Zero(2, 2)), InputError);
  EXPECT_THROW(reduce_template_parameters(MatX::Zero(5, 4), MatX::Zero(4, 2)), InputError);
  EXPECT_THROW(reduce_template_parameters(MatX::Zero(5, 4), MatX::Zero(5, 2)), InputError);  // no spread
}

TEST(FamilySelection, WindowAndSpace) {
  MicrostructureSet set;
  set.space = "cubic3d";
  set.E_stiff = 2.0;
  set.nx = set.ny = set.nz = 8;
  const double props[4][4] = {
      {0.2, -0.3, 0.1, 0.3}, {0.2, 0.35, 0.1, 0.3}, {1.0, -0.1, 0.1, 0.5}, {0.4, -0.6, 0.1, 0.2}};
  for (const auto& p : props) {
    Microstructure m;
    m.properties = (VecX(4) << p[0], p[1], p[2], p[3]).finished();
    m.unit = VecX::Constant(4, 0.5);
    set.items.push_back(m);
  }
  SelectionOptions auxetic;
  auxetic.window.nu_max = 0.0;
  EXPECT_EQ(select_structures(set, auxetic, nullptr, "s.h5"), (std::vector<std::int64_t>{0, 2, 3}));
  auxetic.window.E_max = 0.4;  // E relative to E_stiff = 2: structure 2 (0.5) drops out
  EXPECT_EQ(select_structures(set, auxetic, nullptr, "s.h5"), (std::vector<std::int64_t>{0, 3}));
  SelectionOptions stiff_nu;
  stiff_nu.window.nu_min = 0.3;
  EXPECT_EQ(select_structures(set, stiff_nu, nullptr, "s.h5"), (std::vector<std::int64_t>{1}));
  EXPECT_NEAR(shear_modulus_ratio(1.0, 0.25, 0.4), 1.0, 1e-15);
  set.space = "cubic2d";
  try {
    select_structures(set, auxetic, nullptr, "s.h5");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.h5: attribute 'space' is 'cubic2d'"), std::string::npos);
  }
}
