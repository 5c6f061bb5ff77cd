#include "sampler_checkpoint.hpp"

#include "core/errors.hpp"
#include "io/checkpoint_file.hpp"

namespace msfab {

void write_sampler_checkpoint(const std::string& path, const std::string& run_text, const SamplerState& s) {
  write_checkpoint_file(path, "msfab.gamut.checkpoint", run_text, [&](H5File& f) {
    f.write_attribute("/", "cycles_done", static_cast<std::int32_t>(s.cycles_done));
    f.write_attribute("/", "push_step", s.push_step);
    write_microstructure_set(f, "/set", s.set);
    f.write_vector("/population", s.population);
    f.write_vector("/refined", s.refined);
    std::vector<double> rows;
    for (const GamutCycle& c : s.history)
      rows.insert(rows.end(), {double(c.cycle), double(c.samples), double(c.discrete_added), double(c.continuous_added),
                               c.coverage, c.seconds});
    f.write_dataset("/history", rows, {hsize_t(s.history.size()), 6});
  });
}

SamplerState read_sampler_checkpoint(const std::string& path, const std::string& run_text) {
  const H5File f = open_checkpoint_file(path, "msfab.gamut.checkpoint", "gamut-sampler", run_text);
  SamplerState s;
  s.cycles_done = f.read_attribute<std::int32_t>("/", "cycles_done");
  if (f.has_attribute("/", "push_step")) s.push_step = f.read_attribute<double>("/", "push_step");
  s.set = read_microstructure_set(f, "/set");
  s.population = f.read_vector<std::int64_t>("/population");
  s.refined = f.read_vector<std::uint8_t>("/refined");
  if (s.refined.size() != s.set.items.size()) throw InputError(path + ": /refined does not match /set");
  for (std::int64_t p : s.population)
    if (p < 0 || p >= static_cast<std::int64_t>(s.set.items.size()))
      throw InputError(path + ": /population index out of range");
  const NdArray<double> h = f.read_dataset<double>("/history");
  for (std::size_t r = 0; r + 6 <= h.values.size(); r += 6) {
    const double* v = &h.values[r];
    s.history.push_back({int(v[0]), int(v[1]), int(v[2]), int(v[3]), v[4], v[5]});
  }
  return s;
}

}  // namespace msfab
