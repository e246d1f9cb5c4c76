"""The Blender add-on's Generate as a user presses it: seconds from the operator's call to the new action on the
armature (export of the rig, nec, the bake), with the models kept loaded in one `nec worker` (the default) and with
a new nec process per press, taking turns, in the same Blender.

    blender -b --factory-startup --python benchmarks/blender_generate.py -- NEC_BINARY [REPEAT]

On the CMU 01_01 armature (31 bones), "a person walks forward", 4 s, the default GPT, seeds 1..REPEAT (default 5).
Prints a Markdown table: the first press, the median (fastest - slowest) of the later presses.
"""
import os
import statistics
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender"))
import nec_blender  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if not args:
    raise SystemExit("usage: blender -b --python benchmarks/blender_generate.py -- NEC_BINARY [REPEAT]")
NEC, REPEAT = os.path.abspath(args[0]), int(args[1]) if len(args) > 1 else 5


class Preferences:  # what the add-on reads from Preferences → Add-ons → nec (the add-on is loaded from the tree)
    nec_path, models, threads, keep_loaded = NEC, "", 2, True


nec_blender.preferences = lambda context: Preferences
nec_blender.register()
bpy.ops.import_anim.bvh(filepath="/usr/share/assimp/models/BVH/01_01.bvh", update_scene_fps=False,
                        update_scene_duration=False)
armature = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
bpy.context.view_layer.objects.active = armature
settings = bpy.context.scene.nec
caption = settings.captions.add()
caption.text, caption.seconds = "a person walks forward", 4.0

times = {True: [], False: []}
for seed in range(REPEAT + 1):
    for keep in (True, False):
        Preferences.keep_loaded = keep
        settings.seed = seed
        start = time.perf_counter()
        if bpy.ops.nec.generate() != {'FINISHED'}:
            raise SystemExit("blender_generate.py: Generate failed")
        times[keep].append(time.perf_counter() - start)
nec_blender.unregister()
print(f"\n| Blender add-on, Generate (4-s walk, 31 bones) | first press, s | later presses, median of {REPEAT} "
      f"(fastest - slowest), s |\n|---|---:|---:|")
for keep, label in ((True, "models kept loaded (nec worker, default)"), (False, "a new nec process per press")):
    later = times[keep][1:]
    print(f"| {label} | {times[keep][0]:.2f} | {statistics.median(later):.3f} ({min(later):.3f} - {max(later):.3f}) |")
print()
