"""Two op profiles side by side (benchmarks/train_step_support.h's JSON): where a step's time goes in nec and in its
Python peer.

    /usr/bin/python3 benchmarks/op_profile_report.py --title "Tokenizer, 22 joints, 1 thread" \
        build-bench/profiles/BM_TatTrainStep_joints_22_threads_1.json \
        build-bench/profiles/peer_tat_step_joints_22_threads_1.json [--top 12]

Prints per step: wall clock, time inside ATen and autograd (top-level records), the rest (outside ATen: the
caller's glue, the Python interpreter), the number of op calls; then the ops of largest self time on either side
with their calls and self time per step. Times include the profiler's own overhead per record, on both sides.
"""
import argparse
import json


def per_step(profile):
    n = profile["repeats"]
    ops = {name: {k: v / n for k, v in op.items()} for name, op in profile["ops"].items()}
    return profile["wall_ms"] / n, profile["top_level_ms"] / n, ops


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("nec")
    parser.add_argument("peer")
    parser.add_argument("--title", required=True)
    parser.add_argument("--top", type=int, default=12)
    args = parser.parse_args()
    with open(args.nec) as f:
        nec_wall, nec_aten, nec_ops = per_step(json.load(f))
    with open(args.peer) as f:
        peer_wall, peer_aten, peer_ops = per_step(json.load(f))

    def calls(ops):
        return sum(op["calls"] for op in ops.values())

    print(f"""
| {args.title}, per step under the profiler | C++ | Python |
|---|---:|---:|
| wall clock (ms) | {nec_wall:.1f} | {peer_wall:.1f} |
| inside ATen and autograd (ms) | {nec_aten:.1f} | {peer_aten:.1f} |
| outside them (ms) | {nec_wall - nec_aten:.1f} | {peer_wall - peer_aten:.1f} |
| op and autograd-node calls | {calls(nec_ops):,.0f} | {calls(peer_ops):,.0f} |

| op (largest self time on either side) | C++ calls | C++ self ms | Python calls | Python self ms |
|---|---:|---:|---:|---:|""")
    empty = {"calls": 0, "self_ms": 0.0}
    names = sorted(set(nec_ops) | set(peer_ops),
                   key=lambda name: -max(nec_ops.get(name, empty)["self_ms"], peer_ops.get(name, empty)["self_ms"]))
    for name in names[:args.top]:
        a, b = nec_ops.get(name, empty), peer_ops.get(name, empty)
        print(f"| {name} | {a['calls']:,.0f} | {a['self_ms']:.1f} | {b['calls']:,.0f} | {b['self_ms']:.1f} |")
    print()


if __name__ == "__main__":
    main()
