# Imports BVH files written by nec with Blender's importer (io_anim_bvh) and
# checks them against nec's own reader and against the source file.
#
#   blender -b --factory-startup --python-exit-code 1 \
#       --python tests/interop/blender_import.py -- MANIFEST.tsv
#
# MANIFEST rows (tab-separated): label, source file, file written by nec, and
# what nec's reader sees in the written file: joints, end sites, frames.
# Blender makes one bone per joint; an End Site is no bone, it only places the
# tail of its joint's bone. Motion lines become keys at frames 1..N (frame 0 of
# the file lands on scene frame 1). So we check:
#   bones == joints, action frame range == (1, frames),
#   and the world head and tail of every bone at the first, middle and last
#   frame equal those of the source file imported the same way (relative
#   tolerance 1e-5; Blender computes in single precision). When Blender cannot
#   import the source itself, only the counts are checked (and it says so).
# Prints one line per file; exits with status 1 when any check fails.
import sys

import bpy
import io_anim_bvh.import_bvh

TOLERANCE = 1e-5  # max position difference / extent of the source pose


# Blender 3.4's importer opens files with mode 'rU', which Python 3.11 (the one
# Debian bookworm's blender runs on) no longer accepts: every import fails with
# "ValueError: invalid mode: 'rU'". Python 3 text mode already reads universal
# newlines, so the importer's module gets an open() that drops the 'U'.
def _open_without_u(file, mode="r", *args, **kwargs):
    return open(file, mode.replace("U", ""), *args, **kwargs)


io_anim_bvh.import_bvh.open = _open_without_u


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for collection in (bpy.data.armatures, bpy.data.actions):
        for item in list(collection):
            collection.remove(item)


def import_bvh(path):
    """Imports `path` into an empty scene; returns the armature object."""
    clear_scene()
    bpy.ops.import_anim.bvh(filepath=path, rotate_mode='NATIVE', frame_start=1, use_fps_scale=False,
                            update_scene_fps=False, update_scene_duration=False)
    armatures = [obj for obj in bpy.data.objects if obj.type == 'ARMATURE']
    if len(armatures) != 1:
        raise RuntimeError("expected one armature, found %d" % len(armatures))
    return armatures[0]


def reason(error):
    """The Python exception line of an operator error (its message holds the whole traceback)."""
    lines = [line for line in str(error).splitlines() if line.strip()]
    exception_lines = [line for line in lines if line.split(":")[0].endswith(("Error", "Exception"))]
    return (exception_lines or lines or ["unknown error"])[-1].strip()


def world_points(armature, frame):
    """World heads and tails of all bones at BVH frame `frame` (0-based)."""
    bpy.context.scene.frame_set(1 + frame)
    points = []
    for bone in armature.pose.bones:
        points.append(armature.matrix_world @ bone.head)
        points.append(armature.matrix_world @ bone.tail)
    return points


def source_poses(path, frames):
    armature = import_bvh(path)
    return [bone.name for bone in armature.pose.bones], {f: world_points(armature, f) for f in frames}


def max_difference(reference, points):
    difference = max((a - b).length for a, b in zip(reference, points))
    extent = max((a - reference[0]).length for a in reference)
    return difference / max(extent, 1e-9)


def check(label, source, written, joints, end_sites, frames):
    problems = []
    try:
        armature = import_bvh(written)
    except Exception as error:  # the importer raises plain Exceptions
        return ["import failed: %s" % reason(error)], "unreadable"
    bones = len(armature.data.bones)
    action = armature.animation_data.action if armature.animation_data else None
    start, end = action.frame_range if action else (0.0, -1.0)
    blender_frames = int(round(end - start)) + 1
    seen = "%d bones, frames %g..%g (%d)" % (bones, start, end, blender_frames)
    if bones != joints:
        problems.append("bones %d != nec joints %d" % (bones, joints))
    if (start, blender_frames) != (1.0, frames):
        problems.append("frame range %g..%g != 1..%d" % (start, end, frames))
    if problems:
        return problems, seen
    sample = sorted({0, frames // 2, frames - 1})
    names = [bone.name for bone in armature.pose.bones]
    poses = {f: world_points(armature, f) for f in sample}
    try:
        source_names, source = source_poses(source, sample)
    except Exception as error:
        return problems, seen + " (positions not compared: the source does not import: %s)" % reason(error)
    if source_names != names:
        problems.append("bone names differ from the source import")
        return problems, seen
    worst = max(max_difference(source[f], poses[f]) for f in sample)
    seen += ", max head/tail difference vs source %.1e" % worst
    if not worst <= TOLERANCE:
        problems.append("bone heads/tails differ from the source by %g (relative)" % worst)
    return problems, seen


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        print("usage: blender -b --python blender_import.py -- MANIFEST.tsv")
        sys.exit(2)
    failures = 0
    with open(argv[0]) as manifest:
        rows = [line.rstrip("\n").split("\t") for line in manifest if line.strip()]
    for label, source, written, joints, end_sites, frames in rows:
        problems, seen = check(label, source, written, int(joints), int(end_sites), int(frames))
        failures += bool(problems)
        # Every line starts with "blender <version>": check_import.sh picks them out of Blender's own output.
        prefix = "blender %s " % bpy.app.version_string
        print("%s%s %s: %s" % (prefix, "FAIL" if problems else "ok  ", label, seen), flush=True)
        for problem in problems:
            print("%s    %s" % (prefix, problem), flush=True)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":  # blender_export_assets.py imports import_bvh from here
    main()
