"""nec serve from a user's side: request -> done latency of generate and search, warm workers against the
per-process path, in the same run.

    python3 benchmarks/studio_latency.py --nec build-bench/apps/nec --rig /usr/share/assimp/models/BVH/01_01.bvh \\
        --db out/bench-db [--repeat 10] [--concurrent 50] [--json studio.json]

For each path (the default warm workers, then --process-per-job) a studio starts on a free loopback port
(--workers 1 unless told), the rig is uploaded, and one request at a time: a first generate (the worker loads
the models), then --repeat 4-s "a person walks forward" generations (seeds 1..N) and --repeat searches, each
timed from the POST to the poll that sees it done (polled every 5 ms). Then --concurrent generate requests at
once (1-s motions), all of which must finish without error. The resident memory of the studio and of its
worker processes is read from /proc before the first request and after the last. Only the standard library:
the requests are what a script of a user's would send (docs/studio.md).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
import uuid


class Studio:
    """A running `nec serve` on a free port; stopped (SIGINT) on close."""

    def __init__(self, nec, extra):
        self.process = subprocess.Popen([nec, "serve", "--port", "0"] + extra, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True)
        line = self.process.stdout.readline()
        if "http://" not in line:
            raise SystemExit(f"studio_latency.py: nec serve did not start: {line}{self.process.stdout.read()}")
        self.base = line.split("http://", 1)[1].split("/", 1)[0]

    def close(self):
        self.process.send_signal(2)
        self.process.wait(timeout=30)

    def call(self, method, route, body=None, content_type="application/json"):
        request = urllib.request.Request(f"http://{self.base}{route}", data=body, method=method,
                                         headers={"Content-Type": content_type} if body is not None else {})
        try:
            with urllib.request.urlopen(request, timeout=600) as answer:
                return answer.status, json.loads(answer.read())
        except urllib.error.HTTPError as error:
            return error.code, json.loads(error.read())

    def upload(self, path):
        boundary = uuid.uuid4().hex
        with open(path, "rb") as f:
            content = f.read()
        body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{os.path.basename(path)}\"\r\n"
                f"Content-Type: application/octet-stream\r\n\r\n").encode() + content + f"\r\n--{boundary}--\r\n".encode()
        status, answer = self.call("POST", "/api/rigs", body, f"multipart/form-data; boundary={boundary}")
        if status != 200:
            raise SystemExit(f"studio_latency.py: upload refused: {answer}")
        return answer["id"]

    def run(self, route, request):
        """Seconds from the POST to the poll that sees the job done; exits on a failed job."""
        start = time.perf_counter()
        status, answer = self.call("POST", route, json.dumps(request).encode())
        if status != 202:
            raise SystemExit(f"studio_latency.py: {route} refused: {answer}")
        while True:
            _, job = self.call("GET", f"/api/jobs/{answer['job']}")
            if job["state"] == "done":
                return time.perf_counter() - start
            if job["state"] == "failed":
                raise SystemExit(f"studio_latency.py: {route} failed: {job['error']}")
            time.sleep(0.005)

    def resident_mib(self):
        """(the studio's, its workers' together) resident memory in MiB."""
        def rss(pid):
            try:
                with open(f"/proc/{pid}/status") as f:
                    return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:")) / 1024.0
            except (OSError, StopIteration):
                return 0.0
        children = []
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                try:
                    with open(f"/proc/{entry}/stat") as f:
                        if int(f.read().rsplit(")", 1)[1].split()[1]) == self.process.pid:
                            children.append(int(entry))
                except (OSError, IndexError, ValueError):
                    pass
        return rss(self.process.pid), sum(rss(c) for c in children)


def measure(nec, extra, rig, repeat, concurrent):
    studio = Studio(nec, extra)
    try:
        rig_id = studio.upload(rig)
        memory_before = studio.resident_mib()
        walk = lambda seed, seconds=4: {"rig": rig_id, "seed": seed,
                                        "captions": [{"text": "a person walks forward", "seconds": seconds}]}
        first = studio.run("/api/generate", walk(0))
        generate = [studio.run("/api/generate", walk(seed)) for seed in range(1, repeat + 1)]
        studio.run("/api/search", {"text": "a person walks", "k": 3})  # the index is built or read once
        search = [studio.run("/api/search", {"text": "a person jumps", "k": 3}) for _ in range(repeat)]
        failures, started = [], time.perf_counter()

        def user(seed):
            try:
                studio.run("/api/generate", walk(seed, 1))
            except SystemExit as error:
                failures.append(str(error))
        users = [threading.Thread(target=user, args=(seed,)) for seed in range(concurrent)]
        for u in users:
            u.start()
        for u in users:
            u.join()
        all_done = time.perf_counter() - started
        memory_after = studio.resident_mib()
    finally:
        studio.close()
    if failures:
        raise SystemExit(f"studio_latency.py: {len(failures)} of {concurrent} concurrent requests failed: {failures[0]}")
    return {"first_generate": first, "generate": generate, "search": search, "concurrent": concurrent,
            "concurrent_all_done": all_done, "memory_before": memory_before, "memory_after": memory_after}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nec", required=True)
    parser.add_argument("--rig", required=True, help="the rig to upload (a BVH file)")
    parser.add_argument("--db", required=True, help="a dataset cache to search")
    parser.add_argument("--repeat", type=int, default=10)
    parser.add_argument("--concurrent", type=int, default=50)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--json", help="write every time here")
    args = parser.parse_args()
    common = ["--db", args.db, "--workers", str(args.workers)]
    paths = [("warm workers (default)", common), ("a process per job (--process-per-job)", common + ["--process-per-job"])]
    results = {name: measure(args.nec, extra, args.rig, args.repeat, args.concurrent) for name, extra in paths}
    print(f"\n| nec serve, {args.workers} worker(s) | first generate, s | generate 4 s, median of {args.repeat} (min - max), s "
          f"| search, median, s | {args.concurrent} concurrent 1-s generates: all done, s | studio / workers RSS before "
          f"-> after, MiB |\n|---|---:|---:|---:|---:|---|")
    for name, r in results.items():
        g, s = r["generate"], r["search"]
        (studio_before, workers_before), (studio_after, workers_after) = r["memory_before"], r["memory_after"]
        print(f"| {name} | {r['first_generate']:.2f} | {statistics.median(g):.3f} ({min(g):.3f} - {max(g):.3f}) | "
              f"{statistics.median(s):.3f} | {r['concurrent_all_done']:.1f} | {studio_before:.0f} / {workers_before:.0f} -> "
              f"{studio_after:.0f} / {workers_after:.0f} |")
    warm, cold = (statistics.median(r["generate"]) for r in results.values())
    print(f"\nwarm / per process (generate median): {warm / cold:.2f}\n")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
