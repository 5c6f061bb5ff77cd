#pragma once
// The `msfab.families` artifact (docs/artifacts.md): what family discovery
// found in a set of microstructures (thesis §3.3) — the selection, the
// Isomap embedding, the mixture clusters and, per family, its members, the
// template fitted to its representative and to every member, and the
// reduced parameters that msfab-family-generate turns into structures.
//
// Templates are stored as flat parameter vectors, 9 per beam (a, b, r0, r1,
// theta; families/beam_template.hpp), so the file needs nothing but numbers.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "families/template_reduction.hpp"

namespace msfab {

inline constexpr const char* kFamiliesSchema = "msfab.families";
inline constexpr int kFamiliesSchemaVersion = 1;

struct FamilyRecord {
  std::vector<std::int64_t> members;      // indices into the input set
  std::int64_t representative = -1;       // index into the input set
  bool caps = true;                       // the template's beams carry dome caps
  VecX representative_template;           // 9 per beam, fitted to the representative
  double representative_difference = 0;   // its voxel difference
  std::vector<double> member_difference;  // per member: voxel difference of the refitted template (NaN: not fitted)
  std::vector<char> member_kept;          // per member: used for the reduction
  MatX member_parameters;                 // members x parameters (rows of unfitted members: NaN)
  bool has_reduced = false;
  ReducedTemplate reduced;
  // Property ranges over all members: E / E_stiff, ν, G' = 2G(1+ν)/E.
  double E_range[2] = {0, 0}, nu_range[2] = {0, 0}, shear_ratio_range[2] = {0, 0};
};

struct FamiliesResult {
  int resolution = 0;                   // voxels per cell edge of the input set
  double E_stiff = 0, decades = 4;      // the input set's normalization
  double stiff_E = 0, stiff_nu = 0;     // its stiff base material (generated structures are made of it)
  std::vector<std::int64_t> selection;  // indices of the selected structures
  MatX embedding;                       // selection x dimensions (rows of left-out structures: NaN)
  std::vector<int> labels;              // per selected structure: its mixture cluster, -1 left out
  std::vector<int> family_of;           // per selected structure: its family, -1 none
  VecX eigenvalues;                     // of the MDS
  double residual_variance = 0;
  std::vector<int> bic_components;     // mixture sizes tried
  std::vector<double> bic;             // their BIC
  int clusters = 0;                    // mixture size chosen
  std::vector<FamilyRecord> families;  // by decreasing member count
};

void write_families_artifact(const std::string& path, const FamiliesResult& result, const std::string& executable,
                             const std::string& config_text, const std::vector<std::string>& inputs,
                             std::uint64_t seed);
// InputError naming the file and field on a wrong schema or inconsistent data.
FamiliesResult read_families_artifact(const std::string& path);

}  // namespace msfab
