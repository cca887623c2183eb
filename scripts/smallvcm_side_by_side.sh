#!/usr/bin/env bash
# caustica against SmallVCM (the reference VCM implementation, MIT) on cornell-glass, side by side
# in one run: the speed targets of the README's "Performance" section.
#
#   scripts/smallvcm_side_by_side.sh SMALLVCM_DIR [ROUNDS] [ITERATIONS] [THREADS]
#
# SMALLVCM_DIR holds SmallVCM's src/smallvcm.cxx with a scene 4 "small spheres + ceiling (area)":
# the same scene as caustica's built-in cornell-glass (upstream SmallVCM has scenes 0-3; the
# copy this project measures against adds scene 4 to src/config.hxx). It is built here as its
# README says (g++ -O3 -march=native -fopenmp); nothing of it is committed.
#
# Each round alternates SmallVCM vcm, caustica vcm, SmallVCM pt, caustica pt: ITERATIONS
# iterations (default 16) at 512x512, path length 10 = --max-depth 9, THREADS threads (default
# 2; OMP_NUM_THREADS for SmallVCM), wall seconds of the whole process. In the same window,
# `caustica bench` measures caustica's rays per iteration and the raw Embree rate of the scene,
# so the table also says what the rays alone cost at Embree's incoherent rate: the floor under
# any caustica iteration that traces those rays one by one. Medians over ROUNDS (default 3).
#
# Whole-process seconds include start-up, the first iteration's allocations and writing the
# image, which the targets ("per iteration") do not. So each round also runs both programs for
# one iteration, and a second table gives each round's (T(ITERATIONS) - T(1)) / (ITERATIONS - 1):
# the seconds of one iteration beyond the first, and their ratio per round.
set -euo pipefail
src=${1:?usage: smallvcm_side_by_side.sh SMALLVCM_DIR [ROUNDS] [ITERATIONS] [THREADS]}
rounds=${2:-3}
iterations=${3:-16}
threads=${4:-2}
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${CAUSTICA:-$root/build/apps/caustica/caustica}
[[ -f "$src/src/smallvcm.cxx" ]] || { echo "no $src/src/smallvcm.cxx" >&2; exit 2; }
[[ -x "$bin" ]] || { echo "no $bin: build caustica first (scripts/build.sh)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "building SmallVCM" >&2
g++ -o "$work/smallvcm" "$src/src/smallvcm.cxx" -O3 -march=native -std=c++11 -fopenmp

echo "caustica bench (rays per iteration, raw Embree rate)" >&2
"$bin" bench --scenes cornell-glass --integrators pt,vcm --resolution 512x512 --iterations 4 \
  --runs 1 --threads "$threads" --max-depth 9 --json "$work/bench.json" -q >/dev/null

seconds() {  # wall seconds of a command, its output discarded
  local start=$EPOCHREALTIME
  "$@" >/dev/null 2>&1
  awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f\n", b - a }'
}
: >"$work/times"
for ((r = 1; r <= rounds; ++r)); do
  for a in vcm pt; do
    echo "round $r/$rounds: $a" >&2
    for n in "$iterations" 1; do
      t=$(cd "$work" && seconds env OMP_NUM_THREADS="$threads" ./smallvcm -s 4 -a "$a" -i "$n" \
        -o "$work/s.hdr")
      echo "smallvcm $a $n $t" >>"$work/times"
      t=$(seconds "$bin" render cornell-glass --integrator "$a" --spp "$n" \
        --threads "$threads" --max-depth 9 --outfile "$work/c.exr" -q)
      echo "caustica $a $n $t" >>"$work/times"
    done
  done
done

python3 - "$work/times" "$work/bench.json" "$iterations" "$threads" <<'EOF'
import json, statistics, sys
times, bench, iterations, threads = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
runs, ones = {}, {}
for line in open(times):
    who, algorithm, n, t = line.split()
    (runs if int(n) == iterations else ones).setdefault((who, algorithm), []).append(float(t))
b = json.load(open(bench))
print(f"# {b['machine']['cpu']}, {b['machine']['logical_cores']} logical cores; caustica "
      f"{b['build']['build_type']} {b['build']['commit']}; cornell-glass 512x512, "
      f"{iterations} iterations, --max-depth 9, {threads} threads; wall seconds, medians of "
      f"{len(runs[('smallvcm', 'vcm')])} alternating rounds\n")
print("| | rounds (s) | median (s) | caustica / SmallVCM | caustica rays per iteration "
      "| those rays at the raw Embree rate (ms) | half of SmallVCM's iteration (ms) |")
print("|---|---|---|---|---|---|---|")
for algorithm in ("vcm", "pt"):
    svcm = statistics.median(runs[("smallvcm", algorithm)])
    ours = statistics.median(runs[("caustica", algorithm)])
    r = next(x for x in b["results"] if x["integrator"] == algorithm)["per_thread_count"][0]
    rays = r["rays_per_second"] * r["ms_per_iteration"] / 1000
    floor_ms = 1000 * rays / r["embree_bound_rays_per_second"]
    target_ms = 1000 * svcm / iterations / 2
    for who, m in (("SmallVCM", svcm), ("caustica", ours)):
        cells = " / ".join(f"{t:.2f}" for t in runs[(who.lower(), algorithm)])
        extra = (f"| **{ours / svcm:.2f}** | {rays / 1e6:.2f} M | {floor_ms:.0f} | {target_ms:.0f} |"
                 if who == "caustica" else "| | | | |")
        print(f"| {who} `{algorithm}` | {cells} | {m:.2f} {extra}")
if iterations > 1:
    print(f"\nPer iteration beyond the first, (T({iterations}) - T(1)) / {iterations - 1}, each "
          "round on its own (seconds, SmallVCM / caustica: caustica / SmallVCM):\n")
    rounds = len(runs[("smallvcm", "vcm")])
    print("| | " + " | ".join(f"round {i + 1}" for i in range(rounds)) + " | median ratio |")
    print("|---" * (rounds + 2) + "|")
    for algorithm in ("vcm", "pt"):
        per = {who: [(a - b) / (iterations - 1) for a, b in
                     zip(runs[(who, algorithm)], ones[(who, algorithm)])]
               for who in ("smallvcm", "caustica")}
        ratios = [c / s for c, s in zip(per["caustica"], per["smallvcm"])]
        cells = " | ".join(f"{s:.3f} / {c:.3f}: {c / s:.2f}x"
                           for s, c in zip(per["smallvcm"], per["caustica"]))
        print(f"| `{algorithm}` | {cells} | **{statistics.median(ratios):.2f}** |")
EOF
