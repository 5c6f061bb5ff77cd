#pragma once
// Pieces of the small dense Newton solves that sample a block (the isolated
// block of force_samples.hpp, the periodic block of periodic_samples.hpp).
#include "core/types.hpp"

namespace msfab {

// Newton direction step = -(H + s I)^{-1} g with the smallest shift s in
// {0, 1e-8 d, 1e-7 d, ...} (d the largest |diagonal| of H) for which the
// shifted H is positive definite and the step descends (step . g < 0).
// False if twelve shifts do not give one.
bool shifted_descent_step(const MatX& H, const VecX& g, VecX& step);

// The energy line search's acceptance: Armijo decrease, or, on a first
// (full) trial, an energy unchanged to machine precision: near convergence
// the decrease drowns in round-off.
bool energy_step_accepted(double trial, double current, double alpha, double slope, bool first_trial);

// Largest |eigenvalue| of the small strain sym(grad u).
double largest_small_strain(const Mat3& grad_u);

}  // namespace msfab
