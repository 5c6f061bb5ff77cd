// msfab-inspect: prints what an artifact holds (provenance, the config it
// was made with, its inputs and whether they are still the files it read,
// datasets and their shapes) and, with --schema, checks it is the kind of
// artifact a pipeline step expects. Exit code 2 for a missing, corrupt or
// mismatched file.
#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/sha256.hpp"

using namespace msfab;

namespace {

void list_tree(const H5File& f, const std::string& group, int depth) {
  for (const std::string& name : f.children(group)) {
    const std::string path = (group == "/" ? "" : group) + "/" + name;
    if (f.is_group(path)) {
      std::printf("%*s%s/\n", 2 * depth, "", name.c_str());
      list_tree(f, path, depth + 1);
    } else {
      std::string shape;
      for (auto d : f.dataset_shape(path)) shape += (shape.empty() ? "" : " x ") + std::to_string(d);
      std::printf("%*s%s  [%s]\n", 2 * depth, "", name.c_str(), shape.empty() ? "scalar" : shape.c_str());
    }
  }
}

// What an input is now: the file it names still there with the same bytes
// (and, for an artifact, who made it), changed, or gone.
std::string input_state(const ArtifactInput& in) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(in.path, ec)) return "missing now";
  if (sha256_file_hex(in.path) != in.sha256) return "changed since (hash differs)";
  std::string state = "unchanged";
  try {
    const H5File f = H5File::open(in.path);
    if (f.has_attribute("/", "producer")) state += ", made by " + f.read_string_attribute("/", "producer");
  } catch (const std::exception&) {
    // Not an HDF5 artifact (a YAML scene, a voxel file): nothing more to say.
  }
  return state;
}

void print_indented(const std::string& text, const char* indent) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) std::printf("%s%s\n", indent, line.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-inspect", "Show the provenance and contents of an msfab artifact");
  std::string path, schema;
  int version = 0;
  app.option("artifact", path, "artifact file (.h5)").required();
  app.option("--schema", schema, "fail (exit 2) unless the artifact has this schema, e.g. msfab.result");
  app.option("--schema-version", version, "with --schema: the supported schema_version (default: any)");
  bool no_config = false;
  app.flag("--no-config", no_config, "leave out the config the artifact was made with");
  app.add_version_option();
  return app.run(argc, argv, [&](StageContext&) {
    std::string found_schema;
    if (!schema.empty()) {
      const ArtifactReader reader =
          version > 0 ? ArtifactReader(path, schema, version) : ArtifactReader(path, schema, 1, 1 << 30);
      found_schema = reader.schema();
    }
    // Without --schema any schema is accepted: read it from the file first.
    const H5File f = H5File::open(path);
    if (!f.has_attribute("/", "schema"))
      throw InputError(path + ": not an msfab artifact (no 'schema' attribute on the root group)");
    found_schema = f.read_string_attribute("/", "schema");
    const ArtifactReader reader(path, found_schema, 1, 1 << 30);
    std::printf("%s\n  schema    %s v%d\n  producer  %s\n  created   %s\n  seed      %llu\n", path.c_str(),
                reader.schema().c_str(), reader.schema_version(), reader.producer().c_str(), reader.created().c_str(),
                static_cast<unsigned long long>(reader.seed()));
    for (const auto& in : reader.inputs())
      std::printf("  input     %s  sha256 %s  (%s)\n", in.path.c_str(), in.sha256.c_str(), input_state(in).c_str());
    if (!no_config) {
      const std::string config = reader.config();
      std::printf("config:\n");
      print_indented(config.empty() ? "(none stored)" : config, "  ");
    }
    std::printf("contents:\n");
    list_tree(reader.file(), "/", 1);
  });
}
