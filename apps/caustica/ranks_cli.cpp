#include "ranks_cli.h"

#include <unistd.h>

#include <cstdio>
#include <exception>
#include <string>

#include "options.h"

namespace caustica::cli {

namespace {

int guarded(const std::function<int()>& prepare) {
  try {
    return prepare();
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
}

// Runs `fn` with file descriptor 2 pointing at a temporary file, and returns what was written.
// A descriptor swap, not a stream swap, so that everything reaches it: our fprintf(stderr) and
// any library's write(2).
std::string capture_stderr(const std::function<int()>& fn, int* rc) {
  std::fflush(stderr);
  std::FILE* held = std::tmpfile();
  const int saved = held ? ::dup(STDERR_FILENO) : -1;
  if (saved < 0 || ::dup2(::fileno(held), STDERR_FILENO) < 0) {
    if (saved >= 0) ::close(saved);
    if (held) std::fclose(held);
    *rc = guarded(fn);  // cannot hold it back: print it (a duplicate is better than nothing)
    return "";
  }
  *rc = guarded(fn);
  std::fflush(stderr);
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  std::string text;
  std::rewind(held);
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, held)) > 0;) text.append(buf, n);
  std::fclose(held);
  return text;
}

}  // namespace

int prepare_on_all_ranks(Ranks& ranks, const std::function<int()>& prepare) {
  if (ranks.size() == 1) return guarded(prepare);
  int rc = 0;
  std::string mine;
  if (ranks.is_root())
    rc = guarded(prepare);
  else
    mine = capture_stderr(prepare, &rc);
  while (!mine.empty() && mine.back() == '\n') mine.pop_back();
  if (rc != 0 && mine.empty()) mine = "failed with exit code " + std::to_string(rc);
  // "caustica: error: X" becomes "caustica: error: rank 1 of 2: X": one message, one prefix.
  const std::string prefix = "caustica: error: ";
  if (mine.rfind(prefix, 0) == 0) mine.erase(0, prefix.size());
  std::string message;
  const int agreed = ranks.agree(rc, rc != 0 ? mine : "", &message);
  if (ranks.is_root() && !message.empty())
    std::fprintf(stderr, "%s%s\n", prefix.c_str(), message.c_str());
  return agreed;
}

}  // namespace caustica::cli
