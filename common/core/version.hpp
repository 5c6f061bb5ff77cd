#pragma once
// The toolkit's version and the git revision it was built from, as written
// into every artifact's `producer` attribute and printed by --version.

namespace msfab {

const char* version();
const char* git_revision();

}  // namespace msfab
