#pragma once
// The `msfab.gamut` artifact (docs/artifacts.md): the level set of the
// achievable properties, with the material space and normalization it
// lives in, and the sampler's per-cycle history. The topology optimizer
// reads it for its per-cell constraint Phi(p) <= 0.
#include <cstdint>
#include <string>
#include <vector>

#include "gamut/level_set.hpp"
#include "gamut/space_label.hpp"

namespace msfab {

class H5File;

inline constexpr const char* kGamutSchema = "msfab.gamut";
inline constexpr int kGamutSchemaVersion = 1;

struct GamutCycle {
  int cycle = 0;
  int samples = 0;                               // structures in the set after the cycle
  int discrete_added = 0, continuous_added = 0;  // continuous: the level-set pushes and the directed ones
  double coverage = 0;                           // fraction of the unit cube inside the gamut (coverage())
  double seconds = 0;                            // wall time of the cycle
};

struct Gamut : SpaceLabel {
  GamutLevelSet level_set;
  std::vector<GamutCycle> history;
  // The base materials as tensors of the space (3 x 3 plane-strain in-plane
  // block in 2D, 6 x 6 in 3D; soft zero for void): every structure obeys
  // the Voigt bound C <= rho C_stiff + (1 - rho) C_soft, which the topology
  // optimizer imposes with the level set (topopt/voigt_bound.hpp). Empty in
  // artifacts written before they were stored.
  MatX bound_stiff, bound_soft;
};

// Fraction of the level-set nodes inside the unit cube with Phi <= 0: the
// volume of the sampled gamut in normalized property space.
double coverage(const GamutLevelSet& level_set);

void write_gamut_artifact(const std::string& path, const Gamut& gamut, const std::string& executable,
                          const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed);
// The gamut's datasets and attributes into an artifact being written (a
// member of a commit group, io/commit_group.hpp).
void write_gamut(H5File& file, const Gamut& gamut);
Gamut read_gamut_artifact(const std::string& path);

}  // namespace msfab
