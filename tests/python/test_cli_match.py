"""The module renders what the command line renders: the same settings give the same bits, and
compare() returns what `caustica compare` writes to results.json.

CAUSTICA_BINARY names the command line binary and CAUSTICA_SCENES the scenes/ folder
(tests/CMakeLists.txt sets both).
"""
import json
import os
import subprocess
import tempfile
import unittest

import numpy as np

import caustica

BINARY = os.environ["CAUSTICA_BINARY"]
SCENES = os.environ["CAUSTICA_SCENES"]


def cli_render(folder, scene, flags):
    out = os.path.join(folder, "cli")
    subprocess.run([BINARY, "render", scene, "--quiet", "--outfile", out + ".exr", *flags],
                   check=True, stdout=subprocess.DEVNULL)
    return caustica.read(out + ".exr")


class SameBitsAsTheCommandLine(unittest.TestCase):
    # (scene, load() arguments, render() arguments, the same as flags); the resolutions are
    # not square, so a transposed image could not pass.
    CASES = [
        ("cornell-glass", {"resolution": (16, 12)},
         {"integrator": "vcm", "spp": 2, "seed": 3},
         ["--resolution", "16x12", "--integrator", "vcm", "--spp", "2", "--seed", "3"]),
        ("cornell-glass", {"resolution": (12, 16), "max_depth": 3},
         {"integrator": "pt", "spp": 2, "seed": 1, "mis": "balance"},
         ["--resolution", "12x16", "--max-depth", "3", "--integrator", "pt", "--spp", "2",
          "--seed", "1", "--mis", "balance"]),
        ("cornell-glossy", {"resolution": (16, 12)},
         {"integrator": "ppm", "spp": 2, "radius": 0.05, "radius_alpha": 0.5,
          "light_paths": 300},
         ["--resolution", "16x12", "--integrator", "ppm", "--spp", "2", "--radius", "0.05",
          "--radius-alpha", "0.5", "--light-paths", "300"]),
        ("cornell", {"resolution": (16, 12)},
         {"integrator": "bpt", "spp": 1, "max_depth": 5, "seed": 2**64 - 1},
         ["--resolution", "16x12", "--integrator", "bpt", "--spp", "1", "--max-depth", "5",
          "--seed", str(2**64 - 1)]),
        # A pbrt-v4 file: its own filter (gaussian) and its own spp, which both sides default to.
        (os.path.join(SCENES, "cornell-caustics.pbrt"), {"resolution": (16, 12)},
         {"integrator": "lt", "max_depth": 4},
         ["--resolution", "16x12", "--integrator", "lt", "--max-depth", "4"]),
    ]

    def test_render_matches_the_cli_bit_for_bit(self):
        with tempfile.TemporaryDirectory() as folder:
            for scene_name, load_args, render_args, flags in self.CASES:
                with self.subTest(scene=scene_name, **render_args):
                    scene = caustica.load(scene_name, **load_args)
                    image = caustica.render(scene, threads=2, **render_args)
                    expected = cli_render(folder, scene_name, flags + ["--threads", "2"])
                    self.assertEqual(image.shape, expected.shape)
                    self.assertEqual(image.dtype, expected.dtype)
                    self.assertTrue(np.array_equal(image, expected),
                                    "max difference %g" % np.abs(image - expected).max())

    def test_default_spp_is_the_scenes(self):
        # cornell-caustics.pbrt asks for its own spp; an image with one more or fewer iteration
        # would differ.
        scene = caustica.load(os.path.join(SCENES, "cornell-caustics.pbrt"), resolution=(8, 8))
        self.assertIsNotNone(scene.spp)
        with tempfile.TemporaryDirectory() as folder:
            fewer = caustica.render(scene, "pt", spp=scene.spp - 1)
            default = caustica.render(scene, "pt")
            expected = cli_render(folder, scene.name, ["--resolution", "8x8", "--integrator", "pt"])
            self.assertTrue(np.array_equal(default, expected))
            self.assertFalse(np.array_equal(fewer, expected))


def same_structure(a, b):
    """Same keys in every dict, same lengths of lists, same types of leaves (numbers as one)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(
            same_structure(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(
            same_structure(x, y) for x, y in zip(a, b))
    number = (int, float)
    return type(a) == type(b) or (isinstance(a, number) and isinstance(b, number)
                                  and not isinstance(a, bool) and not isinstance(b, bool))


class CompareAsTheCommandLine(unittest.TestCase):
    def test_compare_returns_what_results_json_holds(self):
        scene = caustica.load("cornell", resolution=(16, 12))
        reference = caustica.render(scene, "vcm", spp=8, seed=5)
        with tempfile.TemporaryDirectory() as folder:
            ref_path = os.path.join(folder, "ref.exr")
            caustica.write(ref_path, reference)
            out = os.path.join(folder, "report")
            subprocess.run([BINARY, "compare", "cornell", "--resolution", "16x12", "--time", "0.2",
                            "--integrators", "pt,bpt", "--threads", "1", "--reference", ref_path,
                            "--out", out], check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            with open(os.path.join(out, "results.json")) as f:
                expected = json.load(f)
        results = caustica.compare(scene, ["pt", "bpt"], time=0.2, reference=reference, threads=1)
        self.assertTrue(same_structure(results, expected),
                        json.dumps(results)[:2000] + "\n" + json.dumps(expected)[:2000])
        for key in ("scene", "seconds_per_integrator", "threads", "interrupted"):
            self.assertEqual(results[key], expected[key])
        # Equal time gives about equal quality; a wrong reference or scene would not.
        for mine, theirs in zip(results["summary"], expected["summary"]):
            ratio = mine["errors"]["relmse"] / theirs["errors"]["relmse"]
            self.assertGreater(ratio, 0.2)
            self.assertLess(ratio, 5)


if __name__ == "__main__":
    unittest.main(verbosity=2)
