"""examples/which_algorithm.py runs and prints the README's table, one row per integrator."""
import os
import subprocess
import sys
import tempfile
import unittest

EXAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "which_algorithm.py")


class WhichAlgorithm(unittest.TestCase):
    def test_prints_one_table_row_per_integrator(self):
        with tempfile.TemporaryDirectory() as folder:
            run = subprocess.run(
                [sys.executable, EXAMPLE, "--resolution", "8x8", "--time", "0.1",
                 "--reference-time", "0.2", "--threads", "1", "--integrators", "pt,bpt,vcm",
                 "--plot", os.path.join(folder, "convergence.png")],
                capture_output=True, text=True, timeout=120)
            self.assertEqual(run.returncode, 0, run.stderr)
            rows = [line for line in run.stdout.splitlines() if line.startswith("| `")]
            self.assertEqual([row.split("`")[1] for row in rows], ["pt", "bpt", "vcm"])
            self.assertTrue(all(row.count("|") == 9 for row in rows), rows)
            try:
                import matplotlib  # noqa: F401
                self.assertTrue(os.path.getsize(os.path.join(folder, "convergence.png")) > 0)
            except ImportError:
                self.assertIn("matplotlib is not installed", run.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
