"""Ctrl-C stops a render (and a comparison) within a few seconds with KeyboardInterrupt, as it
would in a script or a notebook: the child Python process renders for two minutes unless the
SIGINT it is sent ends the render.
"""
import os
import signal
import subprocess
import sys
import textwrap
import time
import unittest

CHILD = textwrap.dedent("""
    import sys, time
    import caustica
    scene = caustica.load("cornell-glass", resolution=(64, 64))
    print("started", flush=True)
    try:
        if sys.argv[1] == "render":
            caustica.render(scene, "vcm", time=120, threads=1)
        else:
            caustica.compare(scene, ["pt", "vcm"], time=60, threads=1)
    except KeyboardInterrupt:
        print("KeyboardInterrupt", flush=True)
        sys.exit(3)
    print("finished", flush=True)
""")


class Interrupt(unittest.TestCase):
    def interrupt(self, what):
        child = subprocess.Popen([sys.executable, "-c", CHILD, what], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, env=os.environ)
        try:
            self.assertEqual(child.stdout.readline().strip(), "started")
            time.sleep(1.0)  # well into the render
            self.assertIsNone(child.poll())
            sent = time.monotonic()
            child.send_signal(signal.SIGINT)
            out, err = child.communicate(timeout=30)
            waited = time.monotonic() - sent
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        self.assertEqual(child.returncode, 3, err)
        self.assertEqual(out.strip(), "KeyboardInterrupt")
        self.assertLess(waited, 5)
        return waited

    def test_sigint_ends_render_with_keyboard_interrupt(self):
        self.interrupt("render")

    def test_sigint_ends_compare_with_keyboard_interrupt(self):
        self.interrupt("compare")


if __name__ == "__main__":
    unittest.main(verbosity=2)
