#!/usr/bin/env python3
"""Writes a BVH file's skeleton in its rest pose as a one-frame BVH: every rotation channel 0, every position
channel as in the first frame. The skeleton a user exports from a rig (no motion in its pose), for generating
onto a clip's skeleton without handing the model the clip's own mean pose (nec's canonical rest pose of a
skeleton file is the mean pose of its motion).
  scripts/rest_pose_bvh.py IN.bvh OUT.bvh
"""
import sys


def main(source, target):
    with open(source, encoding="utf-8", errors="replace") as f:
        lines = f.read().splitlines()
    motion = next(i for i, line in enumerate(lines) if line.strip() == "MOTION")
    channels = []
    for line in lines[:motion]:
        words = line.split()
        if words and words[0] == "CHANNELS":
            channels += words[2:2 + int(words[1])]
    first = next(i for i in range(motion + 1, len(lines)) if lines[i].strip() and not lines[i].strip().startswith(("Frames", "Frame Time")))
    values = lines[first].split()
    if len(values) != len(channels):
        sys.exit(f"{source}:{first + 1}: {len(values)} values for {len(channels)} channels")
    rest = [value if name.lower().endswith("position") else "0" for name, value in zip(channels, values)]
    frame_time = next(line for line in lines[motion:first] if line.strip().startswith("Frame Time"))
    with open(target, "w", encoding="utf-8") as f:
        f.write("\n".join(lines[:motion + 1] + ["Frames: 1", frame_time.strip(), " ".join(rest)]) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: scripts/rest_pose_bvh.py IN.bvh OUT.bvh")
    main(sys.argv[1], sys.argv[2])
