// Running the caustica binary from tests: each run in its own folder, stderr captured.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

namespace cli_test {

namespace fs = std::filesystem;

struct CliRun {
  int exit_code;  // -1 if the shell did not exit normally
  std::string err;
};

// Runs `caustica ARGS` in `dir` (a shell command line: quote as for sh), stdout discarded,
// stderr in dir/stderr.txt. A run still going after `limit_seconds` is killed (exit code 137)
// so that a hang fails the test instead of stalling the suite.
inline CliRun run(const std::string& args, const fs::path& dir, int limit_seconds = 120) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = "cd '" + dir.string() + "' && timeout -s KILL " +
                          std::to_string(limit_seconds) + " " + CAUSTICA_BINARY + " " + args +
                          " > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  std::ifstream f(err);
  std::stringstream ss;
  ss << f.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

inline fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(testing::TempDir()) / ("caustica_cli_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Names in `dir` (hidden ones too), not recursive.
inline std::set<std::string> entries(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

inline bool only_stderr_file(const fs::path& dir) {
  return entries(dir) == std::set<std::string>{"stderr.txt"};
}

}  // namespace cli_test
