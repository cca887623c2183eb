#!/usr/bin/env bash
# Quick start (a): install dependencies, build, render the embedded default scene to
# caustica.exr, caustica.png and caustica.json in the current directory.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
"$root/build/apps/caustica/caustica" render "$@"
