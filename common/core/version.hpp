#pragma once
// The toolkit's version and the git revision it was built from, as written
// into every artifact's `producer` attribute and printed by --version.

namespace msfab {

const char* version();
const char* git_revision();

// A stage executable's identity: the SHA-256 of the sources it is built from
// (tools/stage_identity.sh), registered by a file the build generates for
// each stage. The pipeline reruns a stage's artifacts when it changes, not
// when the revision does. Empty in programs that are not stages (tests,
// bindings).
void register_stage_identity(const char* sha256_hex, int source_count);
const char* stage_identity();
int stage_identity_source_count();

}  // namespace msfab
