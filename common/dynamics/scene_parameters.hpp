#pragma once
// Named parameters in a dynamics scene (docs/design_loop.md), so a design
// loop can vary lengths and heights:
//
//   parameters: {length: 0.040, hinge_height: 0.008}
//   reference_parameters: {length: 0.040}       # optional, see below
//   geometry:
//     boxes:
//       - {material: tango, min: [0, 0, 0.002], max: [0.008, 0.010, hinge_height]}
//       - {material: rigur, min: [0, 0, hinge_height], max: [length, 0.010, "hinge_height + 0.002"]}
//
// Any number in the scene may be written as an arithmetic expression over
// parameter names and numbers (+ - * /, unary minus, parentheses).
//
// The voxel mesh is built once at the reference values (the `parameters`
// themselves unless `reference_parameters` overrides some) and its nodes are
// then moved to the current values: along each axis, the piecewise-linear
// map that sends the sorted distinct box faces at the reference values to
// the same faces at the current values. Element count and connectivity
// therefore never change with the parameters and the rest shape moves
// continuously with them; voxelizing at every value instead would make any
// objective piecewise constant. Clamp and load regions are body-attached:
// read at the reference values and moved by the same map, so the same nodes
// stay loaded. Everything else (obstacles, forces, settings) is read at the
// current values.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "fem/hex_mesh.hpp"
#include "io/config.hpp"

namespace msfab {

using ParameterValues = std::map<std::string, double>;

// Evaluates `text` over `values`. Throws std::invalid_argument whose message
// says what is wrong (unknown name, unexpected token, division by zero).
double evaluate_parameter_expression(const std::string& text, const ParameterValues& values);

// Whether a string scalar is meant as an expression: it is made of names,
// numbers, operators and parentheses only, and it names a parameter or
// combines a number with an operator. Words ("rigur", "block-drop") and
// paths ("out/x.h5") are not.
bool looks_like_expression(const std::string& text, const ParameterValues& values);

// Per-axis piecewise-linear map from reference to current box faces.
class GeometryMorph {
 public:
  GeometryMorph() = default;
  // breakpoints[a]: sorted distinct reference faces along axis a and the
  // current value of each (strictly increasing as well).
  GeometryMorph(std::array<std::vector<double>, 3> reference, std::array<std::vector<double>, 3> current);

  bool is_identity() const;
  double map(int axis, double x) const;
  Vec3 map(const Vec3& x) const;
  // Moves the mesh's nodes and rebuilds its element geometries (one per
  // distinct element shape; connectivity and colours stay).
  void apply(HexMesh& mesh) const;

 private:
  std::array<std::vector<double>, 3> reference_, current_;
};

// Substitutes every expression in the scene `config` (a copy shares its
// document, so the substituted numbers are what later readers see):
// geometry boxes at the reference values, clamp and load regions at the
// reference values moved by the morph, everything else at the current
// values. Returns the morph to apply to the voxel mesh built from the
// boxes. Without a `parameters` section it does nothing and returns the
// identity. Errors (InputError) name the file, the key path and the
// expression.
GeometryMorph apply_scene_parameters(const Config& config);

}  // namespace msfab
