#!/usr/bin/env python3
"""Top-1 and top-5 of `nec retrieve` on the user-style queries of benchmarks/data/queries.tsv (or queries_heldout.tsv).

    nec zoo --out out/queries/zoo --creatures 96 --clips-per-creature 8 --seed 99
    nec prepare zoo=out/queries/zoo/seen cmu=/usr/share/assimp/models/BVH --creature cmu=person -o out/queries/cache
    python3 scripts/eval_queries.py out/queries/cache [--queries benchmarks/data/queries_heldout.tsv] [--evaluator DIR]
        [--caption-weight W] [--json out.json]

A retrieved clip is right when it shows the query's body plan and action. A zoo clip's plan and action are
read from its file name (c012_quadruped_k03_trot.bvh). A clip of any other dataset is a person (biped) doing
every activity its cache caption names in the segmenter's words (corpus/segment.h: stands, walks, trots, runs,
turns, sits, lies down, jumps), e.g. "a person walks forward, then turns left" is right for walk and for turn.
A query is asked only when the cache holds a clip of its plan and action (how many were not is printed). The
evaluator is the default one unless --evaluator is given; --caption-weight is passed to `nec retrieve` (its own
default when not given: blended with the clips' captions). The searches run in one `nec worker`.
"""
import argparse
import collections
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ZOO_CLIP = re.compile(r"c\d{3}_([a-z_]+?)_k\d+_([a-z_]+)\.bvh")
SEGMENTER_WORDS = {"stands": "idle", "walks": "walk", "trots": "trot", "runs": "run", "turns": "turn", "sits": "sit",
                   "lies": "lie_down", "jumps": "jump"}


def clip_labels(clip):
    """The (plan, action) pairs a cache clip shows."""
    match = ZOO_CLIP.search(Path(clip["id"].split("#")[0]).name)
    if match:
        return {(match.group(1), match.group(2))}
    words = re.findall(r"[a-z]+", clip["captions"][0].lower()) if clip.get("captions") else []
    return {("biped", SEGMENTER_WORDS[w]) for w in words if w in SEGMENTER_WORDS}


def read_queries(path):
    rows = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if not line or line.startswith("#") or line.startswith("query\t"):
            continue
        query, plan, action = line.split("\t")
        rows.append((query, plan, action))
    return rows


class Retriever:
    """Runs `nec retrieve` in one long-lived `nec worker` (the database and the evaluator loaded once)."""

    def __init__(self, nec, cache, evaluator, caption_weight):
        self.options = ["--db", str(Path(cache).resolve())] + (["--evaluator", str(Path(evaluator).resolve())] if evaluator else [])
        if caption_weight is not None:
            self.options += ["--caption-weight", caption_weight]
        self.folder = tempfile.TemporaryDirectory(prefix="eval_queries_")
        self.worker = subprocess.Popen([nec, "worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __call__(self, query, k, extra=()):
        """The ids of the k clips found first for `query` (`extra`: more options of `nec retrieve`)."""
        log = Path(self.folder.name) / "log.txt"
        log.write_text("")
        args = ["retrieve", query, "-k", str(k)] + self.options + list(extra)
        self.worker.stdin.write(json.dumps({"args": args, "folder": self.folder.name, "log": str(log)}) + "\n")
        self.worker.stdin.flush()
        answer = json.loads(self.worker.stdout.readline() or '{"exit": -1, "error": "the worker stopped"}')
        output = log.read_text()
        if answer["exit"] != 0:
            raise SystemExit(f"eval_queries: nec {' '.join(args)} failed: {answer.get('error', '')}\n{output}")
        clips = []
        for line in output.splitlines():
            cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
            if len(cells) == 5 and cells[0].isdigit():
                clips.append(cells[2])
        return clips

    def close(self):
        self.worker.stdin.close()
        self.worker.wait()
        self.folder.cleanup()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cache")
    parser.add_argument("--evaluator", default="")
    parser.add_argument("--caption-weight", default=None, help="nec retrieve's --caption-weight (default: its own)")
    parser.add_argument("--queries", default=str(Path(__file__).resolve().parent.parent / "benchmarks/data/queries.tsv"))
    parser.add_argument("--nec", default=str(Path(__file__).resolve().parent.parent / "build/apps/nec"))
    parser.add_argument("--json", default="")
    args = parser.parse_args()

    manifest = json.loads((Path(args.cache) / "manifest.json").read_text())
    labels_of = {clip["id"]: clip_labels(clip) for clip in manifest["clips"]}
    present = set().union(*labels_of.values())
    queries = read_queries(args.queries)
    asked = [q for q in queries if (q[1], q[2]) in present]
    results = []
    retrieve = Retriever(args.nec, args.cache, args.evaluator, args.caption_weight)
    for query, plan, action in asked:
        labels = [labels_of[c] for c in retrieve(query, 5)]
        rank = next((i + 1 for i, shown in enumerate(labels) if (plan, action) in shown), None)
        results.append({"query": query, "plan": plan, "action": action, "rank": rank,
                        "first": ", ".join(sorted(" ".join(pair) for pair in labels[0])) if labels else ""})
    retrieve.close()
    top1 = sum(r["rank"] == 1 for r in results)
    top5 = sum(r["rank"] is not None for r in results)
    n = len(results)
    print(f"{n} of {len(queries)} queries asked ({len(queries) - n} have no clip of their plan and action in the cache)")
    print(f"top-1 {top1}/{n} = {top1 / n:.1%}, top-5 {top5}/{n} = {top5 / n:.1%}")
    by_plan = collections.defaultdict(lambda: [0, 0, 0])
    for r in results:
        by_plan[r["plan"]][0] += 1
        by_plan[r["plan"]][1] += r["rank"] == 1
        by_plan[r["plan"]][2] += r["rank"] is not None
    print("\n| plan | queries | top-1 | top-5 |\n|---|---:|---:|---:|")
    for plan, (count, first, five) in sorted(by_plan.items()):
        print(f"| {plan} | {count} | {first} | {five} |")
    print("\nmissed at top-1 (query -> the plan and action retrieved first):")
    for r in results:
        if r["rank"] != 1:
            print(f"  {r['query']!r} ({r['plan']} {r['action']}) -> {r['first']}")
    if args.json:
        Path(args.json).write_text(json.dumps({"asked": n, "top1": top1, "top5": top5, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
