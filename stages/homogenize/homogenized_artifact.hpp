#pragma once
// The `msfab.homogenized` artifact (docs/artifacts.md).
#include <string>

#include "cell_input.hpp"
#include "finite_strain_check.hpp"
#include "homog/periodic_homogenization.hpp"

namespace msfab {

constexpr const char* kHomogenizedSchema = "msfab.homogenized";
constexpr int kHomogenizedSchemaVersion = 1;
// Relative deviation below which a tensor is reported as cubic.
constexpr double kCubicTolerance = 1e-6;

// `plane`: the 2D (plane strain) result of a cell one voxel thick, or null;
// `finite_strain`: the finite-strain check, or null.
void write_homogenized(const std::string& path, const CellInput& in, const HomogenizationResult& r,
                       const PlaneStrainResult* plane, const FiniteStrainCheck* finite_strain,
                       const std::string& config_text, const std::string& command_line, std::uint64_t seed);

}  // namespace msfab
