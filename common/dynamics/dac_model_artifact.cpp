#include "dynamics/dac_model_artifact.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "io/artifact.hpp"

namespace msfab {

namespace {
constexpr const char* kSchema = "msfab.dac_model";
constexpr int kVersion = 1;
}  // namespace

void write_dac_model_artifact(const std::string& path, const DacModel& m, const std::string& executable,
                              const std::string& config_text, const std::vector<std::string>& inputs,
                              std::uint64_t seed) {
  ArtifactWriter out(path, kSchema, kVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_vector("/coarse_eigenvalues", m.coarse_eigenvalues);
  f.write_attribute("/coarse_eigenvalues", "units", "rad^2/s^2, with the reference modulus");
  f.write_attribute("/", "material", m.material);
  f.write_attribute("/", "reference_modulus", m.reference_modulus);
  f.write_attribute("/", "youngs_modulus", m.youngs_modulus);
  f.write_attribute("/", "damping_a", m.damping_a);
  f.write_attribute("/", "damping_b", m.damping_b);
  f.write_attribute("/", "target_frequency", m.target_frequency);
  f.write_attribute("/", "target_decay", m.target_decay);
  f.write_attribute("/", "target_eigenvalue", m.target_eigenvalue);
  f.write_attribute("/", "voxel_size", m.voxel_size);
  f.write_attribute("/", "elements", m.elements);
  f.write_attribute("/", "marker_rms", m.marker_rms);
  out.commit();
}

DacModel read_dac_model_artifact(const std::string& path) {
  ArtifactReader in(path, kSchema, kVersion);
  const H5File& f = in.file();
  DacModel m;
  m.material = f.read_string_attribute("/", "material");
  m.reference_modulus = f.read_attribute<double>("/", "reference_modulus");
  m.youngs_modulus = f.read_attribute<double>("/", "youngs_modulus");
  m.damping_a = f.read_attribute<double>("/", "damping_a");
  m.damping_b = f.read_attribute<double>("/", "damping_b");
  m.target_frequency = f.read_attribute<double>("/", "target_frequency");
  m.target_decay = f.read_attribute<double>("/", "target_decay");
  m.target_eigenvalue = f.read_attribute<double>("/", "target_eigenvalue");
  m.voxel_size = f.read_attribute<double>("/", "voxel_size");
  m.elements = f.read_attribute<int>("/", "elements");
  m.marker_rms = f.read_attribute<double>("/", "marker_rms");
  const std::vector<double> ev = f.read_vector<double>("/coarse_eigenvalues");
  m.coarse_eigenvalues = Eigen::Map<const VecX>(ev.data(), static_cast<Eigen::Index>(ev.size()));
  if (!(m.youngs_modulus > 0) || !(m.damping_a >= 0) || !(m.damping_b >= 0) || !std::isfinite(m.damping_b))
    throw InputError(path + ": youngs_modulus / damping attributes are not a valid material");
  return m;
}

}  // namespace msfab
