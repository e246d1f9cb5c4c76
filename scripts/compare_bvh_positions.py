#!/usr/bin/env python3
"""How far apart two BVH files of one skeleton put its joints: world positions by the files' own forward
kinematics (no nec code), frame by frame, as the largest and the median distance over joints and frames, in
diameters of the first file's skeleton (its longest root-to-leaf chain of offsets). Joints are matched by name;
frames up to the shorter file.
  scripts/compare_bvh_positions.py A.bvh B.bvh
"""
import math
import sys


def read_bvh(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        tokens = f.read().split()
    joints, stack, i = [], [], 1 if tokens and tokens[0] == "HIERARCHY" else 0
    while tokens[i] != "MOTION":
        word = tokens[i]
        if word in ("ROOT", "JOINT", "End"):
            name = tokens[i + 1] if word != "End" else None
            joints.append({"name": name, "parent": stack[-1] if stack else -1, "channels": []})
            i += 2
        elif word == "{":
            stack.append(len(joints) - 1)
            i += 1
        elif word == "}":
            stack.pop()
            i += 1
        elif word == "OFFSET":
            joints[stack[-1]]["offset"] = [float(v) for v in tokens[i + 1:i + 4]]
            i += 4
        elif word == "CHANNELS":
            count = int(tokens[i + 1])
            joints[stack[-1]]["channels"] = tokens[i + 2:i + 2 + count]
            i += 2 + count
        else:
            sys.exit(f"{path}: unexpected '{word}' in the hierarchy")
    frames = int(tokens[tokens.index("Frames:") + 1])
    start = tokens.index("Time:") + 2
    width = sum(len(j["channels"]) for j in joints)
    values = [float(v) for v in tokens[start:start + frames * width]]
    return joints, [values[f * width:(f + 1) * width] for f in range(frames)]


def multiply(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(3)) for c in range(3)] for r in range(3)]


def axis_matrix(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    if axis == "X":
        return [[1, 0, 0], [0, c, -s], [0, s, c]]
    if axis == "Y":
        return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return [[c, -s, 0], [s, c, 0], [0, 0, 1]]


def positions(joints, frame):
    """Named joints' world positions in one frame."""
    out, rotations, places, k = {}, [], [], 0
    for joint in joints:
        local = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
        offset = list(joint["offset"])
        for channel in joint["channels"]:
            value = frame[k]
            k += 1
            if channel.endswith("position"):
                offset["XYZ".index(channel[0])] = value
            else:
                local = multiply(local, axis_matrix(channel[0], value))
        if joint["parent"] < 0:
            rotation, place = local, offset
        else:
            parent_rotation, parent_place = rotations[joint["parent"]], places[joint["parent"]]
            rotation = multiply(parent_rotation, local)
            place = [parent_place[r] + sum(parent_rotation[r][c] * offset[c] for c in range(3)) for r in range(3)]
        rotations.append(rotation)
        places.append(place)
        if joint["name"]:
            out[joint["name"]] = place
    return out


def diameter(joints):
    lengths = [0.0] * len(joints)
    for index, joint in enumerate(joints):
        bone = math.sqrt(sum(v * v for v in joint["offset"])) if joint["parent"] >= 0 else 0.0
        lengths[index] = bone + (lengths[joint["parent"]] if joint["parent"] >= 0 else 0.0)
    return max(lengths)


def main(first, second):
    joints_a, frames_a = read_bvh(first)
    joints_b, frames_b = read_bvh(second)
    size = diameter(joints_a)
    distances = []
    for frame_a, frame_b in zip(frames_a, frames_b):
        a, b = positions(joints_a, frame_a), positions(joints_b, frame_b)
        distances += [math.dist(a[name], b[name]) / size for name in a if name in b]
    if not distances:
        sys.exit(f"{first} and {second} share no joint name")
    distances.sort()
    print(f"largest {distances[-1]:.4f}, median {distances[len(distances) // 2]:.4f} diameters "
          f"({min(len(frames_a), len(frames_b))} frames)")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: scripts/compare_bvh_positions.py A.bvh B.bvh")
    main(sys.argv[1], sys.argv[2])
