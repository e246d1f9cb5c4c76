"""Runs the nec binary without blocking Blender: a subprocess whose output lines are collected by a reader
thread, polled from the UI thread (a modal operator's timer); cancel() stops it. No bpy here, so that it can be
tested with plain Python."""
import os
import queue
import shutil
import subprocess
import threading


class NecError(RuntimeError):
    """The command failed: its exit code and its own error line (nec prints `nec: error: ...`)."""


def find_nec(configured):
    """The nec binary: the preference when set, else `nec` on PATH; None when neither exists."""
    if configured:
        path = os.path.abspath(os.path.expanduser(configured))
        return path if os.path.isfile(path) and os.access(path, os.X_OK) else None
    return shutil.which("nec")


class NecRun:
    """Runs commands one after another, stopping at the first that fails. A step is an argv list, or a function
    called when the step before it has finished that returns the argv lists to run next (e.g. one per file a
    search wrote)."""

    def __init__(self, steps, cwd=None):
        self.lines = []
        self.argv = None
        self._steps = list(steps)
        self._cwd = cwd
        self._queue = queue.Queue()
        self._process = None
        self._reader = None
        self._code = None
        self._cancelled = False
        if not self._start_next():
            self._code = 0

    def _start_next(self):
        while self._steps:
            step = self._steps.pop(0)
            if callable(step):
                self._steps[:0] = list(step())
                continue
            self.argv = list(step)
            self._process = subprocess.Popen(self.argv, cwd=self._cwd, stdout=subprocess.PIPE,
                                             stderr=subprocess.STDOUT, text=True, bufsize=1)
            self._reader = threading.Thread(target=self._read, args=(self._process,), daemon=True)
            self._reader.start()
            return True
        return False

    def _read(self, process):
        for line in process.stdout:
            self._queue.put(line.rstrip("\n"))
        process.stdout.close()

    def _drain(self, new):
        while True:
            try:
                new.append(self._queue.get_nowait())
            except queue.Empty:
                return

    def poll(self):
        """New output lines since the last call, and the exit code of the whole run: None while a command runs,
        0 when all ended well, else the first failure's code."""
        new = []
        self._drain(new)
        while self._code is None and self._process is not None:
            code = self._process.poll()
            if code is None:
                break
            self._reader.join(timeout=5.0)
            self._drain(new)
            if code != 0 or self._cancelled or not self._start_next():
                self._code = code
        self.lines += new
        return new, self._code

    def wait(self):
        """Blocks until every command has ended (Blender in the background runs no timers); raises NecError when
        one fails."""
        while self._code is None:
            self._process.wait()
            self.poll()
        code = self._code
        if code != 0:
            raise NecError(self.error_message(code))

    def cancel(self):
        self._cancelled = True
        self._steps = []
        if self._process is not None and self._process.poll() is None:
            self._process.terminate()
            try:
                self._process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._process.kill()

    def error_message(self, code):
        errors = [line for line in self.lines if "error:" in line]
        last = errors[-1] if errors else (self.lines[-1] if self.lines else "no output")
        command = os.path.basename(self.argv[0]) + " " + self.argv[1] if self.argv and len(self.argv) > 1 else "nec"
        return f"{command} failed (exit {code}): {last}"
