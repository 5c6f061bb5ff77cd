#pragma once
// The `msfab.dac_model` artifact (docs/artifacts.md): the numerical modulus
// and Rayleigh damping that dynamics-aware coarsening fitted for one
// material at one voxel size, with the target it was fitted to.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct DacModel {
  std::string material;
  double reference_modulus = 0;  // E_m used for the coarse modes
  double youngs_modulus = 0;     // E_n
  double damping_a = 0, damping_b = 0;
  double target_frequency = 0, target_decay = 0, target_eigenvalue = 0;
  VecX coarse_eigenvalues;  // with E_m
  double voxel_size = 0;    // of the coarse mesh the fit holds for
  int elements = 0;
  double marker_rms = 0;  // harmonic-inversion residual (0 if the target was given)
};

void write_dac_model_artifact(const std::string& path, const DacModel& model, const std::string& executable,
                              const std::string& config_text, const std::vector<std::string>& inputs,
                              std::uint64_t seed);
DacModel read_dac_model_artifact(const std::string& path);

}  // namespace msfab
