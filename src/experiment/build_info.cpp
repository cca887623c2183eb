#include "experiment/build_info.h"

#include <fstream>
#include <thread>

// The build type is defined for this file only by src/CMakeLists.txt; the commit comes from a
// header the build regenerates when the commit changes (cmake/write_commit.cmake).
#include "build_commit.h"
#ifndef CAUSTICA_BUILD_TYPE
#define CAUSTICA_BUILD_TYPE "unknown"
#endif

namespace caustica {

BuildInfo build_info() { return {CAUSTICA_BUILD_TYPE, CAUSTICA_GIT_COMMIT}; }

MachineInfo machine_info() {
  MachineInfo m{"unknown", std::thread::hardware_concurrency()};
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon != std::string::npos) m.cpu = line.substr(line.find_first_not_of(" \t", colon + 1));
    break;
  }
  return m;
}

nlohmann::json build_and_machine_json() {
  const BuildInfo b = build_info();
  const MachineInfo m = machine_info();
  return {{"build", {{"build_type", b.build_type}, {"commit", b.commit}}},
          {"machine", {{"cpu", m.cpu}, {"logical_cores", m.logical_cores}}}};
}

}  // namespace caustica
