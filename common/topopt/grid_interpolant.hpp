#pragma once
// A C^1 interpolant of values given on a tensor grid: cubic Hermite along
// each axis with Catmull-Rom tangents (central differences inside, one-sided
// at the ends), combined as a tensor product. It reproduces every grid
// value exactly and is linear in the data, so each channel is a weighted sum
// of node values whose weights have closed-form derivatives. The topology
// optimizer's family spaces use it to move a cell continuously between the
// members of a family grid (topopt/family_material.hpp); a C^1 surface keeps
// Ipopt's line search and MMA's approximations from meeting kinks at the
// members. Two nodes along an axis give linear interpolation, one a constant.
#include <vector>

#include "core/types.hpp"

namespace msfab {

class GridInterpolant {
 public:
  GridInterpolant() = default;
  // sizes: nodes per axis (each >= 1); values: nodes x channels, nodes in
  // grid order with the first axis slowest. std::invalid_argument on
  // inconsistent sizes.
  GridInterpolant(std::vector<int> sizes, MatX values);

  int axes() const { return static_cast<int>(sizes_.size()); }
  int channels() const { return static_cast<int>(values_.cols()); }
  const std::vector<int>& sizes() const { return sizes_; }

  // Values at t in [0, 1]^axes (node j of an axis of n nodes sits at
  // t = j / (n - 1); t is clamped into the box), and with `gradient`, the
  // derivatives d value / d t (channels x axes; zero across a clamped face).
  void evaluate(const VecX& t, VecX& value, MatX* gradient = nullptr) const;

 private:
  std::vector<int> sizes_;
  MatX values_;
};

}  // namespace msfab
