// msfab-inspect: prints what an artifact holds (provenance, datasets and
// their shapes) and, with --schema, checks it is the kind of artifact a
// pipeline step expects. Exit code 2 for a missing, corrupt or mismatched file.
#include <cstdio>
#include <functional>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "io/artifact.hpp"

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

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-inspect", "Show the provenance and contents of an msfab artifact");
  std::string path, schema;
  int version = 0;
  app.cli().add_option("artifact", path, "artifact file (.h5)")->required();
  app.cli().add_option("--schema", schema, "fail (exit 2) unless the artifact has this schema, e.g. msfab.result");
  app.cli().add_option("--schema-version", version, "with --schema: the supported schema_version (default: any)");
  app.add_common_options();
  return app.run(argc, argv, [&](StageContext&) {
    std::string found_schema;
    if (!schema.empty()) {
      const ArtifactReader reader = version > 0 ? ArtifactReader(path, schema, version)
                                                : ArtifactReader(path, schema, 1, 1 << 30);
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
    for (const auto& in : reader.inputs()) std::printf("  input     %s  sha256 %s\n", in.path.c_str(), in.sha256.c_str());
    std::printf("contents:\n");
    list_tree(reader.file(), "/", 1);
  });
}
