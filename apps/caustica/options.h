// Option values as the user typed them, checked before anything is loaded or rendered.
//
// Numbers are registered with CLI11 as text and parsed here, strictly: CLI11's own conversion
// turns "-1" into 2^64-1 for an unsigned and accepts "nan" and "inf" for a float, which crashed
// or hung renders. Every option of render, reference and compare goes through one
// CheckedOptions, so a rule (a range, a format) is written once for all three subcommands, and a
// bad value gives one line naming the option and a short excerpt of the value, exit code 2.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace caustica::cli {

// Prints "caustica: error: MESSAGE" as exactly one line: control bytes escaped, a long message cut.
void print_error(const std::string& message);

// A user's value as an error message may quote it: quoted, at most 40 bytes, control bytes as \xNN.
std::string excerpt(const std::string& value);

// Options whose text is parsed and range-checked by check(); an option not given keeps the
// default already in its target.
class CheckedOptions {
 public:
  explicit CheckedOptions(CLI::App* command) : command_(command) {}

  // An integer in [lo, hi].
  CLI::Option* integer(const std::string& flags, int* out, int lo, int hi, const std::string& help);
  CLI::Option* integer(const std::string& flags, uint64_t* out, uint64_t lo, uint64_t hi,
                       const std::string& help);
  // A finite number in [lo, hi], or (lo, hi] when lo_open.
  CLI::Option* number(const std::string& flags, double* out, double lo, double hi, bool lo_open,
                      const std::string& help);
  CLI::Option* number(const std::string& flags, float* out, double lo, double hi, bool lo_open,
                      const std::string& help);
  // "WxH", both positive; the pixel count is checked against memory later (film_memory_problem).
  CLI::Option* resolution(const std::string& flags, int* width, int* height,
                          const std::string& help);
  // One of `valid`.
  CLI::Option* choice(const std::string& flags, std::string* out, std::vector<std::string> valid,
                      const std::string& help);

  // Any non-empty text (a path, a name checked later).
  CLI::Option* text(const std::string& flags, std::string* out, const std::string& help);

  // Parses every option that was given; on the first bad one prints one line and returns false.
  bool check() const;

 private:
  // Returns "" or what is wrong with the text (the message names the option).
  using Parser = std::function<std::string(const std::string& text)>;
  CLI::Option* add(const std::string& flags, const std::string& type, const std::string& help,
                   Parser parse);

  struct Entry {
    std::shared_ptr<std::string> text;
    CLI::Option* option;
    Parser parse;
  };
  CLI::App* command_;
  std::vector<Entry> entries_;
};

}  // namespace caustica::cli
