"""Runs the nec binary without blocking Blender: a subprocess whose output lines are collected by a reader
thread, polled from the UI thread (a modal operator's timer); cancel() stops it. nec's own commands go to a
`nec worker` kept for the Blender session (the process `nec serve` runs its jobs in), so that the models load
once and a second generation costs the model's work only; a nec that cannot run one is started per command. No
bpy here, so that it can be tested with plain Python."""
import atexit
import itertools
import json
import os
import queue
import shutil
import subprocess
import threading
import time


class NecError(RuntimeError):
    """The command failed: its exit code and its own error line (nec prints `nec: error: ...`)."""


def find_nec(configured):
    """The nec binary: the preference when set, else `nec` on PATH; None when neither exists."""
    if configured:
        path = os.path.abspath(os.path.expanduser(configured))
        return path if os.path.isfile(path) and os.access(path, os.X_OK) else None
    return shutil.which("nec")


class Worker:
    """One `nec worker`: commands sent as JSON lines, each answered with its exit code; the command's output
    goes to the log file named in the request. It ends with Blender (its input closes) or on close()."""

    def __init__(self, nec):
        self.process = subprocess.Popen([nec, "worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self._replies = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.process.stdout:
            self._replies.put(line)
        self._replies.put(None)  # the worker ended

    def alive(self):
        return self.process.poll() is None

    def send(self, argv, folder, log):
        request = {"args": list(argv[1:]), "folder": os.path.abspath(folder), "log": os.path.abspath(log)}
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()

    def reply(self):
        """The answer to the last request: a dict, None while it runs, "ended" when the worker died."""
        try:
            line = self._replies.get_nowait()
        except queue.Empty:
            return None
        if line is None:
            return "ended"
        try:
            return json.loads(line)
        except ValueError:
            return {"exit": 1, "error": "the nec worker answered: " + line.strip()}

    def close(self):
        if self.process.stdin and not self.process.stdin.closed:
            try:
                self.process.stdin.close()
            except OSError:
                pass
        try:
            self.process.wait(timeout=2)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


_workers = {}          # nec path -> its Worker
_without_worker = set()  # nec paths that could not run one (an older nec): a process per command
_logs = itertools.count()


def worker_for(nec):
    """The running worker of `nec`, started when there is none; None when that nec has none."""
    if nec in _without_worker:
        return None
    worker = _workers.get(nec)
    if worker is None or not worker.alive():
        worker = _workers[nec] = Worker(nec)
    return worker


def close_workers():
    """Ends every worker (the add-on's unregister, and Python's exit)."""
    for worker in _workers.values():
        worker.close()
    _workers.clear()


atexit.register(close_workers)


class NecRun:
    """Runs commands one after another, stopping at the first that fails. A step is an argv list, or a function
    called when the step before it has finished that returns the argv lists to run next (e.g. one per file a
    search wrote)."""

    def __init__(self, steps, cwd=None, nec=None):
        """`nec`: the nec binary whose commands (steps starting with it) run in its worker, in `cwd`."""
        self.lines = []
        self.argv = None
        self._steps = list(steps)
        self._cwd = cwd
        self._nec = nec
        self._queue = queue.Queue()
        self._process = None
        self._reader = None
        self._worker = None    # the worker running the current step
        self._log = None       # its log file, read from _log_offset on
        self._log_offset = 0
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
            if self._nec is not None and self._cwd is not None and self.argv[0] == self._nec:
                self._worker = worker_for(self._nec)
                if self._worker is not None:
                    self._log = os.path.join(self._cwd, f"nec-{os.getpid()}-{next(_logs)}.log")
                    self._log_offset = 0
                    try:
                        self._worker.send(self.argv, self._cwd, self._log)
                        return True
                    except OSError:  # it died since: a fresh one next time, a process now
                        _workers.pop(self._nec, None)
                        self._worker = None
            self._process = subprocess.Popen(self.argv, cwd=self._cwd, stdout=subprocess.PIPE,
                                             stderr=subprocess.STDOUT, text=True, bufsize=1)
            self._reader = threading.Thread(target=self._read, args=(self._process,), daemon=True)
            self._reader.start()
            return True
        return False

    def _log_lines(self, new):
        """The whole lines the worker's command wrote to its log since the last call."""
        try:
            with open(self._log, "rb") as log:
                log.seek(self._log_offset)
                data = log.read()
        except OSError:
            return
        end = data.rfind(b"\n") + 1
        self._log_offset += end
        new += data[:end].decode("utf-8", errors="replace").split("\n")[:-1]

    def _worker_step(self, new):
        """The exit code of the worker's command, None while it runs."""
        reply = self._worker.reply()
        self._log_lines(new)
        if reply is None:
            return None
        worker, self._worker = self._worker, None
        if reply != "ended":
            if reply.get("error"):
                new.append("nec: error: " + reply["error"])
            return reply.get("exit", 1)
        _workers.pop(self._nec, None)
        code = worker.process.wait()
        if self._log_offset == 0 and not new and not self._cancelled:
            # It ended before running anything: a nec without `worker`. Every command its own process from now.
            _without_worker.add(self._nec)
            self._steps.insert(0, self.argv)
            return 0
        new.append(f"nec: error: nec stopped during the command (exit {code})")
        return code if code != 0 else 1

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
        while self._code is None and (self._process is not None or self._worker is not None):
            if self._worker is not None:
                code = self._worker_step(new)
            else:
                code = self._process.poll()
                if code is None:
                    break
                self._reader.join(timeout=5.0)
                self._drain(new)
            if code is None:
                break
            self._process = None
            if code != 0 or self._cancelled or not self._start_next():
                self._code = code
        self.lines += new
        return new, self._code

    def wait(self):
        """Blocks until every command has ended (Blender in the background runs no timers); raises NecError when
        one fails."""
        while self._code is None:
            if self._process is not None:
                self._process.wait()
            else:
                time.sleep(0.005)
            self.poll()
        code = self._code
        if code != 0:
            raise NecError(self.error_message(code))

    def cancel(self):
        self._cancelled = True
        self._steps = []
        if self._worker is not None:  # a command cannot be taken back from a worker: it goes, a fresh one follows
            _workers.pop(self._nec, None)
            self._worker.process.kill()
            self._worker.close()
            self._code = self._worker.process.returncode
            self._worker = None
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
