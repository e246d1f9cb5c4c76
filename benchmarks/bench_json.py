"""Google Benchmark JSON output, looked up by benchmark name for the tables of scripts/bench.sh.

    rows = BenchRows("build-bench/bench_gpt.json")
    rows.median("BM_TextToBvh/samples:1")                  # ms, the median aggregate's real_time
    rows.median("BM_SampleTokens/seconds:4/cache:1", "tokens_per_s")

A name is the benchmark's family and arguments as registered; the run options that Google Benchmark appends
to run_name (/iterations:N, /repeats:N, /min_time:S, /real_time, ...) are not part of it. A lookup that finds
no row, or a value that is not a finite number, stops the script with a message naming the benchmark, the field
and the file, so that a table never prints nan.
"""
import json
import math
import re

_RUN_OPTIONS = re.compile(r"(/(iterations|repeats|min_time|min_warmup_time):[^/]+|/(real_time|manual_time|process_time))+$")


def benchmark_name(run_name):
    """run_name without the run options: 'BM_X/a:1/iterations:1/real_time' -> 'BM_X/a:1'."""
    return _RUN_OPTIONS.sub("", run_name)


class BenchRows:
    def __init__(self, path):
        self.path = path
        with open(path) as f:
            self.rows = json.load(f).get("benchmarks", [])
        if not self.rows:
            raise SystemExit(f"bench.sh: {path} holds no benchmark rows")

    def aggregate(self, name, aggregate="median"):
        """The row of one aggregate (median, mean, stddev, cv) of benchmark `name`."""
        for row in self.rows:
            if benchmark_name(row["run_name"]) == name and row.get("aggregate_name") == aggregate:
                return row
        errors = {row.get("error_message") for row in self.rows
                  if benchmark_name(row["run_name"]) == name and row.get("error_occurred")}
        if errors:
            raise SystemExit(f"bench.sh: {name} did not run: {'; '.join(sorted(errors))}")
        known = sorted({benchmark_name(row["run_name"]) for row in self.rows})
        raise SystemExit(f"bench.sh: no {aggregate} of {name} in {self.path} (it holds: {', '.join(known)})")

    def median(self, name, field="real_time"):
        return self.value(self.aggregate(name), field)

    def medians_of(self, prefix):
        """The median rows of every benchmark whose name starts with `prefix`, in file order."""
        found = [row for row in self.rows
                 if benchmark_name(row["run_name"]).startswith(prefix) and row.get("aggregate_name") == "median"]
        if not found:
            raise SystemExit(f"bench.sh: no median of {prefix}* in {self.path}")
        return found

    def value(self, row, field):
        value = row.get(field)
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise SystemExit(f"bench.sh: {row['run_name']} in {self.path} has no finite {field} (got {value!r})")
        return value
