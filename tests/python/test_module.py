"""The caustica Python module: images, determinism, scenes, errors, metrics, files, compare.

Run by CTest with PYTHONPATH set to the build's python/ folder (tests/CMakeLists.txt).
"""
import os
import tempfile
import threading
import time
import unittest

import numpy as np

import caustica


def tiny(name="cornell", resolution=(12, 8), **kwargs):
    return caustica.load(name, resolution=resolution, **kwargs)


class Render(unittest.TestCase):
    def test_image_is_float32_height_width_rgb(self):
        image = caustica.render(tiny(), "pt", spp=1)
        self.assertEqual(image.shape, (8, 12, 3))
        self.assertEqual(image.dtype, np.float32)
        self.assertTrue(image.flags["C_CONTIGUOUS"])
        self.assertTrue(np.isfinite(image).all())
        self.assertGreater(image.mean(), 0)  # the Cornell box is lit

    def test_same_seed_same_bits_other_seed_other_noise(self):
        scene = tiny()
        a = caustica.render(scene, "vcm", spp=2, seed=7)
        b = caustica.render(scene, "vcm", spp=2, seed=7)
        c = caustica.render(scene, "vcm", spp=2, seed=8)
        self.assertTrue(np.array_equal(a, b))
        self.assertFalse(np.array_equal(a, c))

    def test_thread_count_does_not_change_the_image(self):
        scene = tiny()
        one = caustica.render(scene, "bpt", spp=2, threads=1)
        two = caustica.render(scene, "bpt", spp=2, threads=2)
        self.assertTrue(np.array_equal(one, two))

    def test_options_reach_the_integrator(self):
        scene = tiny()
        direct = caustica.render(scene, "pt", spp=2, max_depth=1)
        full = caustica.render(scene, "pt", spp=2)
        # Indirect light only adds energy.
        self.assertLess(direct.mean(), full.mean())
        balance = caustica.render(scene, "bpt", spp=2, mis="balance")
        power = caustica.render(scene, "bpt", spp=2, mis="power")
        self.assertFalse(np.array_equal(balance, power))
        self.assertFalse(np.array_equal(caustica.render(scene, "ppm", spp=2, radius=0.01),
                                        caustica.render(scene, "ppm", spp=2, radius=0.2)))

    def test_time_budget_renders_about_that_long(self):
        start = time.monotonic()
        image = caustica.render(tiny(), "pt", time=0.3)
        elapsed = time.monotonic() - start
        self.assertGreaterEqual(elapsed, 0.3)
        self.assertLess(elapsed, 5)
        self.assertEqual(image.shape, (8, 12, 3))

    def test_render_releases_the_gil(self):
        scene = tiny(resolution=(32, 32))
        worker = threading.Thread(target=caustica.render, args=(scene, "vcm"),
                                  kwargs={"time": 0.5, "threads": 1})
        worker.start()
        steps = 0
        while worker.is_alive():
            steps += 1
        worker.join()
        # With the GIL held for the whole render this loop would barely run.
        self.assertGreater(steps, 10000)

    def test_integrators_lists_the_registry(self):
        names = caustica.integrators()
        self.assertEqual(list(names)[:6], ["pt", "lt", "bpt", "ppm", "bpm", "vcm"])
        for name, description in names.items():
            self.assertIsInstance(description, str)
            self.assertGreater(len(description), 10)
        for name in names:  # every listed name renders
            self.assertEqual(caustica.render(tiny(resolution=(4, 4)), name, spp=1).shape,
                             (4, 4, 3))


class Scenes(unittest.TestCase):
    def test_load_applies_resolution_and_max_depth(self):
        scene = caustica.load("cornell-glass", resolution=(20, 10), max_depth=3)
        self.assertEqual(scene.resolution, (20, 10))
        self.assertEqual(scene.max_depth, 3)
        self.assertEqual(scene.name, "cornell-glass")
        self.assertEqual(caustica.load("cornell-glass").max_depth, 10)

    def test_builtin_scenes_are_listed_and_load(self):
        names = [name for name, _ in caustica.scenes()]
        self.assertIn("cornell-glass", names)
        self.assertEqual(tiny(names[0], resolution=(4, 4)).resolution, (4, 4))


class Errors(unittest.TestCase):
    def test_missing_file_and_unknown_name_raise_load_error(self):
        self.assertTrue(issubclass(caustica.LoadError, ValueError))
        with self.assertRaisesRegex(caustica.LoadError, "no such file"):
            caustica.load("/nonexistent/scene.pbrt")
        with self.assertRaisesRegex(caustica.LoadError, "unknown scene 'no-such-scene'"):
            caustica.load("no-such-scene")
        with tempfile.TemporaryDirectory() as folder:
            with self.assertRaisesRegex(caustica.LoadError, "is a directory"):
                caustica.load(folder)

    def test_malformed_pbrt_names_file_line_and_column(self):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "bad.pbrt")
            with open(path, "w") as f:
                f.write('Camera "perspective" "float fov" [ 45 ]\nWorldBegin\n'
                        'LightSource "point" "rgb I" [ 1 1 1 ]\n'
                        'Shape "sphere" "float radius" [ "oops" ]\n')
            with self.assertRaises(caustica.LoadError) as caught:
                caustica.load(path)
            message = str(caught.exception)
            self.assertRegex(message, "^" + path + r":4:\d+: error: ")
            self.assertEqual((caught.exception.file, caught.exception.line), (path, 4))
            self.assertGreater(caught.exception.column, 1)

    def test_bad_load_arguments(self):
        with self.assertRaisesRegex(ValueError, "max_depth"):
            caustica.load("cornell", max_depth=256)
        with self.assertRaisesRegex(ValueError, "resolution width"):
            caustica.load("cornell", resolution=(0, 8))
        with self.assertRaises(TypeError):
            caustica.load("cornell", resolution="16x16")

    def test_unknown_option_and_bad_values_raise_value_error(self):
        scene = tiny(resolution=(4, 4))
        bad = [
            ({"integrator": "nope"}, "unknown integrator 'nope'"),
            ({"bogus": 1}, "unknown option 'bogus'"),
            ({"spp": 0}, "spp must be"),
            ({"time": 0}, "time must be"),
            ({"time": float("nan")}, "time must be"),
            ({"time": 31 * 24 * 3600}, "time must be"),
            ({"seed": -1}, "seed must be"),
            ({"threads": 1025}, "threads must be"),
            ({"mis": "heuristic"}, "mis must be one of balance, power"),
            ({"max_depth": -1}, "max_depth must be"),
            ({"light_paths": 0}, "light_paths must be"),
            ({"radius": 0}, "radius must be"),
            ({"radius": float("inf")}, "radius must be"),
            ({"radius_alpha": 1.01}, "radius_alpha must be"),
        ]
        for kwargs, message in bad:
            with self.subTest(**kwargs):
                with self.assertRaisesRegex(ValueError, message):
                    caustica.render(scene, **{"spp": 1, **kwargs})
        with self.assertRaises(TypeError):
            caustica.render(scene, spp=True)
        with self.assertRaises(TypeError):
            caustica.render(scene, spp=1.0)

    def test_the_range_limits_themselves_are_accepted(self):
        scene = tiny(resolution=(4, 4))
        caustica.render(scene, "vcm", spp=1, seed=2**64 - 1, max_depth=0, radius_alpha=1,
                        light_paths=1, radius=1e12, mis=None)


class Metrics(unittest.TestCase):
    def setUp(self):
        rng = np.random.default_rng(1)
        self.ref = rng.random((9, 7, 3), dtype=np.float32)
        self.img = self.ref + rng.normal(0, 0.1, self.ref.shape).astype(np.float32)

    def test_mse_and_relmse_follow_their_formulas(self):
        diff = self.img.astype(np.float64) - self.ref
        self.assertAlmostEqual(caustica.metrics.mse(self.img, self.ref), np.mean(diff ** 2),
                               places=12)
        expected = np.mean(diff ** 2 / (self.ref.astype(np.float64) ** 2 + 0.01))
        self.assertAlmostEqual(caustica.metrics.relmse(self.img, self.ref), expected, places=12)
        self.assertEqual(caustica.metrics.relmse(self.ref, self.ref), 0.0)

    def test_ssim_is_one_for_identical_images_and_less_otherwise(self):
        self.assertAlmostEqual(caustica.metrics.ssim(self.ref, self.ref), 1.0, places=9)
        self.assertLess(caustica.metrics.ssim(self.img, self.ref), 0.99)

    def test_sizes_must_match(self):
        with self.assertRaises(ValueError):
            caustica.metrics.relmse(self.img, self.ref[:-1])
        with self.assertRaisesRegex(ValueError, "shape"):
            caustica.metrics.ssim(self.img[..., :2], self.ref[..., :2])


class Files(unittest.TestCase):
    def test_exr_round_trip_is_exact_and_png_is_srgb(self):
        rng = np.random.default_rng(2)
        image = (rng.random((5, 6, 3)) * 3).astype(np.float32)
        with tempfile.TemporaryDirectory() as folder:
            exr = os.path.join(folder, "a.exr")
            caustica.write(exr, image)
            self.assertTrue(np.array_equal(caustica.read(exr), image))
            png = os.path.join(folder, "a.png")
            caustica.write(png, image, exposure=-2)
            back = caustica.read(png)  # decoded from sRGB to linear
            np.testing.assert_allclose(back, np.clip(image / 4, 0, 1), atol=0.01)
            with self.assertRaisesRegex(ValueError, "use .exr, .png or .pfm"):
                caustica.write(os.path.join(folder, "a.tiff"), image)
            with self.assertRaises(RuntimeError):
                caustica.read(os.path.join(folder, "missing.exr"))


class Compare(unittest.TestCase):
    def test_results_against_a_given_reference(self):
        scene = tiny()
        reference = caustica.render(scene, "vcm", spp=16, seed=99)
        results = caustica.compare(scene, ["pt", "vcm"], time=0.2, reference=reference,
                                   threads=1)
        self.assertEqual(set(results), {"scene", "seconds_per_integrator", "threads",
                                        "runs_per_integrator", "reference", "interrupted",
                                        "summary", "runs"})
        self.assertEqual(results["runs_per_integrator"], 1)
        self.assertEqual(results["scene"], "cornell")
        self.assertEqual(results["threads"], 1)
        self.assertFalse(results["interrupted"])
        self.assertEqual([row["integrator"] for row in results["summary"]], ["pt", "vcm"])
        for row, run in zip(results["summary"], results["runs"]):
            self.assertGreater(run["iterations"], 0)
            self.assertEqual(row["errors"], run["snapshots"][-1]["errors"])
        self.assertEqual(results["summary"][0]["speedup_vs_pt"], 1.0)

    def test_several_runs_keep_the_median_and_list_every_run(self):
        scene = tiny()
        reference = caustica.render(scene, "vcm", spp=16, seed=99)
        results = caustica.compare(scene, "pt", time=0.1, reference=reference, threads=1,
                                   seed=4, runs=3)
        self.assertEqual(results["runs_per_integrator"], 3)
        row, run = results["summary"][0], results["runs"][0]
        self.assertEqual(row["seeds"], [4, 5, 6])
        self.assertEqual([r["seed"] for r in run["repeats"]], [4, 5, 6])
        self.assertEqual(sorted(row["relmse_runs"])[1], row["relmse_median"])
        self.assertEqual(row["errors"]["relmse"], row["relmse_median"])
        self.assertIn(run["seed"], [4, 5, 6])
        with self.assertRaisesRegex(ValueError, "runs"):
            caustica.compare(scene, "pt", time=0.1, reference=reference, runs=0)

    def test_without_a_reference_one_is_rendered_first(self):
        results = caustica.compare(tiny(), "pt", time=0.1, threads=1)
        self.assertRegex(results["reference"], r"^vcm, \d+ iterations, \d+ s, rendered by compare$")
        self.assertEqual(len(results["runs"]), 1)

    def test_bad_arguments(self):
        scene = tiny()
        with self.assertRaisesRegex(ValueError, "integrators is empty"):
            caustica.compare(scene, [], time=1)
        with self.assertRaisesRegex(ValueError, "unknown integrator"):
            caustica.compare(scene, ["pt", "xyz"], time=1)
        with self.assertRaisesRegex(ValueError, "reference is 3x3 but the scene renders 12x8"):
            caustica.compare(scene, ["pt"], time=1, reference=np.zeros((3, 3, 3)))
        with self.assertRaisesRegex(ValueError, "time must be"):
            caustica.compare(scene, ["pt"], time=-1)


if __name__ == "__main__":
    unittest.main(verbosity=2)
