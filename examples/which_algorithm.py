#!/usr/bin/env python3
"""Reproduces the README's "Which algorithm?" table for one scene with the caustica module:
a long vcm reference, then an equal-time comparison of pt, lt, bpt, ppm and vcm against it,
printed as the README's Markdown table, and relMSE against time plotted when matplotlib is
installed.

The defaults are small so that it runs in about a minute on two cores:

    PYTHONPATH=build/python python3 examples/which_algorithm.py
    PYTHONPATH=build/python python3 examples/which_algorithm.py --scene cornell-caustics.pbrt \
        --resolution 512x512 --time 30 --reference-time 190 --threads 2   # the README's setup
"""
import argparse
import sys

import caustica


def parse_resolution(text):
    width, height = text.lower().split("x")
    return int(width), int(height)


def markdown_table(results):
    lines = ["| integrator | iterations | Mrays/s | RMSE | relMSE | relMSE (trimmed 0.1%) | SSIM "
             "| speed-up vs pt |", "|---|---|---|---|---|---|---|---|"]
    for row in results["summary"]:
        errors = row["errors"]
        speedup = row.get("speedup_vs_pt")
        lines.append("| `%s` | %d | %.2f | %.4f | %.4f | %.4f | %.3f | %s |" % (
            row["integrator"], row["iterations"], row["rays_per_second"] * 1e-6, errors["rmse"],
            errors["relmse"], errors["relmse_trimmed"], errors["ssim"],
            "%.2fx" % speedup if speedup is not None else "n/a"))
    return "\n".join(lines)


def plot_convergence(results, path):
    try:
        import matplotlib
        matplotlib.use("Agg")  # no display needed
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for run in results["runs"]:
        points = [(s["seconds"], s["errors"]["relmse"]) for s in run["snapshots"]
                  if s["seconds"] > 0 and s["errors"]["relmse"] > 0]
        ax.loglog(*zip(*points), marker="o", label=run["integrator"])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("relMSE")
    ax.set_title(results["scene"])
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print("convergence plot:", path, file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="cornell-glass", help="built-in name or file")
    parser.add_argument("--resolution", type=parse_resolution, default=(128, 128),
                        help="WxH (default 128x128)")
    parser.add_argument("--time", type=float, default=5, help="seconds per integrator (5)")
    parser.add_argument("--reference-time", type=float, default=30,
                        help="seconds for the vcm reference (30)")
    parser.add_argument("--integrators", default="pt,lt,bpt,ppm,vcm")
    parser.add_argument("--threads", type=int, default=0, help="0: all cores")
    parser.add_argument("--plot", default="convergence.png", help="where to save the plot")
    args = parser.parse_args()

    scene = caustica.load(args.scene, resolution=args.resolution)
    print("%s: %dx%d, max depth %d; reference: vcm for %g s" % (
        scene.name, *scene.resolution, scene.max_depth, args.reference_time), file=sys.stderr)
    # A seed of its own, so the reference's noise is independent of the compared runs'.
    reference = caustica.render(scene, "vcm", time=args.reference_time, seed=12345,
                                threads=args.threads)
    results = caustica.compare(scene, args.integrators.split(","), time=args.time,
                               reference=reference, threads=args.threads)
    print("### %s (%dx%d, max depth %d, %g s per integrator)\n" % (
        scene.name, *scene.resolution, scene.max_depth, args.time))
    print(markdown_table(results))
    plot_convergence(results, args.plot)


if __name__ == "__main__":
    main()
