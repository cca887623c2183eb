// Deduplicating warning reporter: each distinct construct is reported once, at its first
// position, as "file:line:col: warning: message".
#pragma once

#include <set>
#include <string>

#include "io/load_error.h"

namespace caustica::pbrt {

class Warnings {
 public:
  explicit Warnings(WarningSink sink) : sink_(sink) {}
  // `key` identifies the construct (defaults to the message); a repeated key is dropped.
  void warn(const SourceLocation& where, const std::string& message, const std::string& key = {}) {
    if (!seen_.insert(key.empty() ? message : key).second) return;
    ++count_;
    if (sink_) sink_(where.str() + ": warning: " + message);
  }
  int count() const { return count_; }

 private:
  WarningSink sink_;
  std::set<std::string> seen_;
  int count_ = 0;
};

}  // namespace caustica::pbrt
