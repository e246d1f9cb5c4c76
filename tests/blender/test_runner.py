"""The Blender add-on's command runner, without Blender: commands run in order with their output collected, a
failure stops the run with the command's own error line, steps may be computed from earlier results, and cancel
stops a running command.   python3 tests/blender/test_runner.py"""
import os
import pathlib
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "blender", "nec_blender"))
import runner  # noqa: E402  (no bpy in it)

PYTHON = sys.executable


def say(*lines, code=0):
    return [PYTHON, "-c", f"import sys; print({chr(10).join(lines)!r}); sys.exit({code})"]


class NecRunTest(unittest.TestCase):
    def test_runs_commands_in_order_and_computes_later_steps(self):
        with tempfile.TemporaryDirectory() as folder:
            marker = os.path.join(folder, "made")
            run = runner.NecRun([[PYTHON, "-c", f"open({marker!r}, 'w').write('3')"],
                                 lambda: [say(f"step {i}") for i in range(int(pathlib.Path(marker).read_text()))]])
            run.wait()
            self.assertEqual(run.lines, ["step 0", "step 1", "step 2"])
            self.assertEqual(run.poll(), ([], 0))

    def test_a_failure_stops_the_run_with_its_error_line(self):
        run = runner.NecRun([say("working", "nec: error: walk.bvh:3: bad channel count", code=1), say("never")])
        with self.assertRaises(runner.NecError) as raised:
            run.wait()
        self.assertIn("failed (exit 1): nec: error: walk.bvh:3: bad channel count", str(raised.exception))
        self.assertNotIn("never", run.lines)

    def test_poll_does_not_block_and_cancel_stops_the_command(self):
        run = runner.NecRun([[PYTHON, "-c", "import time; print('started', flush=True); time.sleep(30)"], say("x")])
        start = time.monotonic()
        while "started" not in run.lines and time.monotonic() - start < 10:
            lines, code = run.poll()
            self.assertIsNone(code)
            time.sleep(0.05)
        self.assertIn("started", run.lines)
        run.cancel()
        _, code = run.poll()
        self.assertNotEqual(code, 0)
        self.assertIsNotNone(code)
        self.assertLess(time.monotonic() - start, 10)
        self.assertNotIn("x", run.lines)

    def test_nothing_to_run_ends_well(self):
        self.assertEqual(runner.NecRun([lambda: []]).poll(), ([], 0))

    def test_finds_the_binary_or_says_none(self):
        self.assertIsNone(runner.find_nec("/no/such/nec"))
        self.assertEqual(runner.find_nec(PYTHON), os.path.abspath(PYTHON))


if __name__ == "__main__":
    unittest.main(verbosity=2)
