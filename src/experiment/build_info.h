// What a benchmark must print about where it ran (STYLE.md: "every benchmark prints the
// machine, build type, commit"): the CPU, its cores, and the build as CMake configured it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace caustica {

struct BuildInfo {
  std::string build_type;  // CMAKE_BUILD_TYPE
  std::string commit;      // `git describe --always --dirty` when CMake last configured
};
BuildInfo build_info();

struct MachineInfo {
  std::string cpu;         // "model name" of /proc/cpuinfo ("unknown" elsewhere)
  unsigned logical_cores;  // std::thread::hardware_concurrency
};
MachineInfo machine_info();

// Both, as the JSON objects `caustica bench` writes.
nlohmann::json build_and_machine_json();

}  // namespace caustica
