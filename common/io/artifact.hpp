#pragma once
// Artifact files (DESIGN §3): one HDF5 file per stage output, carrying its
// provenance as root attributes and written atomically. docs/artifacts.md
// describes the conventions.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/hdf5_file.hpp"

namespace msfab {

// One input artifact as recorded in the `inputs` root attribute.
struct ArtifactInput {
  std::string path;
  std::string sha256;
};

// "<executable> <version> (git <revision>)" (core/version.hpp).
std::string producer_string(const std::string& executable);
// Current time as ISO-8601 UTC, e.g. "2024-05-01T12:34:56Z".
std::string utc_timestamp_now();
// The `inputs` attribute: one "<sha256>  <path>" line per input, the format
// of `sha256sum`, so `sha256sum -c` can check it.
std::string format_inputs(const std::vector<ArtifactInput>& inputs);
std::vector<ArtifactInput> parse_inputs(const std::string& text);

// Attributes holding a list of names ("E,nu,G,rho").
std::string format_name_list(const std::vector<std::string>& names);
std::vector<std::string> parse_name_list(const std::string& text);

// Writes an exclusive temporary "<path>.<random>.tmp" (io/atomic_file.hpp);
// commit() flushes, closes, syncs and renames it over <path>. Destroyed
// without commit() (an exception, an early return), it deletes the
// temporary and leaves whatever was at <path> untouched.
//
//   ArtifactWriter out(path, "msfab.result", 1, "msfab-simulate", config_text,
//                      {mesh_path}, seed);
//   out.file().write_matrix("/displacement", u);
//   out.file().write_attribute("/displacement", "units", "m");
//   out.commit();
class ArtifactWriter {
 public:
  // Hashes every input (InputError if one is missing or is the output
  // itself), creates the temporary (InputError if the output folder is
  // missing or not writable, or the path is a folder) and writes the root
  // attributes. `executable` is the program name; the version and
  // git revision are added here.
  ArtifactWriter(std::string path, std::string schema, int schema_version, const std::string& executable,
                 const std::string& config_text, const std::vector<std::string>& input_paths, std::uint64_t seed);
  // The same with inputs already hashed (an artifact of the same commit
  // group, io/commit_group.hpp, whose final path does not hold it yet).
  struct HashedInputs {
    explicit HashedInputs(std::vector<ArtifactInput> inputs) : list(std::move(inputs)) {}
    std::vector<ArtifactInput> list;
  };
  ArtifactWriter(std::string path, std::string schema, int schema_version, const std::string& executable,
                 const std::string& config_text, HashedInputs inputs, std::uint64_t seed);
  ArtifactWriter(const ArtifactWriter&) = delete;
  ArtifactWriter& operator=(const ArtifactWriter&) = delete;
  ~ArtifactWriter();

  H5File& file();
  const std::string& path() const { return path_; }
  const std::string& tmp_path() const;
  bool committed() const { return committed_; }

  // Throws std::runtime_error if the data cannot be made durable; the final
  // path then still holds its previous content.
  void commit();
  // The first half of commit(): the HDF5 file closed and its temporary
  // synced to disk (file() is then no longer usable). Idempotent.
  void prepare();
  // After prepare(): the temporary's name, handed over to a commit group's
  // journal; this writer no longer removes it.
  std::string release_temporary();

 private:
  void discard() noexcept;

  std::string path_;
  std::unique_ptr<AtomicFile> tmp_;
  std::optional<H5File> file_;
  bool prepared_ = false;
  bool committed_ = false;
};

// Opens an artifact for reading after checking that the file exists, is
// valid HDF5, and carries the expected schema with a supported version.
// Every failure is an InputError naming the file, what was expected and what
// was found.
class ArtifactReader {
 public:
  ArtifactReader(const std::string& path, const std::string& expected_schema, int supported_version);
  // Accepts schema_version in [min_version, max_version].
  ArtifactReader(const std::string& path, const std::string& expected_schema, int min_version, int max_version);

  const H5File& file() const { return file_; }
  const std::string& path() const { return file_.path(); }
  const std::string& schema() const { return schema_; }
  int schema_version() const { return schema_version_; }
  std::string producer() const;
  std::string config() const;
  std::vector<ArtifactInput> inputs() const;
  std::uint64_t seed() const;
  std::string created() const;

 private:
  H5File file_;
  std::string schema_;
  int schema_version_ = 0;
};

}  // namespace msfab
