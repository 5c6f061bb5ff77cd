// Scene parameters: the expression language, substitution into a dynamics
// scene, the mesh built at the reference values and morphed (continuous in
// the parameters, fixed connectivity), and errors that name the key path.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/scene_parameters.hpp"
#include "io/config.hpp"

namespace msfab {
namespace {

const ParameterValues kValues{{"a", 2.0}, {"b", 0.5}, {"hinge_height", 0.008}};

TEST(ParameterExpression, FollowsPrecedenceSignsAndParentheses) {
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("a + b * 4", kValues), 4.0);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("(a + b) * 4", kValues), 10.0);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("a - b - 1", kValues), 0.5);  // left associative
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("a / b / 2", kValues), 2.0);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("-a * -b", kValues), 1.0);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("--a", kValues), 2.0);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression("hinge_height + 2e-3", kValues), 0.010);
  EXPECT_DOUBLE_EQ(evaluate_parameter_expression(" .5E+1 ", kValues), 5.0);
}

TEST(ParameterExpression, ReportsWhatIsWrong) {
  auto message = [](const std::string& text) {
    try {
      evaluate_parameter_expression(text, kValues);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("a + c").find("unknown parameter 'c' (defined: a, b, hinge_height)"), std::string::npos);
  EXPECT_NE(message("a +").find("expression ends early"), std::string::npos);
  EXPECT_NE(message("(a + b").find("missing ')'"), std::string::npos);
  EXPECT_NE(message("a b").find("unexpected 'b'"), std::string::npos);
  EXPECT_NE(message("a / (b - 0.5)").find("division by zero"), std::string::npos);
  EXPECT_NE(message("a % 2").find("unexpected character '%'"), std::string::npos);
  EXPECT_NE(message("1e").find("malformed number"), std::string::npos);
}

TEST(ParameterExpression, TellsExpressionsFromWordsAndPaths) {
  EXPECT_TRUE(looks_like_expression("a", kValues));
  EXPECT_TRUE(
      looks_like_expression("hinge_heigth + 0.002", kValues));  // misspelled: still an expression, then an error
  EXPECT_FALSE(looks_like_expression("rigur", kValues));
  EXPECT_FALSE(looks_like_expression("bbi", kValues));
  EXPECT_FALSE(looks_like_expression("flipper-param", kValues));
  EXPECT_TRUE(looks_like_expression("-(0.5)", kValues));
  EXPECT_FALSE(looks_like_expression("out/dac_soft.h5", kValues));
}

TEST(GeometryMorph, IsPiecewiseLinearAndTranslatesOutside) {
  const GeometryMorph m({std::vector<double>{0, 0.008, 0.040}, {}, {}}, {std::vector<double>{0, 0.010, 0.050}, {}, {}});
  EXPECT_DOUBLE_EQ(m.map(0, 0.004), 0.005);
  EXPECT_DOUBLE_EQ(m.map(0, 0.008), 0.010);
  EXPECT_DOUBLE_EQ(m.map(0, 0.024), 0.030);
  EXPECT_DOUBLE_EQ(m.map(0, 0.045), 0.055);  // beyond the last face: moves with it
  EXPECT_DOUBLE_EQ(m.map(1, 0.123), 0.123);  // no faces on y: identity
  EXPECT_FALSE(m.is_identity());
}

// A two-material flipper-like scene; `length` moves the end of the plates,
// `hinge` the hinge top and the top plate.
std::string scene_text(const std::string& extra = "") {
  return R"(
name: param
parameters: {length: 0.012, hinge: 0.004, b0: 2}
materials:
  - {name: stiff, E: 1.0e6, nu: 0.3, density: 1000}
  - {name: soft, E: 1.0e5, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.002
  boxes:
    - {material: stiff, min: [0, 0, 0], max: [length, 0.002, 0.002]}
    - {material: soft, min: [0, 0, 0.002], max: [0.004, 0.002, hinge]}
    - {material: stiff, min: [0, 0, hinge], max: [length, 0.002, "hinge + 0.002"]}
obstacles:
  - {type: ground, z: 0}
  - {type: box, name: wall, min: ["length + 0.01", -1, 0], max: ["length + 0.02", 1, "2 * hinge"]}
press:
  region: {min: ["length - 0.004", 0, "hinge + 0.002"], max: [length, 0.002, "hinge + 0.002"]}
  force: [0, 0, "-1 * b0"]
simulation: {time_step: 1.0e-4, duration: 0.001}
)" + extra;
}

std::string text_of(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

DynamicsScene read(const std::string& text, const std::vector<std::string>& overrides) {
  Config c = Config::from_string(text, "param.yaml");
  c.apply_overrides(overrides);
  DynamicsScene s = read_dynamics_scene(c);
  c.check_no_unknown_keys();
  return s;
}

TEST(SceneParameters, SubstituteIntoObstaclesLoadsAndGeometry) {
  const DynamicsScene s = read(scene_text(), {});
  EXPECT_EQ(s.model.mesh.num_elements(), 6 + 2 + 6);
  EXPECT_NEAR(s.model.mesh.bbox_max().x(), 0.012, 1e-15);
  EXPECT_NEAR(s.model.mesh.bbox_max().z(), 0.006, 1e-15);
  ASSERT_EQ(s.model.obstacles.size(), 2u);
  EXPECT_NEAR(s.model.obstacles[1].lo.x(), 0.022, 1e-15);
  EXPECT_NEAR(s.model.obstacles[1].hi.z(), 0.008, 1e-15);
  EXPECT_DOUBLE_EQ(s.load.force.z(), -2.0);
  EXPECT_NEAR(s.load.lo.x(), 0.008, 1e-15);
}

TEST(SceneParameters, NodesMoveContinuouslyWithFixedConnectivity) {
  const std::string text = scene_text();
  const DynamicsScene ref = read(text, {});
  // Parameters changed by far less than a voxel: no remeshing, nodes move
  // by a proportionally small amount, the press keeps the same nodes.
  for (double d : {1e-6, 1e-4, 7e-4}) {
    const DynamicsScene s =
        read(text, {"parameters.length=" + text_of(0.012 + d), "reference_parameters.length=0.012",
                    "parameters.hinge=" + text_of(0.004 + d / 2), "reference_parameters.hinge=0.004"});
    ASSERT_EQ(s.model.mesh.num_nodes(), ref.model.mesh.num_nodes());
    ASSERT_EQ(s.model.mesh.elements, ref.model.mesh.elements);
    const double moved = (s.model.mesh.nodes - ref.model.mesh.nodes).cwiseAbs().maxCoeff();
    EXPECT_NEAR(moved, d, 1e-12) << "the plate ends move with length";
    EXPECT_NEAR(s.model.mesh.bbox_max().x(), 0.012 + d, 1e-12);
    EXPECT_NEAR(s.model.mesh.bbox_max().z(), 0.006 + d / 2, 1e-12);
    const VecX f = region_force(s, s.load, "press"), f0 = region_force(ref, ref.load, "press");
    EXPECT_EQ((f.array() != 0).count(), (f0.array() != 0).count()) << "the same nodes stay loaded";
    EXPECT_NEAR((f - f0).cwiseAbs().maxCoeff(), 0, 1e-15);
    // Stretched elements get their own geometry: volume grows with length.
    double volume = 0, volume0 = 0;
    for (int e = 0; e < s.model.mesh.num_elements(); ++e)
      for (double w : s.model.mesh.geometries[s.model.mesh.element_geometry[e]].weight) volume += w;
    for (int e = 0; e < ref.model.mesh.num_elements(); ++e)
      for (double w : ref.model.mesh.geometries[ref.model.mesh.element_geometry[e]].weight) volume0 += w;
    EXPECT_GT(volume, volume0);
  }
}

TEST(SceneParameters, WithoutReferenceTheSceneIsVoxelizedAtTheValues) {
  const std::string text = scene_text();
  const DynamicsScene s = read(text, {"parameters.length=0.016"});
  EXPECT_EQ(s.model.mesh.num_elements(), 8 + 2 + 8);
  EXPECT_NEAR(s.model.mesh.bbox_max().x(), 0.016, 1e-15);
}

std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    read(text, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(SceneParameters, ErrorsNameFileKeyPathAndExpression) {
  const std::string ok = scene_text();
  const std::string unknown = std::string(ok).replace(ok.find("\"hinge + 0.002\"]}"), 15, "\"hinje + 0.002\"");
  EXPECT_NE(
      error_of(unknown).find("param.yaml: geometry.boxes[2].max[2] = \"hinje + 0.002\": unknown parameter 'hinje'"),
      std::string::npos)
      << error_of(unknown);
  const std::string malformed = std::string(ok).replace(ok.find("\"2 * hinge\""), 11, "\"2 * (hinge\"");
  EXPECT_NE(error_of(malformed).find("obstacles[1].max[2] = \"2 * (hinge\": missing ')'"), std::string::npos)
      << error_of(malformed);
  EXPECT_NE(error_of(ok, {"parameters.length=abc"}).find("parameters.length"), std::string::npos);
  EXPECT_NE(error_of(ok, {"reference_parameters.width=0.01"}).find("reference_parameters.width"), std::string::npos);
  // The plate ends pulled back past the hinge's end on x.
  const std::string order = error_of(ok, {"parameters.length=0.003", "reference_parameters.length=0.012"});
  EXPECT_NE(order.find("change order"), std::string::npos) << order;
}

TEST(SceneParameters, SceneWithoutParametersIsUntouched) {
  const std::string text = R"(
materials: [{name: m, E: 1.0e6, nu: 0.3, density: 1000}]
geometry: {voxel_size: 0.002, boxes: [{material: m, min: [0, 0, 0], max: [0.004, 0.002, 0.002]}]}
simulation: {time_step: 1.0e-4, duration: 0.001}
)";
  const DynamicsScene s = read(text, {});
  EXPECT_EQ(s.model.mesh.num_elements(), 2);
  EXPECT_NE(error_of(text, {"reference_parameters.a=1"}).find("needs a `parameters` section"), std::string::npos);
}

}  // namespace
}  // namespace msfab
