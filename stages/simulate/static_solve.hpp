#pragma once
// The static solves of msfab-simulate: Newton with the scene's load
// stepping, a progress display, and an error naming the solve when it does
// not converge.
#include "scene/scene.hpp"
#include "solve/newton.hpp"

namespace msfab {

// solve_static from x0 (rest if empty) with a progress line labelled
// `label`; throws NumericalError with the residual history if Newton fails.
NewtonResult solve_or_throw(const ElasticAssembler& assembler, const StaticConditions& conditions,
                            const NewtonOptions& options, const char* label, const VecX& x0 = VecX());

}  // namespace msfab
