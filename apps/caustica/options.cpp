#include "options.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace caustica::cli {

namespace {

// Whole-string parses: no sign for unsigned, no leading blanks or '+', nothing after the number.
template <typename T>
bool parse_whole(const std::string& text, T* out) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *out);
  return ec == std::errc() && ptr == end && !text.empty();
}

std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string first_flag(const std::string& flags) { return flags.substr(0, flags.find(',')); }

template <typename T>
std::string check_integer(const std::string& name, const std::string& text, T lo, T hi, T* out) {
  T value{};
  if (!parse_whole(text, &value) || value < lo || value > hi)
    return name + " must be an integer from " + std::to_string(lo) + " to " + std::to_string(hi) +
           ", got " + excerpt(text);
  *out = value;
  return "";
}

std::string check_number(const std::string& name, const std::string& text, double lo, double hi,
                         bool lo_open, double* out) {
  double value = 0;
  // from_chars accepts "nan" and "inf"; the range test below rejects them (NaN compares false).
  const bool ok = parse_whole(text, &value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  if (!ok)
    return name + " must be a number " + (lo_open ? "greater than " : "at least ") +
           format_number(lo) + " and at most " + format_number(hi) + ", got " + excerpt(text);
  *out = value;
  return "";
}

}  // namespace

void print_error(const std::string& message) {
  constexpr size_t kMaxBytes = 400;  // one terminal line or two; values are already excerpts
  std::string line;
  for (const unsigned char c : message) {
    if (line.size() >= kMaxBytes) {
      line += "...";
      break;
    }
    if (c < 0x20 || c == 0x7f) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\x%02x", c);
      line += esc;
    } else {
      line += char(c);
    }
  }
  std::fprintf(stderr, "caustica: error: %s\n", line.c_str());
}

std::string excerpt(const std::string& value) {
  constexpr size_t kMaxBytes = 40;
  std::string out = "'";
  for (size_t i = 0; i < value.size() && i < kMaxBytes; ++i) {
    const unsigned char c = value[i];
    if (c < 0x20 || c == 0x7f) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\x%02x", c);
      out += esc;
    } else {
      out += char(c);
    }
  }
  out += value.size() > kMaxBytes ? "'..." : "'";
  return out;
}

CLI::Option* CheckedOptions::add(const std::string& flags, const std::string& type,
                                 const std::string& help, Parser parse) {
  auto text = std::make_shared<std::string>();
  CLI::Option* option = command_->add_option(flags, *text, help)->type_name(type);
  entries_.push_back({text, option, std::move(parse)});
  return option;
}

CLI::Option* CheckedOptions::integer(const std::string& flags, int* out, int lo, int hi,
                                     const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "INT", help,
             [=](const std::string& t) { return check_integer(name, t, lo, hi, out); });
}

CLI::Option* CheckedOptions::integer(const std::string& flags, uint64_t* out, uint64_t lo,
                                     uint64_t hi, const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "UINT", help,
             [=](const std::string& t) { return check_integer(name, t, lo, hi, out); });
}

CLI::Option* CheckedOptions::number(const std::string& flags, double* out, double lo, double hi,
                                    bool lo_open, const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "FLOAT", help,
             [=](const std::string& t) { return check_number(name, t, lo, hi, lo_open, out); });
}

CLI::Option* CheckedOptions::number(const std::string& flags, float* out, double lo, double hi,
                                    bool lo_open, const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "FLOAT", help, [=](const std::string& t) {
    double value = 0;
    std::string problem = check_number(name, t, lo, hi, lo_open, &value);
    if (problem.empty()) *out = float(value);
    return problem;
  });
}

CLI::Option* CheckedOptions::resolution(const std::string& flags, int* width, int* height,
                                        const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "WxH", help, [=](const std::string& t) {
    const size_t x = t.find('x');
    int w = 0, h = 0;
    // Each side fits an int; whether their product fits in memory is film_memory_problem's.
    if (x == std::string::npos || !parse_whole(t.substr(0, x), &w) ||
        !parse_whole(t.substr(x + 1), &h) || w <= 0 || h <= 0)
      return name + " expects WxH with positive integers, e.g. 256x256, got " + excerpt(t);
    *width = w;
    *height = h;
    return std::string();
  });
}

CLI::Option* CheckedOptions::choice(const std::string& flags, std::string* out,
                                    std::vector<std::string> valid, const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "TEXT", help, [=](const std::string& t) {
    for (const auto& v : valid)
      if (v == t) {
        *out = t;
        return std::string();
      }
    std::string list;
    for (const auto& v : valid) list += (list.empty() ? "" : ", ") + v;
    return name + " must be one of " + list + ", got " + excerpt(t);
  });
}

CLI::Option* CheckedOptions::text(const std::string& flags, std::string* out,
                                  const std::string& help) {
  const std::string name = first_flag(flags);
  return add(flags, "TEXT", help, [=](const std::string& t) {
    if (t.empty()) return name + " must not be empty";
    *out = t;
    return std::string();
  });
}

bool CheckedOptions::check() const {
  for (const Entry& e : entries_) {
    if (e.option->count() == 0) continue;
    if (std::string problem = e.parse(*e.text); !problem.empty()) {
      print_error(problem);
      return false;
    }
  }
  return true;
}

}  // namespace caustica::cli
