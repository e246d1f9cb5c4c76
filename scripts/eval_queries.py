#!/usr/bin/env python3
"""Top-1 and top-5 of `nec retrieve` on the user-style queries of benchmarks/data/queries.tsv.

    nec zoo --out out/queries/zoo --creatures 45 --clips-per-creature 8 --seed 99
    nec prepare zoo=out/queries/zoo/seen cmu=/usr/share/assimp/models/BVH --creature cmu=person -o out/queries/cache
    python3 scripts/eval_queries.py out/queries/cache [--evaluator DIR] [--json out.json]

A retrieved clip is right when it shows the query's body plan and action. A zoo clip's plan and action are
read from its file name (c012_quadruped_k03_trot.bvh). A clip of any other dataset is a person (biped) doing
every activity its cache caption names in the segmenter's words (corpus/segment.h: stands, walks, trots, runs,
turns, sits, lies down, jumps), e.g. "a person walks forward, then turns left" is right for walk and for turn.
A query is asked only when the cache holds a clip of its plan and action (how many were not is printed). The
evaluator is the default one unless --evaluator is given.
"""
import argparse
import collections
import json
import re
import subprocess
import sys
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


def retrieve(nec, cache, query, k, evaluator):
    command = [nec, "retrieve", query, "--db", cache, "-k", str(k)] + (["--evaluator", evaluator] if evaluator else [])
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"eval_queries: {' '.join(command)} failed:\n{done.stdout}{done.stderr}")
    clips = []
    for line in done.stdout.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 5 and cells[0].isdigit():
            clips.append(cells[2])
    return clips


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cache")
    parser.add_argument("--evaluator", default="")
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
    for query, plan, action in asked:
        labels = [labels_of[c] for c in retrieve(args.nec, args.cache, query, 5, args.evaluator)]
        rank = next((i + 1 for i, shown in enumerate(labels) if (plan, action) in shown), None)
        results.append({"query": query, "plan": plan, "action": action, "rank": rank,
                        "first": ", ".join(sorted(" ".join(pair) for pair in labels[0])) if labels else ""})
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
