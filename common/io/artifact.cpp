#include "io/artifact.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/version.hpp"
#include "io/commit_group.hpp"
#include "io/input_file.hpp"
#include "io/sha256.hpp"

namespace msfab {

std::string format_name_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ",") + name;
  return out;
}

std::vector<std::string> parse_name_list(const std::string& text) {
  std::vector<std::string> names;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');) names.push_back(name);
  return names;
}

namespace {

std::string versions_text(int min_version, int max_version) {
  if (min_version == max_version) return "version " + std::to_string(min_version);
  return "version " + std::to_string(min_version) + " to " + std::to_string(max_version);
}

}  // namespace

std::string producer_string(const std::string& executable) {
  const std::string identity = stage_identity();
  return executable + " " + version() + " (git " + git_revision() +
         (identity.empty() ? "" : ", stage " + identity.substr(0, 12)) + ")";
}

std::string utc_timestamp_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::string format_inputs(const std::vector<ArtifactInput>& inputs) {
  std::string text;
  for (const ArtifactInput& input : inputs) text += input.sha256 + "  " + input.path + "\n";
  return text;
}

std::vector<ArtifactInput> parse_inputs(const std::string& text) {
  std::vector<ArtifactInput> inputs;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    const std::size_t gap = line.find("  ");
    if (gap == std::string::npos) {
      inputs.push_back({line, ""});  // written by something else; keep the text
    } else {
      inputs.push_back({line.substr(gap + 2), line.substr(0, gap)});
    }
  }
  return inputs;
}

// ---------------------------------------------------------------------------
// ArtifactWriter

namespace {
void refuse_output_as_input(const std::string& output, const std::string& input) {
  if (same_file(input, output))
    throw InputError(output + ": the output is also an input of this run; writing it would destroy the input");
}

// The inputs with their hashes, each checked before it is read.
std::vector<ArtifactInput> hash_inputs(const std::string& output, const std::vector<std::string>& input_paths) {
  std::vector<ArtifactInput> inputs;
  for (const std::string& input : input_paths) {
    refuse_output_as_input(output, input);
    inputs.push_back({input, sha256_file_hex(input)});
  }
  return inputs;
}
}  // namespace

ArtifactWriter::ArtifactWriter(std::string path, std::string schema, int schema_version, const std::string& executable,
                               const std::string& config_text, const std::vector<std::string>& input_paths,
                               std::uint64_t seed)
    : ArtifactWriter(path, std::move(schema), schema_version, executable, config_text,
                     HashedInputs(hash_inputs(path, input_paths)), seed) {}

ArtifactWriter::ArtifactWriter(std::string path, std::string schema, int schema_version, const std::string& executable,
                               const std::string& config_text, HashedInputs inputs, std::uint64_t seed)
    : path_(std::move(path)) {
  for (const ArtifactInput& input : inputs.list) refuse_output_as_input(path_, input.path);
  tmp_ = std::make_unique<AtomicFile>(path_);
  try {
    file_.emplace(H5File::create_in(*tmp_));
    H5File& out = *file_;
    out.write_attribute("/", "schema", schema);
    out.write_attribute("/", "schema_version", std::int32_t(schema_version));
    out.write_attribute("/", "producer", producer_string(executable));
    out.write_attribute("/", "config", config_text);
    out.write_attribute("/", "inputs", format_inputs(inputs.list));
    out.write_attribute("/", "seed", std::uint64_t(seed));
    out.write_attribute("/", "created", utc_timestamp_now());
  } catch (...) {
    discard();  // the destructor does not run for a half-built object
    throw;
  }
}

const std::string& ArtifactWriter::tmp_path() const { return tmp_->tmp_path(); }

void ArtifactWriter::discard() noexcept {
  file_.reset();  // closes quietly
  tmp_.reset();   // removes the temporary
}

ArtifactWriter::~ArtifactWriter() {
  if (!committed_) discard();
}

H5File& ArtifactWriter::file() {
  if (committed_) throw std::logic_error(path_ + ": artifact used after commit()");
  return *file_;
}

void ArtifactWriter::prepare() {
  if (committed_) throw std::logic_error(path_ + ": prepare() after commit()");
  if (prepared_) return;
  file_->flush();
  file_->close();
  tmp_->sync();
  prepared_ = true;
}

std::string ArtifactWriter::release_temporary() {
  prepare();
  committed_ = true;
  return tmp_->release();
}

void ArtifactWriter::commit() {
  if (committed_) throw std::logic_error(path_ + ": commit() called twice");
  prepare();
  // An older group commit left unfinished over this path would otherwise
  // roll its stale temporary over what is committed now.
  complete_interrupted_commit(path_);
  tmp_->commit();
  committed_ = true;
}

// ---------------------------------------------------------------------------
// ArtifactReader

namespace {
// A member of an interrupted group commit is opened only once the group is
// whole again (io/commit_group.hpp).
H5File open_finished(const std::string& path) {
  complete_interrupted_commit(path);
  return H5File::open(path);
}
}  // namespace

ArtifactReader::ArtifactReader(const std::string& path, const std::string& expected_schema, int supported_version)
    : ArtifactReader(path, expected_schema, supported_version, supported_version) {}

ArtifactReader::ArtifactReader(const std::string& path, const std::string& expected_schema, int min_version,
                               int max_version)
    : file_(open_finished(path)) {
  const std::string expected = "expected schema '" + expected_schema + "' " + versions_text(min_version, max_version);
  if (!file_.has_attribute("/", "schema") || !file_.has_attribute("/", "schema_version")) {
    throw InputError(path + ": " + expected +
                     ", found no schema/schema_version root attributes (not an msfab artifact)");
  }
  schema_ = file_.read_string_attribute("/", "schema");
  schema_version_ = int(file_.read_attribute<std::int64_t>("/", "schema_version"));
  if (schema_ != expected_schema || schema_version_ < min_version || schema_version_ > max_version) {
    throw InputError(path + ": " + expected + ", found schema '" + schema_ + "' version " +
                     std::to_string(schema_version_));
  }
}

std::string ArtifactReader::producer() const { return file_.read_string_attribute("/", "producer"); }
std::string ArtifactReader::config() const { return file_.read_string_attribute("/", "config"); }
std::vector<ArtifactInput> ArtifactReader::inputs() const {
  return parse_inputs(file_.read_string_attribute("/", "inputs"));
}
std::uint64_t ArtifactReader::seed() const { return file_.read_attribute<std::uint64_t>("/", "seed"); }
std::string ArtifactReader::created() const { return file_.read_string_attribute("/", "created"); }

}  // namespace msfab
