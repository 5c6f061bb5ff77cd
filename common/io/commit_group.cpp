#include "io/commit_group.hpp"

#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/input_file.hpp"
#include "io/sha256.hpp"

namespace msfab {
namespace {

constexpr const char* kJournalHeader = "msfab commit group 1";
constexpr std::uint64_t kMaxJournalBytes = 1 << 16;

struct JournalEntry {
  std::string tmp, final_path;
};

bool is_temporary_of(const std::string& tmp, const std::string& final_path) {
  // "<final>.<16 hex digits>.tmp", the names AtomicFile draws.
  if (tmp.size() != final_path.size() + 21 || tmp.compare(0, final_path.size(), final_path) != 0) return false;
  if (tmp[final_path.size()] != '.' || tmp.compare(tmp.size() - 4, 4, ".tmp") != 0) return false;
  const std::string digits = tmp.substr(final_path.size() + 1, 16);
  return digits.find_first_not_of("0123456789abcdef") == std::string::npos;
}

std::string format_journal(const std::vector<JournalEntry>& entries) {
  std::string text = std::string(kJournalHeader) + "\n";
  for (const JournalEntry& e : entries) text += e.tmp + "\t" + e.final_path + "\n";
  return text;
}

std::vector<JournalEntry> parse_journal(const std::string& journal, const std::string& member) {
  const std::string text = read_text_file(journal, kMaxJournalBytes);
  std::istringstream in(text);
  std::string line;
  const auto bad = [&](const std::string& why) {
    return InputError(journal + ": not a commit journal of msfab (" + why + "); remove it if no commit is running");
  };
  if (!std::getline(in, line) || line != kJournalHeader) throw bad("first line");
  std::vector<JournalEntry> entries;
  bool lists_member = false;
  while (std::getline(in, line)) {
    const std::size_t tab = line.find('\t');
    if (tab == std::string::npos) throw bad("a line without a tab");
    JournalEntry e{line.substr(0, tab), line.substr(tab + 1)};
    if (!is_temporary_of(e.tmp, e.final_path)) throw bad("'" + e.tmp + "' is no temporary of '" + e.final_path + "'");
    lists_member |= e.final_path == member;
    entries.push_back(std::move(e));
  }
  if (!lists_member) throw bad("it does not list " + member);
  return entries;
}

bool is_plain_file(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Steps 3 and 4 of the protocol; stops (as a killed process would) after
// `stop_after` renames.
void roll_forward(const std::vector<JournalEntry>& entries, std::size_t stop_after) {
  std::set<std::string> folders;
  for (const JournalEntry& e : entries) folders.insert(parent_directory(e.final_path));
  std::size_t renamed = 0;
  for (const JournalEntry& e : entries) {
    if (renamed == stop_after) return;
    if (!is_plain_file(e.tmp)) continue;  // renamed before an interruption
    // ENOENT: another process finishing the same journal renamed it first.
    if (::rename(e.tmp.c_str(), e.final_path.c_str()) != 0 && errno != ENOENT)
      throw std::runtime_error("commit group: cannot rename " + e.tmp + " to " + e.final_path + " (" +
                               std::strerror(errno) + ")");
    ++renamed;
  }
  for (const std::string& folder : folders) sync_directory(folder);
  for (const JournalEntry& e : entries) ::unlink(pending_journal_path(e.final_path).c_str());
  for (const std::string& folder : folders) sync_directory(folder);
}

}  // namespace

std::string pending_journal_path(const std::string& path) { return path + ".pending"; }

ArtifactWriter& CommitGroup::add(const std::string& path, const std::string& schema, int schema_version,
                                 const std::string& executable, const std::string& config_text,
                                 std::vector<ArtifactInput> inputs, std::uint64_t seed) {
  for (const auto& m : members_)
    if (same_file(m->path(), path)) throw InputError(path + ": named twice among the outputs of one run");
  members_.push_back(std::make_unique<ArtifactWriter>(path, schema, schema_version, executable, config_text,
                                                      ArtifactWriter::HashedInputs{std::move(inputs)}, seed));
  return *members_.back();
}

ArtifactInput CommitGroup::as_input(ArtifactWriter& member) {
  member.prepare();
  return {member.path(), sha256_file_hex(member.tmp_path())};
}

void CommitGroup::commit() { run_commit(std::numeric_limits<std::size_t>::max()); }

void CommitGroup::commit_interrupted_after(std::size_t renames) { run_commit(renames); }

void CommitGroup::run_commit(std::size_t stop_after) {
  if (members_.empty()) return;
  for (const auto& m : members_) {
    m->prepare();
    complete_interrupted_commit(m->path());  // an older group's journal must not outlive this commit
  }
  std::vector<JournalEntry> entries;
  for (const auto& m : members_) entries.push_back({m->tmp_path(), m->path()});
  const std::string journal = format_journal(entries);
  for (const JournalEntry& e : entries) write_file_atomically(pending_journal_path(e.final_path), journal);
  for (const auto& m : members_) m->release_temporary();  // the journals own them now
  roll_forward(entries, stop_after);
}

void complete_interrupted_commit(const std::string& path) {
  const std::string journal = pending_journal_path(path);
  struct stat st {};
  if (::lstat(journal.c_str(), &st) != 0) return;
  if (!S_ISREG(st.st_mode)) throw InputError(journal + ": not a regular file; remove it if no commit is running");
  const std::vector<JournalEntry> entries = parse_journal(journal, path);
  spdlog::warn("{}: finishing an interrupted commit of {} artifacts ({})", path, entries.size(), journal);
  roll_forward(entries, std::numeric_limits<std::size_t>::max());
}

}  // namespace msfab
