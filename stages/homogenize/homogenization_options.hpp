#pragma once
// The cell solver settings of msfab-homogenize's config (void_stiffness,
// linear_solver, linear_tolerance, linear_max_iterations, use_symmetry), read into the options of
// homog/periodic_homogenization.hpp; shared by the stage and the Python
// bindings, so both solve a cell the same way.
#include "homog/periodic_homogenization.hpp"
#include "io/config.hpp"

namespace msfab {

// Missing keys keep HomogenizationOptions' defaults; InputError naming the
// key on a value out of range.
HomogenizationOptions read_homogenization_options(const Config& config);

}  // namespace msfab
