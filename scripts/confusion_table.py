#!/usr/bin/env python3
"""Within a body plan, which action `nec retrieve` finds for a caption of each action: a confusion table per plan.

    nec zoo --out out/near/zoo --plans biped,quadruped,bird,dragon,ungulate \
        --actions walk,trot,run,gallop,sit,lie_down,fly,glide,flap_wings,take_off --creatures 80 --clips-per-creature 8 --seed 99
    nec prepare zoo=out/near/zoo/seen -o out/near/cache
    python3 scripts/confusion_table.py out/near/cache [--evaluator DIR] [--caption-weight W]

Every zoo clip of the cache asks for its own plan and action once, with one of its own captions (the levels taken
in turn); the search is kept to the clip's plan (`nec retrieve --plan`) and the clip itself is left out of the
answer (the first clip found that is not the asking one). A row is the asked action, a column the action of the
clip found; the diagonal share is "right". With the default --caption-weight 0 the clips are ranked by their
motions alone (the evaluator); a weight above 0 would match a caption with clips of the same creature's captions.
"""
import argparse
import collections
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_queries import ZOO_CLIP, Retriever  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cache")
    parser.add_argument("--evaluator", default="")
    parser.add_argument("--caption-weight", default="0")
    parser.add_argument("--nec", default=str(Path(__file__).resolve().parent.parent / "build/apps/nec"))
    parser.add_argument("--json", default="")
    args = parser.parse_args()

    manifest = json.loads((Path(args.cache) / "manifest.json").read_text())
    label = {}
    for clip in manifest["clips"]:
        match = ZOO_CLIP.search(Path(clip["id"].split("#")[0]).name)
        if match and clip.get("captions"):
            label[clip["id"]] = (match.group(1), match.group(2))
    if not label:
        raise SystemExit(f"confusion_table: {args.cache} has no captioned zoo clip")
    retrieve = Retriever(args.nec, args.cache, args.evaluator, args.caption_weight)
    tables = collections.defaultdict(lambda: collections.defaultdict(collections.Counter))
    asked_per_plan = collections.Counter()
    for clip in manifest["clips"]:
        if clip["id"] not in label:
            continue
        plan, action = label[clip["id"]]
        caption = clip["captions"][asked_per_plan[plan] % len(clip["captions"])]
        asked_per_plan[plan] += 1
        found = [c for c in retrieve(caption, 2, ["--plan", plan]) if c != clip["id"]]
        tables[plan][action][label[found[0]][1] if found and found[0] in label else "none"] += 1
    retrieve.close()

    print(f"evaluator {args.evaluator or 'default'}, caption weight {args.caption_weight}: "
          f"each clip's own caption, search kept to its plan, itself left out")
    summary = {}
    for plan in sorted(tables):
        rows = tables[plan]
        actions = sorted(rows)
        right = sum(rows[a][a] for a in actions)
        total = sum(sum(rows[a].values()) for a in actions)
        summary[plan] = {"right": right, "asked": total, "table": {a: dict(rows[a]) for a in actions}}
        print(f"\n### {plan}: {right} of {total} right ({right / total:.0%})\n")
        print("| asked \\ found | " + " | ".join(actions) + " |")
        print("|---|" + "---:|" * len(actions))
        for a in actions:
            print(f"| {a} | " + " | ".join(f"**{rows[a][b]}**" if a == b else str(rows[a][b]) for b in actions) + " |")
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
