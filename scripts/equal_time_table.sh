#!/usr/bin/env bash
# The README's "Let caustica choose" measurement: every scene in scenes/ at 160 pixels wide,
# equal time per integrator on 2 threads (caustica compare, seed 0) against a vcm reference
# (seed 7919, 1 thread; two references render at once), then one markdown table.
#
#   scripts/equal_time_table.sh OUT [SECONDS] [REFERENCE_SECONDS] [INTEGRATORS] [RESOLUTION]
#
# RESOLUTION: small (default: 160 pixels wide, the resolutions listed below) or native (each
# scene's own Film resolution: 2-16x the pixels, so fewer iterations and fewer probes in the
# same time).
# RUNS=N in the environment: N runs per integrator (compare --runs; seeds 0 to N - 1, the
# integrators taking turns), each cell then the median run's; N times as long.
# References already in OUT/refs are kept (delete them after a change to the integrators'
# images). Run it on an otherwise idle machine: the compare runs are timed.
set -euo pipefail
out=${1:?usage: equal_time_table.sh OUT [SECONDS] [REFERENCE_SECONDS] [INTEGRATORS]}
seconds=${2:-20}
ref_seconds=${3:-300}
integrators=${4:-pt,bpt,ppm,vcm,adaptive-vcm}
resolution=${5:-small}
[[ $resolution == small || $resolution == native ]] || {
  echo "RESOLUTION is small or native" >&2
  exit 2
}
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${CAUSTICA:-$root/build/apps/caustica/caustica}
mkdir -p "$out/refs"

# name file resolution
scenes=(
  "cornell-caustics scenes/cornell-caustics.pbrt 160x160"
  "door-ajar scenes/door-ajar.pbrt 160x120"
  "material-spheres scenes/material-spheres.pbrt 160x90"
  "mirror-caustic scenes/mirror-caustic.pbrt 160x120"
  "mis-plates scenes/mis-plates.pbrt 160x107"
  "point-room scenes/point-room.pbrt 160x120"
  "sun-glass scenes/sun-glass.pbrt 160x120"
  "coffee scenes/pbrt-v4/coffee/scene-v4.pbrt 160x200"
  "cornell-box scenes/pbrt-v4/cornell-box/scene-v4.pbrt 160x160"
  "cornell-spot-textured scenes/pbrt-v4/cornell-spot-textured/scene-v4.pbrt 160x160"
  "material-testball scenes/pbrt-v4/material-testball/scene-v4.pbrt 160x90"
  "veach-bidir scenes/pbrt-v4/veach-bidir/scene-v4.pbrt 160x160"
  "veach-mis scenes/pbrt-v4/veach-mis/scene-v4.pbrt 160x90"
  "water-caustic scenes/pbrt-v4/water-caustic/scene-v4.pbrt 160x160"
)

# The --resolution option of a scene's runs (none at its own resolution).
resolution_of() {
  [[ $resolution == small ]] && echo "--resolution $1"
  return 0
}

reference() {
  local name=$1 file=$2 res=$3
  [[ -f "$out/refs/$name.exr" ]] && return 0
  # shellcheck disable=SC2046
  "$bin" reference "$root/$file" --integrator vcm --time "$ref_seconds" --threads 1 \
    $(resolution_of "$res") --outfile "$out/refs/$name.exr" 2>"$out/refs/$name.log"
}

# References, two at a time.
running=0
for s in "${scenes[@]}"; do
  read -r name file res <<<"$s"
  reference "$name" "$file" "$res" &
  running=$((running + 1))
  if ((running == 2)); then
    wait -n
    running=$((running - 1))
  fi
done
wait

for s in "${scenes[@]}"; do
  read -r name file res <<<"$s"
  echo "compare $name" >&2
  # shellcheck disable=SC2046
  "$bin" compare "$root/$file" $(resolution_of "$res") --time "$seconds" --threads 2 --seed 0 \
    --runs "${RUNS:-1}" --integrators "$integrators" --reference "$out/refs/$name.exr" \
    --out "$out/$name" \
    >"$out/$name.log" 2>&1
done

python3 "$root/scripts/equal_time_summary.py" "$out" "${scenes[@]%% *}"
