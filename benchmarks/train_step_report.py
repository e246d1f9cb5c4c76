"""Tables of a training step against its Python peer, for scripts/bench.sh.

    /usr/bin/python3 benchmarks/train_step_report.py --family BM_TatTrainStep --title "Tokenizer, ..." \
        --nec build-bench/bench_tat_step1.json build-bench/bench_tat_step2.json \
        --peer build-bench/peer_tat_step1.json build-bench/peer_tat_step2.json \
        [--load-before "0.1 0.2 0.3"] [--load-after "..."] [--wait-policy passive] [--goal 0.7]

--nec: Google Benchmark JSON of the C++ step, one file per round (benchmark names FAMILY/key:value/...);
--peer: the peer's JSON (benchmarks/peer_*_step.py), one file per round, each run naming the same keys.
A setting is one combination of the keys (e.g. joints:22/threads:1); the C++ repetitions of every round are
pooled against the peer's. Exits 1 when the two sides' first losses differ by more than float rounding
could explain (1e-3 relative): then the peer no longer computes what nec computes, and its time means nothing.
"""
import argparse
import json
import re
import statistics
import sys

LOSS_KEYS = ("loss_step0", "loss_step1")
SAME_COMPUTATION = 1e-3  # relative; the golden-step tests hold the tight tolerances


def settings_of(run_name, family):
    """'BM_X/joints:22/threads:1/iterations:3/repeats:3' -> {'joints': 22, 'threads': 1}."""
    parts = run_name.split("/")
    if parts[0] != family:
        return None
    setting = {}
    for part in parts[1:]:
        key, _, value = part.partition(":")
        if key in ("iterations", "repeats", "min_time", "real_time", "process_time", "manual_time"):
            continue
        setting[key] = int(value) if re.fullmatch(r"-?\d+", value) else value
    return setting


def label(setting):
    return ", ".join(f"{key} {value}" for key, value in setting.items())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--family", required=True, help="the C++ benchmark, e.g. BM_TatTrainStep")
    parser.add_argument("--title", required=True, help="first line above the tables: the model, config and batch")
    parser.add_argument("--nec", nargs="+", required=True, help="bench JSON, one per round")
    parser.add_argument("--peer", nargs="+", required=True, help="peer JSON, one per round")
    parser.add_argument("--load-before", default="?")
    parser.add_argument("--load-after", default="?")
    parser.add_argument("--wait-policy", default="default")
    parser.add_argument("--goal", type=float, default=0.7, help="C++ / Python wall-clock ratio to meet")
    args = parser.parse_args()

    rows = []
    for path in args.nec:
        with open(path) as f:
            rows += [row for row in json.load(f)["benchmarks"] if row.get("run_type") == "iteration"]
    peers = []
    for path in args.peer:
        with open(path) as f:
            peers.append(json.load(f))

    nec = {}  # setting (as a tuple of items) -> C++ rows of every round
    for row in rows:
        setting = settings_of(row["run_name"], args.family)
        if setting is not None:
            nec.setdefault(tuple(setting.items()), []).append(row)
    if not nec:
        sys.exit(f"train_step_report: no {args.family} rows in {', '.join(args.nec)}")

    def peer_runs(setting):
        found = [run for peer in peers for run in peer["runs"] if all(run.get(k) == v for k, v in setting)]
        if not found:
            sys.exit(f"train_step_report: the peer has no run with {label(dict(setting))}")
        return found

    first_rows = next(iter(nec.values()))
    print(f"""
{args.title}; {first_rows[0]['parameters']:.0f} parameters in both;
median of {len(first_rows)} repetitions ({len(args.nec)} round(s), C++ and Python in turn);
torch {peers[0]['torch']} (Debian), Python {peers[0]['python']}; load average (1, 5, 15 min) {args.load_before}
before, {args.load_after} after; OMP_WAIT_POLICY={args.wait_policy}. Wall clock decides the goal; CPU time (all
threads of the process) is less sensitive to other load.

| training step | C++ (ms) | min-max | Python (ms) | min-max | C++ / Python | goal <= {args.goal} | CPU: C++ / Python (ms) |
|---|---:|---|---:|---|---:|---|---|""")
    for setting, nec_rows in nec.items():
        runs = peer_runs(setting)
        wall = [row["real_time"] for row in nec_rows]
        cpu = statistics.median(row["cpu_time"] for row in nec_rows)
        peer_wall = [t for run in runs for t in run["times_ms"]]
        peer_cpu = statistics.median(t for run in runs for t in run["cpu_times_ms"])
        ratio = statistics.median(wall) / statistics.median(peer_wall)
        print(f"| {label(dict(setting))} | {statistics.median(wall):.1f} | {min(wall):.1f}-{max(wall):.1f} | "
              f"{statistics.median(peer_wall):.1f} | {min(peer_wall):.1f}-{max(peer_wall):.1f} | {ratio:.2f} | "
              f"{'met' if ratio <= args.goal else 'MISSED'} | {cpu:.0f} / {peer_cpu:.0f} = {cpu / peer_cpu:.2f} |")

    # First losses and memory are made once per model (at one thread): one line per setting without threads.
    print("""
| same step, same inputs (first round) | C++ | Python | relative difference |
|---|---:|---:|---:|""")
    worst = 0.0
    shown = set()
    for setting, nec_rows in nec.items():
        model_setting = tuple((k, v) for k, v in setting if k != "threads")
        for other in nec_rows + peer_runs(setting):
            for key in LOSS_KEYS:
                reference = peer_runs(setting)[0][key]
                worst = max(worst, abs(other[key] - reference) / max(abs(reference), 1e-12))
        if model_setting in shown:
            continue
        shown.add(model_setting)
        row, run = nec_rows[0], peer_runs(setting)[0]
        name = label(dict(model_setting)) or "model"
        for key in LOSS_KEYS:
            print(f"| {name}, {key.replace('_', ' ')} | {row[key]:.6f} | {run[key]:.6f} | "
                  f"{abs(row[key] - run[key]) / max(abs(run[key]), 1e-12):.1e} |")
        print(f"| {name}, peak RSS of a step above its start (MiB) | {row['step_peak_MiB']:.1f} | "
              f"{run['step_peak_MiB']:.1f} | |")
        print(f"| {name}, process peak RSS during it (MiB) | {row['rss_peak_MiB']:.1f} | {run['rss_peak_MiB']:.1f} | |")
    print()
    if worst > SAME_COMPUTATION:
        sys.exit(f"train_step_report: the Python peer's first losses differ from {args.family}'s by {worst:.1e} "
                 "(relative); they run the same computation on the same inputs and agree to float rounding unless "
                 "the peer no longer matches the C++ model")


if __name__ == "__main__":
    main()
