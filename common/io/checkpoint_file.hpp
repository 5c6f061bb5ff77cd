#pragma once
// The checkpoint of a long stage, "<out>.checkpoint.h5", kept by one rule
// for every stage that resumes (the database builder, the gamut sampler):
//   - rewritten whole after each round, through an AtomicFile, so an
//     interrupted write leaves the last complete checkpoint;
//   - tagged with a schema and the run's text (the resolved config, plus the
//     seed where results depend on it);
//   - read back only when both match, so a resume never mixes two runs.
// The stage writes and reads its own state inside the file.
#include <cstdint>
#include <functional>
#include <string>

#include "io/hdf5_file.hpp"

namespace msfab {

std::string checkpoint_path(const std::string& out);

// The text a checkpoint is tagged with when the run depends on its seed as
// well as on its config.
std::string checkpoint_run_text(const std::string& resolved_config, std::uint64_t seed);

void write_checkpoint_file(const std::string& path, const std::string& schema, const std::string& run_text,
                           const std::function<void(H5File&)>& write_state);

// The checkpoint open for reading. InputError naming the file when it is not
// an HDF5 file, has another schema ("not a <what> checkpoint") or was written
// by another run (with the remedy).
H5File open_checkpoint_file(const std::string& path, const std::string& schema, const std::string& what,
                            const std::string& run_text);

}  // namespace msfab
