#!/usr/bin/env bash
# Quick start (b): install dependencies, build, run every test through CTest.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
# chromium: the HTML report is tested in a headless browser.
"$root/scripts/install-deps.sh" chromium
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure --parallel "$(nproc)" "$@"
