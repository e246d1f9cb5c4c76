#!/usr/bin/env python3
"""Writes a Mixamo-style human as a one-frame BVH in its T-pose (65 joints named mixamorig:Hips ... with five
four-joint fingers a hand and *_End tips, centimetres, +Y up, facing +Z, every rotation 0): a character as users
export one, that no nec model was trained on. Proportions of an adult about 1.75 m tall.
  scripts/mixamo_tpose.py OUT.bvh [--first-pose-arms DEGREES]
--first-pose-arms: lower the arms that far in the one frame (an A-pose at 45).
"""
import sys

FINGERS = {  # first joint's offset from the hand (x along the arm, z forward), then the next three bone lengths
    "Thumb": ((2.5, -1.0, 3.0), (3.0, 2.8, 2.2)),
    "Index": ((9.0, 0.0, 2.5), (3.8, 2.4, 2.0)),
    "Middle": ((9.2, 0.0, 0.6), (4.2, 2.8, 2.2)),
    "Ring": ((8.8, 0.0, -1.3), (3.8, 2.5, 2.0)),
    "Pinky": ((8.0, 0.0, -3.2), (3.0, 2.0, 1.8)),
}


def joint(lines, depth, name, offset, children, end=None):
    pad = "  " * depth
    kind = "ROOT" if depth == 0 else "JOINT"
    lines.append(f"{pad}{kind} mixamorig:{name}")
    lines.append(f"{pad}{{")
    lines.append(f"{pad}  OFFSET {offset[0]:.4f} {offset[1]:.4f} {offset[2]:.4f}")
    if depth == 0:
        lines.append(f"{pad}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation")
    else:
        lines.append(f"{pad}  CHANNELS 3 Zrotation Xrotation Yrotation")
    for child in children:
        child(lines, depth + 1)
    if end is not None:
        lines.append(f"{pad}  End Site")
        lines.append(f"{pad}  {{")
        lines.append(f"{pad}    OFFSET {end[0]:.4f} {end[1]:.4f} {end[2]:.4f}")
        lines.append(f"{pad}  }}")
    lines.append(f"{pad}}}")


def chain(names, offsets, end):
    """A chain of joints: names[k] at offsets[k] from the one before; an end site after the last."""
    def build(lines, depth, k=0):
        last = k == len(names) - 1
        joint(lines, depth, names[k], offsets[k], [] if last else [lambda l, d: build(l, d, k + 1)],
              end if last else None)
    return build


def arm(side):
    s = 1.0 if side == "Left" else -1.0
    fingers = []
    for finger, (first, lengths) in FINGERS.items():
        offsets = [(s * first[0], first[1], first[2])] + [(s * length, 0.0, 0.0) for length in lengths]
        names = [f"{side}Hand{finger}{k}" for k in range(1, 5)]
        fingers.append(chain(names, offsets, (s * 1.5, 0.0, 0.0)))
    hand = lambda lines, depth: joint(lines, depth, f"{side}Hand", (s * 25.0, 0, 0), fingers)
    forearm = lambda lines, depth: joint(lines, depth, f"{side}ForeArm", (s * 27.0, 0, 0), [hand])
    upper = lambda lines, depth: joint(lines, depth, f"{side}Arm", (s * 12.0, 0, 0), [forearm])
    return lambda lines, depth: joint(lines, depth, f"{side}Shoulder", (s * 6.0, 10.0, 0), [upper])


def leg(side):
    s = 1.0 if side == "Left" else -1.0
    return chain([f"{side}UpLeg", f"{side}Leg", f"{side}Foot", f"{side}ToeBase", f"{side}Toe_End"],
                 [(s * 9.0, -6.0, 0.0), (0.0, -42.0, 0.0), (0.0, -42.0, 0.0), (0.0, -7.0, 12.0), (0.0, 0.0, 6.0)],
                 (0.0, 0.0, 1.0))


def main(out, arms_degrees):
    head = chain(["Neck", "Head", "HeadTop_End"], [(0, 15.0, 1.0), (0, 10.0, 1.0), (0, 18.0, 0)], (0, 1.0, 0))
    spine2 = lambda lines, depth: joint(lines, depth, "Spine2", (0, 13.0, 0), [head, arm("Left"), arm("Right")])
    spine1 = lambda lines, depth: joint(lines, depth, "Spine1", (0, 12.0, 0), [spine2])
    spine = lambda lines, depth: joint(lines, depth, "Spine", (0, 10.0, 0), [spine1])
    lines = ["HIERARCHY"]
    joint(lines, 0, "Hips", (0, 0, 0), [spine, leg("Left"), leg("Right")])
    names = [line.split()[1] for line in lines if line.split()[:1] in (["ROOT"], ["JOINT"])]
    values = []
    for name in names:
        if name == "mixamorig:Hips":
            values += [0.0, 100.0, 0.0, 0.0, 0.0, 0.0]
        elif name in ("mixamorig:LeftArm", "mixamorig:RightArm"):
            values += [(-arms_degrees if "Left" in name else arms_degrees), 0.0, 0.0]  # Zrotation lowers them
        else:
            values += [0.0, 0.0, 0.0]
    lines += ["MOTION", "Frames: 1", "Frame Time: 0.0333333", " ".join(f"{v:.4f}" for v in values)]
    with open(out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {out}: {len(names)} joints")


if __name__ == "__main__":
    args = sys.argv[1:]
    degrees = 0.0
    if len(args) == 3 and args[1] == "--first-pose-arms":
        degrees = float(args[2])
        args = args[:1]
    if len(args) != 1:
        sys.exit("usage: scripts/mixamo_tpose.py OUT.bvh [--first-pose-arms DEGREES]")
    main(args[0], degrees)
