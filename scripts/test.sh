#!/usr/bin/env bash
# Quick start (b): install dependencies, build, run every test through CTest.
#  1. the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/), except
#     the headless-browser test; set CAUSTICA_SANITIZERS=0 to skip this stage. It builds at -O1
#     with line tables only (-g1): a third of the compile time of -O2 -g (tinygltf's translation
#     unit: 71 s against 223 s on a development machine), still enough for ASan's stack traces;
#  2. the whole suite on the Release build (build/). Its CTest summary is the last output.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
# chromium: the HTML report is tested in a headless browser; clang-format and git: the tree's
# formatting is a test (Format.TreeIsClangFormatClean).
"$root/scripts/install-deps.sh" chromium clang-format git
jobs="$(nproc)"
if [[ "${CAUSTICA_SANITIZERS:-1}" != 0 ]]; then
  cmake -S "$root" -B "$root/build-asan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCAUSTICA_SANITIZE=ON >/dev/null
  cmake --build "$root/build-asan" --parallel "$jobs" --target caustica caustica_tests
  (cd "$root/build-asan" && ctest --output-on-failure --parallel "$jobs" -E '^ReportBrowser')
fi
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure --parallel "$jobs" "$@"
