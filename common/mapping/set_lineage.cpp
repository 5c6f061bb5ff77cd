#include "mapping/set_lineage.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <vector>

#include "core/errors.hpp"
#include "gamut/gamut_artifact.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/artifact.hpp"
#include "io/sha256.hpp"
#include "topopt/design_artifact.hpp"

namespace msfab {

namespace {

bool lists_hash(const std::vector<ArtifactInput>& inputs, const std::string& hash) {
  return std::any_of(inputs.begin(), inputs.end(), [&](const ArtifactInput& i) { return i.sha256 == hash; });
}

// The design's gamut as recorded in its inputs, if a gamut file is still at
// that path (path empty otherwise).
struct RecordedGamut {
  std::string path, sha256;
  std::vector<ArtifactInput> inputs;  // the gamut's own: its structures
};
RecordedGamut recorded_gamut(const std::vector<ArtifactInput>& design_inputs) {
  for (const ArtifactInput& in : design_inputs) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(in.path, ec)) continue;
    try {
      return {in.path, in.sha256, ArtifactReader(in.path, kGamutSchema, kGamutSchemaVersion).inputs()};
    } catch (const InputError&) {
      continue;  // another input (not a gamut)
    }
  }
  return {};
}

}  // namespace

void check_set_belongs_to_design(const std::string& design_path, const std::string& structures_path) {
  const std::vector<ArtifactInput> design_inputs =
      ArtifactReader(design_path, kDesignSchema, kDesignSchemaVersion).inputs();
  const std::string set_hash = sha256_file_hex(structures_path);
  if (lists_hash(design_inputs, set_hash)) return;  // a design made from this set (msfab-assign)
  const RecordedGamut gamut = recorded_gamut(design_inputs);
  if (gamut.path.empty()) {
    spdlog::warn("{}: its gamut is not where the design records it; cannot check that {} holds its structures",
                 design_path, structures_path);
    return;
  }
  if (sha256_file_hex(gamut.path) != gamut.sha256) {
    spdlog::warn("{}: changed since {} was optimized in it; cannot check that {} holds its structures", gamut.path,
                 design_path, structures_path);
    return;
  }
  if (gamut.inputs.empty()) return;  // a gamut that records no structures: nothing to compare
  if (lists_hash(gamut.inputs, set_hash)) return;
  const std::vector<ArtifactInput> set_inputs =
      ArtifactReader(structures_path, kMicrostructuresSchema, kMicrostructuresSchemaVersion).inputs();
  for (const ArtifactInput& in : set_inputs)
    if (lists_hash(gamut.inputs, in.sha256)) return;  // derived from the gamut's structures
  throw InputError(structures_path + ": not the structures of the gamut " + gamut.path + " that " + design_path +
                   " was optimized in, nor a set derived from them (the gamut was built from " +
                   gamut.inputs.front().path + "); pass that set");
}

}  // namespace msfab
