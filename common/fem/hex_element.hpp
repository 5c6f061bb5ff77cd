#pragma once
// Energy, gradient and Hessian of one hexahedron whose quadrature points each
// carry a material (a plain element uses the same material everywhere; a
// DDFEM coarse element, Eq. 2.6-2.7, uses a different one per point).
#include <memory>
#include <vector>

#include "fem/hex8.hpp"
#include "material/material.hpp"

namespace msfab {

// Materials at the quadrature points of one element. A single entry applies
// to every point. A null entry is a point without material (a void voxel
// inside a Galerkin coarse element): it adds no energy and cannot invert,
// and is skipped rather than evaluated as a zero material.
//
// An element on none of the standard rules (the Galerkin element on fewer
// points, ddfem/galerkin_quadrature.hpp) carries its own `rule`, one
// material per point of it; without one the mesh builders tell the rule by
// the number of materials.
struct QuadratureMaterials {
  std::vector<MaterialPtr> at_point;
  std::shared_ptr<const hex8::QuadratureRule> rule = nullptr;
  const Material* at(int q) const { return at_point[at_point.size() == 1 ? 0 : static_cast<size_t>(q)].get(); }
};

// Element energy for deformed node positions x (rows = nodes). Returns +inf
// as soon as one quadrature point is inverted.
double hex_energy(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x);

// What an element with bubble modes keeps between evaluations (one per
// such element of a mesh; ElasticAssembler holds them). Its state changes
// only the cost of an evaluation, not its result beyond the condensation's
// tolerance (hex_element.cpp: a decrement below 1e-14 of the energy, or a
// step below 1e-13 of the element's size, whose energy error is ~1e-26 of
// the element's energy scale).
struct BubbleState {
  // The minimizing amplitudes at the positions of the last condensation,
  // and the energy there.
  Mat3 A = Mat3::Zero();
  hex8::NodeMatrix at = hex8::NodeMatrix::Zero();
  double energy = 0;
  bool condensed = false;
  int evaluations = 0;  // of the element's terms in the last condensation (0: reused)
  // From the last evaluation with a gradient: the amplitudes there and their
  // derivative in the positions (dA/dx = -sensitivity, node-major columns),
  // so that a later condensation nearby starts from
  // model_A - sensitivity (x - model_at), second-order close to its minimum.
  Eigen::Matrix<double, 9, 24> sensitivity = Eigen::Matrix<double, 9, 24>::Zero();
  Mat3 model_A = Mat3::Zero();
  hex8::NodeMatrix model_at = hex8::NodeMatrix::Zero();
  bool has_model = false;
  Mat3 predicted(const hex8::NodeMatrix& x) const;
};

// Energy, gradient (24, node-major: 3*i + a) and Hessian (24x24) in one pass;
// pass nullptr for what is not needed. Returns the energy (+inf if inverted,
// in which case gradient and Hessian are not meaningful).
//
// For an element with bubble modes, `bubbles` (optional) is the element's
// state: the condensation at positions it last condensed at is reused, and
// elsewhere starts from the state's prediction (from its last amplitudes,
// then from 0, if the element is inverted there); the state is then
// updated. A Newton iteration (one gradient evaluation and a line search
// along its step) then condenses in about one bubble Newton step per
// evaluation instead of three to six.
double hex_evaluate(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                    Vec24* gradient, Mat24* hessian, BubbleState* bubbles = nullptr);

// For an element with bubble modes (geo.has_enhanced_modes()): the 3 x 3
// amplitudes A (row i: displacement component i, column k: bubble
// 1 - chi_k^2) that minimize its energy at nodal positions x, found as
// hex_evaluate finds them. False if the element is inverted at A = 0. The
// DDFEM fit on the enhanced element holds A fixed while it solves for the
// material parameters (ddfem/coarse_fit.hpp).
bool hex_condensed_bubbles(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat, const hex8::NodeMatrix& x,
                           Mat3& A);

}  // namespace msfab
