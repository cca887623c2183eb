#!/usr/bin/env python3
"""Fit adaptive-vcm's fixed cost model (src/integrators/bidir/adaptive_plan.cpp, CostModel).

Renders bpt and vcm at several light-path counts and connection counts on a few scenes, reads
each render's operation counts ("work_per_iteration") and pass times from its JSON statistics,
and fits microseconds per operation by least squares:

  camera pass  = camera_vertex * camera vertices + connection * connections
                 + merge_query * merge queries + photon * photons
  light pass   = light_path * light paths + light_vertex * light vertices   (ppm: no lens
                 connections)
               + lens_connection * light vertices                           (bpt, vcm)
  pt iteration = path_tracing_vertex * camera vertices (of bpt's camera subpaths, the same paths)

Run on an otherwise idle machine (the model is per thread: times are multiplied by --threads):

  scripts/fit_cost_model.py --caustica build/apps/caustica/caustica [--spp 8] [--threads 1]
      [--scenes door-ajar,...|all] [--out fit.json]

Prints the fitted costs, each scene's own fit, and the relative error of the pooled fit per
render. Only the ratios between the costs matter to the choice (a candidate's score is its
relative variance times its predicted time, compared with the others').
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

SCENES = {
    "door-ajar": ("scenes/door-ajar.pbrt", "160x120"),
    "cornell-box": ("scenes/pbrt-v4/cornell-box/scene-v4.pbrt", "160x160"),
    "veach-bidir": ("scenes/pbrt-v4/veach-bidir/scene-v4.pbrt", "160x160"),
    "water-caustic": ("scenes/pbrt-v4/water-caustic/scene-v4.pbrt", "160x160"),
    "mis-plates": ("scenes/mis-plates.pbrt", "160x107"),
    "cornell-caustics": ("scenes/cornell-caustics.pbrt", "160x160"),
}
# The rest of the equal-time table's scenes (--scenes all).
MORE_SCENES = {
    "material-spheres": ("scenes/material-spheres.pbrt", "160x90"),
    "mirror-caustic": ("scenes/mirror-caustic.pbrt", "160x120"),
    "point-room": ("scenes/point-room.pbrt", "160x120"),
    "sun-glass": ("scenes/sun-glass.pbrt", "160x120"),
    "coffee": ("scenes/pbrt-v4/coffee/scene-v4.pbrt", "160x200"),
    "cornell-spot-textured": ("scenes/pbrt-v4/cornell-spot-textured/scene-v4.pbrt", "160x160"),
    "material-testball": ("scenes/pbrt-v4/material-testball/scene-v4.pbrt", "160x90"),
    "veach-mis": ("scenes/pbrt-v4/veach-mis/scene-v4.pbrt", "160x90"),
}
LIGHT_PATH_FACTORS = (0.25, 1.0, 2.0)


def render(exe, scene, resolution, integrator, spp, extra, tmp, threads):
    out = os.path.join(tmp, "fit.exr")
    cmd = [exe, "render", scene, "--integrator", integrator, "--spp", str(spp), "--threads",
           str(threads), "--resolution", resolution, "--seed", "1", "--outfile", out] + extra
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(tmp, "fit.json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("--caustica", default="build/apps/caustica/caustica")
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--out", help="write every render's counts and times as JSON")
    ap.add_argument("--extra", action="append", default=[],
                    help="another scene as NAME=FILE@WxH (repeatable; add NAME to --scenes)")
    args = ap.parse_args()
    for e in args.extra:
        name, rest = e.split("=", 1)
        path, res = rest.rsplit("@", 1)
        SCENES[name] = (path, res)
    SCENES.update(MORE_SCENES)
    if args.scenes == "all":
        args.scenes = ",".join(SCENES)
    th = args.threads

    rows = []  # (scene, counts..., camera_ms, light_ms)
    pt_rows = []
    ppm_rows = []  # light passes without lens connections
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenes.split(","):
            scene, res = SCENES[name]
            w, h = map(int, res.split("x"))
            for integrator in ("bpt", "vcm"):
                for connections in (1, 4):
                    for factor in LIGHT_PATH_FACTORS:
                        paths = max(1, int(factor * w * h))
                        d = render(args.caustica, scene, res, integrator, args.spp,
                                   ["--connections", str(connections), "--light-paths",
                                    str(paths)], tmp, th)
                        b = d["bidir"]
                        wk = b["work_per_iteration"]
                        rows.append({
                            "scene": name, "integrator": integrator,
                            "connections": connections, "light_paths": paths,
                            "camera_vertices": wk["camera_vertices"],
                            "connections_made": wk["connections"],
                            "merge_queries": wk["merge_queries"], "photons": wk["photons"],
                            "light_vertices": wk["light_vertices"],
                            "light_paths_traced": wk["light_paths"],
                            "camera_ms": th * b["camera_paths_ms_per_iteration"],
                            "light_ms": th * b["light_paths_ms_per_iteration"]})
                        print(f"{name} {integrator} c={connections} n={paths}: camera "
                              f"{rows[-1]['camera_ms']:.1f} ms, light {rows[-1]['light_ms']:.1f} ms",
                              file=sys.stderr)
            for factor in LIGHT_PATH_FACTORS:
                paths = max(1, int(factor * w * h))
                d = render(args.caustica, scene, res, "ppm", args.spp,
                           ["--light-paths", str(paths)], tmp, th)
                b = d["bidir"]
                wk = b["work_per_iteration"]
                ppm_rows.append({"scene": name, "light_paths": wk["light_paths"],
                                 "light_vertices": wk["light_vertices"],
                                 "light_ms": th * b["light_paths_ms_per_iteration"]})
            d = render(args.caustica, scene, res, "pt", args.spp, [], tmp, th)
            vertices = np.mean([r["camera_vertices"] for r in rows
                                if r["scene"] == name and r["integrator"] == "bpt"])
            pt_ms = th * 1e3 * d["seconds"] / d["iterations"]
            pt_rows.append({"scene": name, "pt_ms": pt_ms, "camera_vertices": vertices})

    def fit(subset):
        a = np.array([[r["camera_vertices"], r["connections_made"], r["merge_queries"],
                       r["photons"]] for r in subset])
        y = np.array([r["camera_ms"] for r in subset]) * 1e3
        # Relative least squares: each render weighs by its own time, so small and large
        # renders count alike.
        wgt = 1 / y
        cam, *_ = np.linalg.lstsq(a * wgt[:, None], y * wgt, rcond=None)
        # The light pass without lens connections (ppm's), per path and per vertex, then what
        # bpt's and vcm's lens connections add per vertex.
        ppm = [r for r in ppm_rows if r["scene"] in {x["scene"] for x in subset}]
        la = np.array([[r["light_paths"], r["light_vertices"]] for r in ppm])
        ly = np.array([r["light_ms"] for r in ppm]) * 1e3
        light, *_ = np.linalg.lstsq(la / ly[:, None], np.ones(len(ly)), rcond=None)
        lv = np.array([r["light_vertices"] for r in subset])
        rest = np.array([r["light_ms"] * 1e3 - light[0] * r["light_paths_traced"]
                         - light[1] * r["light_vertices"] for r in subset])
        ly = np.array([r["light_ms"] for r in subset]) * 1e3
        lens = float(np.sum(lv * rest / ly**2) / np.sum((lv / ly) ** 2))
        pred = a @ cam
        light_err = np.abs(la @ light / (np.array([r["light_ms"] for r in ppm]) * 1e3) - 1)
        return cam, (light[0], light[1], lens), np.abs(pred / y - 1), light_err

    cam, light, err, light_err = fit(rows)
    pt = [r["pt_ms"] * 1e3 / r["camera_vertices"] for r in pt_rows]
    result = {"camera_vertex": cam[0], "connection": cam[1], "merge_query": cam[2],
              "photon": cam[3], "light_path": light[0], "light_vertex": light[1],
              "lens_connection": light[2],
              "path_tracing_vertex": float(np.median(pt)),
              "camera_pass_relative_error_median": float(np.median(err)),
              "camera_pass_relative_error_max": float(np.max(err)),
              "light_pass_relative_error_median": float(np.median(light_err)),
              "light_pass_relative_error_max": float(np.max(light_err))}
    print(json.dumps(result, indent=2))
    for name in args.scenes.split(","):
        c, l, e, _ = fit([r for r in rows if r["scene"] == name])
        lp = [r for r in ppm_rows if r["scene"] == name]
        per_path = np.median([1e3 * r["light_ms"] / r["light_paths"] for r in lp])
        pooled = np.median([(light[0] * r["light_paths"] + light[1] * r["light_vertices"])
                            / (1e3 * r["light_ms"]) for r in lp])
        p = [x["pt_ms"] * 1e3 / x["camera_vertices"] for x in pt_rows if x["scene"] == name][0]
        print(f"{name}: camera vertex {c[0]:.3f}, connection {c[1]:.3f}, merge query "
              f"{c[2]:.3f}, photon {c[3]:.4f}, pt vertex {p:.3f}, lens connection {l[2]:.3f} "
              f"us; ppm's light pass "
              f"{per_path:.3f} us per path at {lp[0]['light_vertices'] / lp[0]['light_paths']:.2f} "
              f"vertices, the pooled fit predicts {pooled:.2f}x of it")
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"fit": result, "renders": rows, "pt": pt_rows, "ppm": ppm_rows}, f,
                      indent=1)


if __name__ == "__main__":
    main()
