"""scripts/equal_time_summary.py: the README's equal-time table from compare's results.json, with
a per-seed column (adaptive-vcm over the best fixed integrator of the same seed) when the runs
were repeated (RUNS=N)."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "equal_time_summary.py")


def summary(integrator, seeds, relmse):
    median = sorted(relmse)[(len(relmse) - 1) // 2]
    return {"integrator": integrator, "iterations": 10, "runs": len(seeds), "seeds": seeds,
            "relmse_runs": relmse, "errors": {"relmse": median, "relmse_trimmed": median / 2}}


def write(folder, name, runs, summaries):
    os.makedirs(os.path.join(folder, name))
    history = [{"light_path_factor": 0.5, "connections": 0, "merge_fraction": 0.25,
                "path_trace_fraction": 0.0, "stop_fraction": 0.0}]
    results = {"runs_per_integrator": runs, "summary": summaries,
               "runs": [{"integrator": "adaptive-vcm",
                         "stats": {"adaptive": {"history": history}}}]}
    with open(os.path.join(folder, name, "results.json"), "w") as f:
        json.dump(results, f)


class EqualTimeSummary(unittest.TestCase):
    def table(self, folder, *names):
        run = subprocess.run([sys.executable, SCRIPT, folder, *names], capture_output=True,
                             text=True, timeout=60)
        self.assertEqual(run.returncode, 0, run.stderr)
        return [line for line in run.stdout.splitlines() if line.startswith("| ")]

    def test_several_runs_add_the_per_seed_ratio_to_the_best_fixed_of_that_seed(self):
        with tempfile.TemporaryDirectory() as folder:
            # Seed 1: bpt is best (2.0), seed 2: pt (1.0), seed 3: bpt (4.0).
            write(folder, "room", 3, [
                summary("adaptive-vcm", [1, 2, 3], [3.0, 1.5, 2.0]),
                summary("pt", [1, 2, 3], [5.0, 1.0, 8.0]),
                summary("bpt", [1, 2, 3], [2.0, 3.0, 4.0])])
            header, row = self.table(folder, "room")
            self.assertIn("per seed", header)
            self.assertTrue(row.endswith("| 1.50 / 1.50 / 0.50 |"), row)
            # The medians: adaptive-vcm 2.0 against bpt's 3.0, the best fixed median.
            self.assertIn("0.67x / 0.67x", row)

    def test_one_run_keeps_the_table_as_it_was(self):
        with tempfile.TemporaryDirectory() as folder:
            write(folder, "room", 1, [summary("adaptive-vcm", [0], [1.0]),
                                      summary("vcm", [0], [2.0])])
            lines = self.table(folder, "room")
            self.assertNotIn("per seed", lines[0])
            self.assertEqual(lines[1].count("|"), 10, lines[1])
            self.assertIn("0.50x / 0.50x", lines[1])


if __name__ == "__main__":
    unittest.main()
