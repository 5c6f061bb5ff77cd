#include "io/checkpoint_file.hpp"

#include "core/errors.hpp"
#include "io/atomic_file.hpp"

namespace msfab {

std::string checkpoint_path(const std::string& out) { return out + ".checkpoint.h5"; }

std::string checkpoint_run_text(const std::string& resolved_config, std::uint64_t seed) {
  return resolved_config + "# seed " + std::to_string(seed) + "\n";
}

void write_checkpoint_file(const std::string& path, const std::string& schema, const std::string& run_text,
                           const std::function<void(H5File&)>& write_state) {
  AtomicFile tmp(path);
  {
    H5File f = H5File::create_in(tmp);
    f.write_attribute("/", "schema", schema);
    f.write_attribute("/", "config", run_text);
    write_state(f);
    f.close();
  }
  tmp.commit();
}

H5File open_checkpoint_file(const std::string& path, const std::string& schema, const std::string& what,
                            const std::string& run_text) {
  H5File f = H5File::open(path);
  if (!f.has_attribute("/", "schema") || f.read_string_attribute("/", "schema") != schema)
    throw InputError(path + ": not a " + what + " checkpoint");
  if (!f.has_attribute("/", "config") || f.read_string_attribute("/", "config") != run_text)
    throw InputError(path +
                     ": checkpoint was written with a different configuration or seed; delete it or rerun "
                     "without --resume");
  return f;
}

}  // namespace msfab
