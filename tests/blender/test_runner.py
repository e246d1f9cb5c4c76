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


FAKE_NEC = """#!/usr/bin/env python3
import json, os, sys, time
if sys.argv[1:2] != ["worker"]:
    print("process", os.getpid(), *sys.argv[1:])
    sys.exit(0)
if OLD:
    sys.exit(2)  # a nec without `worker`
for line in sys.stdin:
    request = json.loads(line)
    args = request["args"]
    with open(request["log"], "a") as log:
        print("worker", os.getpid(), request["folder"], *args, file=log, flush=True)
        if args[0] == "fail":
            print("nec: error: bad.bvh:3: broken", file=log)
        if args[0] == "die":
            os.kill(os.getpid(), 9)
        if args[0] == "sleep":
            time.sleep(30)
    print(json.dumps({"exit": 1 if args[0] == "fail" else 0}), flush=True)
"""


class WorkerTest(unittest.TestCase):
    """nec's commands in a `nec worker` kept between runs (a fake nec speaking its protocol)."""

    def setUp(self):
        self.folder = tempfile.TemporaryDirectory()
        self.nec = self.fake("nec", old=False)

    def tearDown(self):
        runner.close_workers()
        self.folder.cleanup()

    def fake(self, name, old):
        path = os.path.join(self.folder.name, name)
        pathlib.Path(path).write_text(FAKE_NEC.replace("OLD", str(old)))
        os.chmod(path, 0o755)
        return path

    def run_nec(self, *steps, nec=None):
        run = runner.NecRun(list(steps), cwd=self.folder.name, nec=nec or self.nec)
        run.wait()
        return run.lines

    def test_commands_run_in_one_worker_kept_between_runs(self):
        first = self.run_nec([self.nec, "generate", "a"], [PYTHON, "-c", "print('other program')"])
        self.assertEqual(first[0].split()[0::2], ["worker", os.path.abspath(self.folder.name), "a"])  # in the run's folder
        self.assertEqual(first[1:], ["other program"])
        second = self.run_nec([self.nec, "generate", "b"])
        self.assertEqual(second[0].split()[1], first[0].split()[1], "the same worker process")

    def test_a_failure_or_a_crash_fails_the_run_and_the_next_gets_a_fresh_worker(self):
        pid = self.run_nec([self.nec, "generate", "a"])[0].split()[1]
        with self.assertRaises(runner.NecError) as failed:
            self.run_nec([self.nec, "fail"], [self.nec, "never"])
        self.assertIn("failed (exit 1): nec: error: bad.bvh:3: broken", str(failed.exception))
        with self.assertRaises(runner.NecError) as crashed:
            self.run_nec([self.nec, "die"])
        self.assertIn("nec stopped during the command (exit -9)", str(crashed.exception))
        after = self.run_nec([self.nec, "generate", "c"])[0].split()
        self.assertEqual(after[0], "worker")
        self.assertNotEqual(after[1], pid)

    def test_cancel_stops_the_worker_and_the_next_run_starts_another(self):
        run = runner.NecRun([[self.nec, "sleep"]], cwd=self.folder.name, nec=self.nec)
        start = time.monotonic()
        while not run.lines and time.monotonic() - start < 10:
            self.assertIsNone(run.poll()[1])
            time.sleep(0.02)
        pid = run.lines[0].split()[1]
        run.cancel()
        _, code = run.poll()
        self.assertIsNotNone(code)
        self.assertNotEqual(code, 0)
        self.assertLess(time.monotonic() - start, 10)
        self.assertNotEqual(self.run_nec([self.nec, "generate"])[0].split()[1], pid)

    def test_a_nec_without_worker_runs_a_process_per_command(self):
        old = self.fake("old-nec", old=True)
        lines = self.run_nec([old, "generate", "a"], [old, "generate", "b"], nec=old)
        self.assertEqual([(line.split()[0], line.split()[2:]) for line in lines],
                         [("process", ["generate", "a"]), ("process", ["generate", "b"])])


if __name__ == "__main__":
    unittest.main(verbosity=2)
