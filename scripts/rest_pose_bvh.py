#!/usr/bin/env python3
"""Writes a BVH file's skeleton in its rest pose as a one-frame BVH: every rotation channel 0, every position
channel as in the first frame. The skeleton a user exports from a rig (no motion in its pose), for generating
onto a clip's skeleton without handing the model the clip's own pose.
  scripts/rest_pose_bvh.py IN.bvh OUT.bvh [--lower-arms DEGREES | --first-frame]
--first-frame: keep the first frame's rotations too (the rig given as its first pose, e.g. a capture's).
--lower-arms: turn both upper arms (joints named LeftArm, upper_arm.L, Left UpperArm, ...) that far towards
straight down, as in an A-pose when the rest is a T-pose. At rest every joint frame is aligned with the file's
axes, so the turn is about the axis across the arm and down; it is written when that axis is one of the file's
axes (arms along one axis, as in a T-pose), else the arm is left as it is and a note says so.
"""
import re
import sys


def words_of(name):
    name = name.split(":")[-1]  # mixamorig:LeftArm
    name = re.sub(r"([a-z])([A-Z])", r"\1 \2", name)
    return [w for w in re.split(r"[^a-z]+", name.lower()) if w]


def upper_arm_side(name):
    """'left' or 'right' for an upper arm joint, else None."""
    words = words_of(name)
    side = "left" if ("left" in words or "l" in words) else "right" if ("right" in words or "r" in words) else None
    rest = "".join(w for w in words if w not in ("left", "right", "l", "r"))
    return side if rest in ("arm", "upperarm", "uparm", "shldr") else None


def parse_hierarchy(lines, motion):
    """Joints as dicts: name, offset, channels (names), first channel index, parent, children offsets."""
    joints, stack, channel = [], [], 0
    pending = None
    for line in lines[:motion]:
        words = line.split()
        if not words:
            continue
        if words[0] in ("ROOT", "JOINT"):
            pending = {"name": " ".join(words[1:]), "parent": stack[-1] if stack else None, "children": []}
        elif words[0] == "End":
            pending = {"name": None, "parent": stack[-1], "children": []}
        elif words[0] == "{":
            joints.append(pending)
            stack.append(len(joints) - 1)
        elif words[0] == "}":
            stack.pop()
        elif words[0] == "OFFSET":
            joint = joints[stack[-1]]
            joint["offset"] = [float(v) for v in words[1:4]]
            if joint["parent"] is not None:
                joints[joint["parent"]]["children"].append(joint["offset"])
        elif words[0] == "CHANNELS":
            joint = joints[stack[-1]]
            joint["channels"] = words[2:2 + int(words[1])]
            joint["first"] = channel
            channel += int(words[1])
    return joints


def lower_arms(joints, values, degrees):
    # The up axis: the one along which the head-most joints sit farthest above the root, Y unless Z is.
    spans = [max(abs(j["offset"][axis]) for j in joints if "offset" in j) for axis in range(3)]
    heights = [sum(j["offset"][axis] for j in joints if j["name"] and "spine" in j["name"].lower()) for axis in (1, 2)]
    up = 2 if abs(heights[1]) > abs(heights[0]) and spans[2] > 0 else 1
    for joint in joints:
        side = joint["name"] and upper_arm_side(joint["name"])
        if not side or not joint["children"] or "channels" not in joint:
            continue
        bone = joint["children"][0]
        down = [0.0, 0.0, 0.0]
        down[up] = -1.0
        axis = [bone[1] * down[2] - bone[2] * down[1], bone[2] * down[0] - bone[0] * down[2],
                bone[0] * down[1] - bone[1] * down[0]]
        size = max(abs(a) for a in axis)
        principal = max(range(3), key=lambda a: abs(axis[a]))
        if size == 0 or any(abs(axis[a]) > 0.02 * size for a in range(3) if a != principal):
            print(f"note: {joint['name']}: the arm is not along an axis; left as it is", file=sys.stderr)
            continue
        name = "XYZ"[principal] + "rotation"
        index = next((i for i, c in enumerate(joint["channels"]) if c.lower() == name.lower()), None)
        if index is None:
            print(f"note: {joint['name']}: no {name} channel; left as it is", file=sys.stderr)
            continue
        sign = 1.0 if axis[principal] > 0 else -1.0
        values[joint["first"] + index] = "%.6f" % (sign * degrees)


def main(source, target, arms_degrees, first_frame):
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
    rest = [value if first_frame or name.lower().endswith("position") else "0" for name, value in zip(channels, values)]
    if arms_degrees:
        lower_arms(parse_hierarchy(lines, motion), rest, arms_degrees)
    frame_time = next(line for line in lines[motion:first] if line.strip().startswith("Frame Time"))
    with open(target, "w", encoding="utf-8") as f:
        f.write("\n".join(lines[:motion + 1] + ["Frames: 1", frame_time.strip(), " ".join(rest)]) + "\n")


if __name__ == "__main__":
    args = sys.argv[1:]
    degrees, first = 0.0, False
    if len(args) == 4 and args[2] == "--lower-arms":
        degrees = float(args[3])
        args = args[:2]
    elif len(args) == 3 and args[2] == "--first-frame":
        first = True
        args = args[:2]
    if len(args) != 2:
        sys.exit("usage: scripts/rest_pose_bvh.py IN.bvh OUT.bvh [--lower-arms DEGREES | --first-frame]")
    main(args[0], args[1], degrees, first)
