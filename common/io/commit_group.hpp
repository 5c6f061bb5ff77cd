#pragma once
// Artifacts that only make sense together (a gamut and the structure set it
// was sampled from) appear together or not at all.
//
// Each artifact is written to its own exclusive temporary (io/artifact.hpp).
// commit() then
//   1. syncs every temporary to disk,
//   2. writes a journal "<final path>.pending" beside every member, listing
//      each member's temporary and final path (each journal written
//      atomically itself),
//   3. renames every temporary over its final path,
//   4. removes the journals.
// A process killed anywhere in 3 leaves some members new and some old, and
// the journals in place. Whoever next opens any member as an artifact
// (ArtifactReader), or commits over it, first finishes the renames the
// journal lists (complete_interrupted_commit), so no reader ever sees the
// mixture. Killed before 2 finished, the temporaries are complete and the
// journal that exists rolls the whole group forward as well.
//
//   CommitGroup group;
//   ArtifactWriter& set = group.add(set_path, kSetSchema, 1, exe, config, {}, seed);
//   write_set(set.file(), structures);
//   ArtifactWriter& gamut = group.add(gamut_path, kGamutSchema, 1, exe, config,
//                                     {group.as_input(set)}, seed);
//   write_gamut(gamut.file(), g);
//   group.commit();
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "io/artifact.hpp"

namespace msfab {

class CommitGroup {
 public:
  CommitGroup() = default;
  CommitGroup(const CommitGroup&) = delete;
  CommitGroup& operator=(const CommitGroup&) = delete;

  // A new member (the ArtifactWriter constructor's arguments). InputError if
  // another member has the same path.
  ArtifactWriter& add(const std::string& path, const std::string& schema, int schema_version,
                      const std::string& executable, const std::string& config_text, std::vector<ArtifactInput> inputs,
                      std::uint64_t seed);
  // Finishes `member` (nothing more can be written to it) and returns it as
  // an input of a later member: its final path and the hash of its content.
  ArtifactInput as_input(ArtifactWriter& member);

  // All members or none (see above). Destroyed without commit(), the group
  // removes its temporaries and leaves every final path as it was.
  void commit();
  // For tests: commit() as far as `renames` renames, then stop as a killed
  // process would (temporaries and journals left on disk).
  void commit_interrupted_after(std::size_t renames);

  std::size_t size() const { return members_.size(); }

 private:
  void run_commit(std::size_t stop_after);
  std::vector<std::unique_ptr<ArtifactWriter>> members_;
};

// If a group commit over `path` was interrupted ("<path>.pending" exists),
// finishes it: renames every listed temporary that is still there over its
// final path and removes the group's journals. InputError naming the
// journal if it is not one this code writes (its entries must be
// temporaries of the form "<final>.<16 hex digits>.tmp" of the group's own
// members, which include `path`).
void complete_interrupted_commit(const std::string& path);

// The journal beside a member.
std::string pending_journal_path(const std::string& path);

}  // namespace msfab
