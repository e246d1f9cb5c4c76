"""What every training-step peer (benchmarks/peer_*_step.py) shares: the allocator policy nec runs with, the
peak memory of a step, the timing of each setting, the op profile and the JSON that scripts/bench.sh reads.

    add_arguments(parser, "tat_cpu.json and owo_cpu.json", default_repetitions=5)
    args = parser.parse_args()
    keep_large_allocations_in_heap()
    result = run_settings("tat", [({"joints": 22}, 3), ({"joints": 100}, 1)], lambda s: Trainee(c, s["joints"]), args)
    print_json(result)

A trainee has .parameters and .step() -> the loss before the step. Per setting (e.g. {"joints": 22}) the model,
its first WARMUP_STEPS losses and the peak memory of one more step are made at one thread, as the C++
benchmarks do; then per thread count, `repetitions` times `iterations` timed steps.
"""
import ctypes
import json
import math
import os
import re
import statistics
import sys
import time

import torch

WARMUP_STEPS = 2  # untimed steps before a setting's first measurement, as the C++ benchmarks
LARGE_BLOCK = 1 << 30  # train/src/heap.cpp kLargeBlock
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3  # glibc's mallopt parameters
OP_SCOPES = (0, 1)  # at::RecordScope FUNCTION, BACKWARD_FUNCTION


def learning_rate_at(c, step):
    """train/optimizer.cpp LearningRateSchedule::at (step from 1): linear warmup, then cosine to the final rate."""
    peak, warmup = c["learning_rate"], c["warmup_steps"]
    if warmup > 0 and step <= warmup:
        return peak * max(step, 1) / warmup
    floor = peak * c["final_lr_fraction"]
    progress = min(1.0, max(0.0, (step - warmup) / max(1, c["steps"] - warmup)))
    return floor + (peak - floor) * 0.5 * (1.0 + math.cos(math.pi * progress))


def optimizer_step(optimizer, parameters, grad_clip, lr):
    """train/optimizer.cpp optimizer_step on one process: the global norm, the clip, the rate, AdamW."""
    gradients = [p.grad for p in parameters if p.grad is not None]
    norm = torch.cat([g.detach().norm().reshape(1) for g in gradients]).norm().item()
    if not math.isfinite(norm):
        optimizer.zero_grad()
        return
    if 0 < grad_clip < norm:
        with torch.no_grad():
            for g in gradients:
                g.mul_(grad_clip / (norm + 1e-6))
    for group in optimizer.param_groups:
        group["lr"] = lr
    optimizer.step()


class ScheduledTrainee:
    """What the peers' Trainee classes share: AdamW over the trained parameters at the scheduled rate."""

    def __init__(self, c, model, trained):
        self.c, self.model, self.trained = c, model, list(trained)
        self.optimizer = torch.optim.AdamW(self.trained, lr=c["learning_rate"], weight_decay=c["weight_decay"])
        self.parameters = sum(p.numel() for p in model.parameters())
        self.steps = 0

    def next_rate(self):
        """Counts the step and returns its learning rate."""
        self.steps += 1
        return learning_rate_at(self.c, self.steps)

    def optimizer_step(self, lr):
        optimizer_step(self.optimizer, self.trained, self.c["grad_clip"], lr)


def keep_large_allocations_in_heap():
    """What nec does at start (train/heap.h): glibc keeps every block in its heap and never trims it, so a step's
    large tensors reuse memory instead of being mapped and page-faulted again each step. The peers run with the
    same policy so that the allocator is not what the comparison measures."""
    libc = ctypes.CDLL("libc.so.6")
    if not (libc.mallopt(M_MMAP_THRESHOLD, LARGE_BLOCK) and libc.mallopt(M_TRIM_THRESHOLD, LARGE_BLOCK)):
        sys.exit("peer: mallopt refused the allocator settings nec runs with")


def status_kib(field):
    with open("/proc/self/status") as f:
        match = re.search(rf"^{field}:\s+(\d+)", f.read(), re.MULTILINE)
    return int(match.group(1)) if match else -1


def measure_peak_rss(region):
    """(peak RSS above the start, peak RSS) in MiB of region(), as the C++ benchmarks' measure_peak_rss."""
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    start = status_kib("VmRSS")
    region()
    peak = status_kib("VmHWM")
    return (peak - start) / 1024.0, peak / 1024.0


def profile_ops(region, repeats):
    """region() under PyTorch's profiler, in the JSON of benchmarks/train_step_support.h. It reads the same RecordFunction
    records as train_step_support.h's callbacks; only operator and autograd-node records count, as in C++, so the
    optimizer's user-scope records ("Optimizer.step#AdamW.step") are transparent and the ops inside them count as
    top level. Times include the profiler's own overhead per record, like the C++ callbacks'."""
    with torch.autograd.profiler.profile() as prof:
        start = time.perf_counter()
        for _ in range(repeats):
            region()
        wall_ms = (time.perf_counter() - start) * 1e3
    ops, top_level_ms = {}, 0.0
    for event in prof.function_events:
        if event.scope not in OP_SCOPES:
            continue
        op = ops.setdefault(event.name, {"calls": 0, "self_ms": 0.0, "total_ms": 0.0})
        op["calls"] += 1
        op["self_ms"] += event.self_cpu_time_total / 1e3
        op["total_ms"] += event.cpu_time_total / 1e3
        parent = event.cpu_parent
        while parent is not None and parent.scope not in OP_SCOPES:
            parent = parent.cpu_parent
        if parent is None:
            top_level_ms += event.cpu_time_total / 1e3
    return {"repeats": repeats, "wall_ms": wall_ms, "top_level_ms": top_level_ms, "ops": ops}


def add_arguments(parser, config_files, default_repetitions):
    configs = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs")
    parser.add_argument("--configs", default=configs,
                        help=f"folder with {config_files} (default: the repository's configs/)")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="torch threads (default: 1 2)")
    parser.add_argument("--repetitions", type=int, default=default_repetitions,
                        help=f"repetitions per setting (default: {default_repetitions})")
    parser.add_argument("--expect-parameters", type=int, default=None,
                        help="parameter count the C++ benchmark reported; exit 1 when this model's differs")
    parser.add_argument("--profile-ops", metavar="DIR", default=None,
                        help="profile one more step per setting into DIR/peer_NAME_step_<setting>.json, "
                             "as the C++ benchmark's --profile_ops=DIR")


def setting_label(setting, threads):
    """{"joints": 22}, 1 -> "joints_22_threads_1", as train_step_support.h names the C++ side's files."""
    return "_".join(f"{key}_{value}" for key, value in list(setting.items()) + [("threads", threads)])


def run_settings(name, settings, make_trainee, args):
    """settings: [(setting dict, timed steps per repetition)]; returns the JSON object scripts/bench.sh reads."""
    program = f"peer_{name}_step"
    result = {"torch": torch.__version__, "python": sys.version.split()[0], "repetitions": args.repetitions,
              "runs": []}
    for setting, iterations in settings:
        torch.set_num_threads(1)  # model, first losses and memory at one thread, as the C++ benchmarks
        t = make_trainee(setting)
        print(f"{program}: parameters: python {t.parameters}, C++ "
              f"{args.expect_parameters if args.expect_parameters is not None else '(not given)'}", file=sys.stderr)
        if args.expect_parameters is not None and t.parameters != args.expect_parameters:
            sys.exit(f"{program}: parameter count {t.parameters} differs from the C++ benchmark's "
                     f"{args.expect_parameters}: the re-implementation is not the same architecture")
        result["parameters"] = t.parameters
        first_losses = [t.step() for _ in range(WARMUP_STEPS)]
        step_peak, rss_peak = measure_peak_rss(t.step)
        for threads in args.threads:
            torch.set_num_threads(threads)
            times, cpu_times = [], []
            for _ in range(args.repetitions):
                start, cpu_start = time.perf_counter(), time.process_time()
                for _ in range(iterations):
                    t.step()
                times.append((time.perf_counter() - start) / iterations * 1e3)
                cpu_times.append((time.process_time() - cpu_start) / iterations * 1e3)
            run = dict(setting, threads=threads, iterations=iterations,
                       median_ms=statistics.median(times), min_ms=min(times), max_ms=max(times), times_ms=times,
                       cpu_median_ms=statistics.median(cpu_times), cpu_times_ms=cpu_times,
                       loss_step0=first_losses[0], loss_step1=first_losses[1],
                       step_peak_MiB=step_peak, rss_peak_MiB=rss_peak)
            result["runs"].append(run)
            print(f"{program}: {setting_label(setting, threads).replace('_', ' ')}: median {run['median_ms']:.1f} ms "
                  f"({run['min_ms']:.1f}-{run['max_ms']:.1f}), first losses {first_losses[0]:.8g} "
                  f"{first_losses[1]:.8g}", file=sys.stderr)
            if args.profile_ops:
                os.makedirs(args.profile_ops, exist_ok=True)
                path = os.path.join(args.profile_ops, f"{program}_{setting_label(setting, threads)}.json")
                with open(path, "w") as f:
                    json.dump(profile_ops(t.step, 1), f, indent=1)
    return result


def print_json(result):
    json.dump(result, sys.stdout, indent=1)
    print()
