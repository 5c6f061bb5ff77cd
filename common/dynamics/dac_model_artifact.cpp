#include "dynamics/dac_model_artifact.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/field_table.hpp"

namespace msfab {

namespace {
constexpr const char* kSchema = "msfab.dac_model";
constexpr int kVersion = 1;
const FieldOf<DacModel> kFields[] = {MSFAB_FIELD(DacModel, material),       MSFAB_FIELD(DacModel, reference_modulus),
                                     MSFAB_FIELD(DacModel, youngs_modulus), MSFAB_FIELD(DacModel, damping_a),
                                     MSFAB_FIELD(DacModel, damping_b),      MSFAB_FIELD(DacModel, target_frequency),
                                     MSFAB_FIELD(DacModel, target_decay),   MSFAB_FIELD(DacModel, target_eigenvalue),
                                     MSFAB_FIELD(DacModel, voxel_size),     MSFAB_FIELD(DacModel, elements),
                                     MSFAB_FIELD(DacModel, marker_rms)};
}  // namespace

void write_dac_model_artifact(const std::string& path, const DacModel& m, const std::string& executable,
                              const std::string& config_text, const std::vector<std::string>& inputs,
                              std::uint64_t seed) {
  ArtifactWriter out(path, kSchema, kVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_vector("/coarse_eigenvalues", m.coarse_eigenvalues);
  f.write_attribute("/coarse_eigenvalues", "units", "rad^2/s^2, with the reference modulus");
  write_attribute_fields(f, "/", m, kFields);
  out.commit();
}

DacModel read_dac_model_artifact(const std::string& path) {
  ArtifactReader in(path, kSchema, kVersion);
  const H5File& f = in.file();
  DacModel m;
  read_attribute_fields(f, "/", m, kFields);
  const std::vector<double> ev = f.read_vector<double>("/coarse_eigenvalues");
  m.coarse_eigenvalues = Eigen::Map<const VecX>(ev.data(), static_cast<Eigen::Index>(ev.size()));
  if (!(m.youngs_modulus > 0) || !(m.damping_a >= 0) || !(m.damping_b >= 0) || !std::isfinite(m.damping_b))
    throw InputError(path + ": youngs_modulus / damping attributes are not a valid material");
  return m;
}

}  // namespace msfab
