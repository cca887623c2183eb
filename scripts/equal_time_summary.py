#!/usr/bin/env python3
"""The markdown table of scripts/equal_time_table.sh: per scene, relMSE / trimmed relMSE of each
integrator (the best fixed one in bold), adaptive-vcm over the best fixed one, what adaptive-vcm
chose after its last probe, and the iterations of vcm and adaptive-vcm. With several runs per
integrator (RUNS=N) every figure is of each integrator's median run by relMSE, and a last column
gives adaptive-vcm's relMSE over the best fixed integrator's of the same seed, seed by seed.

    equal_time_summary.py OUT SCENE...
"""
import json
import sys

FIXED = ["pt", "bpt", "ppm", "vcm"]


def fmt(x):
    return f"{x:.3g}"


def load(out, name):
    with open(f"{out}/{name}/results.json") as f:
        return json.load(f)


def per_seed(summary, fixed):
    """adaptive-vcm's relMSE over the best fixed integrator's, seed by seed ("a / b / c")."""
    by = {s["integrator"]: dict(zip(s["seeds"], s["relmse_runs"])) for s in summary
          if "seeds" in s}
    if "adaptive-vcm" not in by:
        return ""
    ratios = []
    for seed, value in by["adaptive-vcm"].items():
        best = min((by[i][seed] for i in fixed if i in by and seed in by[i]), default=None)
        ratios.append(f"{value / best:.2f}" if best else "-")
    return " / ".join(ratios)


def row(out, name, several):
    results = load(out, name)
    errors = {s["integrator"]: s["errors"] for s in results["summary"]}
    iterations = {s["integrator"]: s["iterations"] for s in results["summary"]}
    fixed = [i for i in FIXED if i in errors]
    best = min(fixed, key=lambda i: errors[i]["relmse"])
    best_trim = min(errors[i]["relmse_trimmed"] for i in fixed)
    cells = []
    for i in FIXED + ["adaptive-vcm"]:
        if i not in errors:
            cells.append("")
            continue
        e = errors[i]
        text = f"{fmt(e['relmse'])} / {fmt(e['relmse_trimmed'])}"
        cells.append(f"**{fmt(e['relmse'])}** / {fmt(e['relmse_trimmed'])}" if i == best else text)
    chose, vs = "", ""
    if "adaptive-vcm" in errors:
        a = errors["adaptive-vcm"]
        vs = f"{a['relmse'] / errors[best]['relmse']:.2f}x / {a['relmse_trimmed'] / best_trim:.2f}x"
        run = next(r for r in results["runs"] if r["integrator"] == "adaptive-vcm")
        last = run["stats"]["adaptive"]["history"][-1]
        chose = (f"{last['light_path_factor']:g}, {last['connections']}, "
                 f"{100 * last['merge_fraction']:.0f}%, {100 * last['path_trace_fraction']:.0f}%, "
                 f"{100 * last.get('stop_fraction', 0):.0f}%")
    its = f"{iterations.get('vcm', '')} / {iterations.get('adaptive-vcm', '')}"
    extra = [per_seed(results["summary"], fixed)] if several else []
    return f"| {name} | " + " | ".join(cells + [vs, chose, its] + extra) + " |"


def main():
    out, names = sys.argv[1], sys.argv[2:]
    several = False
    for name in names:
        try:
            several = several or load(out, name).get("runs_per_integrator", 1) > 1
        except (OSError, ValueError):
            pass
    print("| scene | `pt` | `bpt` | `ppm` | `vcm` | `adaptive-vcm` | vs best (relMSE / trimmed) "
          "| chose (light paths / pixel, connections, merging, path tracing, photon mapping) "
          "| iterations (`vcm` / `adaptive-vcm`) |" +
          (" per seed, vs the best fixed of that seed |" if several else ""))
    print("|---|---|---|---|---|---|---|---|---|" + ("---|" if several else ""))
    for name in names:
        try:
            print(row(out, name, several))
        except (OSError, KeyError, StopIteration, ValueError) as e:
            print(f"| {name} | (no result: {e}) |||||||| ")


if __name__ == "__main__":
    main()
