"""The nec add-on inside Blender (run by check_addon.sh):

  blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_addon.py -- \
      NEC ADDON.zip DATABASE ASSIMP_MODELS

Installs and enables the add-on from its zip, then, with the scene at 24 fps (nec's models run at 30):
  - Generate: two captions with their own lengths (2 s + 1 s) on an armature imported from a CMU BVH;
  - a walk generated onto the same armature without an action (its bind pose: a T-pose) stands like a person:
    upper arms within 45 degrees of hanging, thighs swinging (measured on the baked action in Blender);
  - Transfer: a CMU file onto the rig of huesitos.fbx (Blender's FBX importer: other bone rolls, an object
    transform), and the action of one armature onto another;
  - Search: a caption against DATABASE, two matches, each an action;
  - failures: no nec binary, no caption, a caption nec refuses; they add no action.
Both armatures' bones are rolled first (bone axes of their own, unlike the bones the importer gives nec's file).
Each result must be a new action on the selected armature, named after its caption, spanning the motion's length
at the scene's rate, with every bone's world position within 0.1 % of the armature's size, and its turn from its rest pose
within 0.05°, of the same joint in nec's own output file (read by Blender's BVH importer, which the interop tests check against nec's reader),
and its position within 0.1 % of the joint's by the file's own forward kinematics (scripts/compare_bvh_positions.py); the
armatures' existing actions must keep every key. Exits 1 on the first failed check."""
import glob
import math
import os
import sys

import addon_utils
import bpy
from mathutils import Vector

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import compare_bvh_positions as file_fk  # noqa: E402  (the BVH's own forward kinematics, neither Blender's nor nec's)

NEC, ZIP, DATABASE, MODELS = sys.argv[sys.argv.index("--") + 1:]
TOLERANCE = 1e-3  # of the armature's size
TURN_TOLERANCE = math.radians(0.05)
ARMS_FROM_HANGING = 45.0  # degrees: a T-pose is 90, a walk's arms hang within about 20
THIGH_SWING = 8.0  # degrees: a standing shuffle swings about 5, real walks 22-26 (issue 61: the GPT's walks 8-15)
FPS = 24


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def install():
    bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
    addon_utils.enable("nec_blender", default_set=True, handle_error=None)
    check("nec_blender" in bpy.context.preferences.addons, "the add-on did not enable")
    bpy.context.preferences.addons["nec_blender"].preferences.nec_path = NEC
    bpy.context.preferences.addons["nec_blender"].preferences.threads = 2


def select(obj):
    for other in bpy.context.view_layer.objects:
        other.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def import_cmu(path):
    before = set(bpy.data.objects)
    bpy.ops.import_anim.bvh(filepath=path, use_fps_scale=True, update_scene_fps=False, update_scene_duration=False)
    return next(o for o in bpy.data.objects if o not in before and o.type == 'ARMATURE')


def roll_bones(armature):
    select(armature)
    bpy.ops.object.mode_set(mode='EDIT')
    for i, bone in enumerate(armature.data.edit_bones):
        bone.roll += 0.4 * (i % 5 + 1)
    bpy.ops.object.mode_set(mode='OBJECT')


def keys_of(action):
    return {(c.data_path, c.array_index): [tuple(k.co) for k in c.keyframe_points] for c in action.fcurves}


def snapshot():
    return {a.name: keys_of(a) for a in bpy.data.actions}


def size_of(armature):
    heads = [armature.matrix_world @ b.head_local for b in armature.data.bones]
    return max((a - b).length for a in heads for b in heads)


def newest_work_folder():
    folders = glob.glob(os.path.join(bpy.app.tempdir, "nec_*"))
    return max(folders, key=os.path.getmtime)


def reference(path):
    """nec's output as Blender's importer reads it, in the armature space the rig was exported in."""
    before = set(bpy.data.objects)
    bpy.ops.import_anim.bvh(filepath=path, axis_forward='Y', axis_up='Z', rotate_mode='NATIVE', frame_start=1,
                            use_fps_scale=True, update_scene_fps=False, update_scene_duration=False)
    return next(o for o in bpy.data.objects if o not in before and o.type == 'ARMATURE')


def frames_of(path):
    with open(path) as bvh:
        text = bvh.read()
    frames = int(text.split("Frames:")[1].split()[0])
    frame_time = float(text.split("Frame Time:")[1].split()[0])
    return frames, frame_time


def check_action(armature, action, path, label):
    """The action plays nec's file `path` on `armature`: length at the scene's rate and every joint's position."""
    check(armature.animation_data.action == action, f"{label}: the new action is not the armature's action")
    frames, frame_time = frames_of(path)
    expected_last = 1 + (frames - 1) * frame_time * FPS
    first, last = action.frame_range
    check(first == 1 and abs(last - expected_last) <= 1,
          f"{label}: action spans frames {first}-{last}, the file {frames} frames at {1 / frame_time:g} fps "
          f"(last frame {expected_last:.1f} at {FPS} fps)")
    source = reference(path)
    size = size_of(armature)
    worst, where, worst_turn, where_turn = 0.0, None, 0.0, None
    missing = [b.name for b in armature.pose.bones if b.name not in source.pose.bones]
    check(not missing, f"{label}: nec's file has no joint for the bones {missing[:5]} ({len(missing)} in all): "
                       f"they could not be compared")
    for frame in sorted({1, int(last) // 2, int(last)}):
        bpy.context.scene.frame_set(frame)
        for bone in armature.pose.bones:
            joint = source.pose.bones[bone.name]
            # the rig went out in its armature space, so nec's joints are in that space: place them in the world
            error = (armature.matrix_world @ bone.head - armature.matrix_world @ joint.head).length / size
            if error > worst:
                worst, where = error, (frame, bone.name)
            # what a skinned mesh follows: each bone's turn from its rest pose, whatever its own axes (roll)
            made = bone.matrix.to_quaternion() @ bone.bone.matrix_local.to_quaternion().inverted()
            wanted = joint.matrix.to_quaternion() @ joint.bone.matrix_local.to_quaternion().inverted()
            gap = made.rotation_difference(wanted)  # its angle from the axis part: exact for small angles
            turn = 2 * math.asin(min(1.0, math.sqrt(gap.x ** 2 + gap.y ** 2 + gap.z ** 2)))
            if turn > worst_turn:
                worst_turn, where_turn = turn, (frame, bone.name)
    bpy.data.objects.remove(source, do_unlink=True)
    # Against the file's own forward kinematics too (not Blender's importer): at the scene frames that fall on a
    # frame of the file (24 of its 30 fps: every fourth), the first, middle and last of them.
    joints, file_frames = file_fk.read_bvh(path)
    on_file = [f for f in range(1, int(last) + 1)
               if abs((f - 1) / FPS / frame_time - round((f - 1) / FPS / frame_time)) < 1e-3
               and round((f - 1) / FPS / frame_time) < len(file_frames)]
    fk_worst, fk_where, compared = 0.0, None, 0
    for frame in sorted({on_file[0], on_file[len(on_file) // 2], on_file[-1]}):
        bpy.context.scene.frame_set(frame)
        places = file_fk.positions(joints, file_frames[round((frame - 1) / FPS / frame_time)])
        for bone in armature.pose.bones:
            gap = (armature.matrix_world @ Vector(places[bone.name]) - armature.matrix_world @ bone.head).length / size
            compared += 1
            if gap > fk_worst:
                fk_worst, fk_where = gap, (frame, bone.name)
    check(compared == 3 * len(armature.pose.bones) or (len(on_file) < 3 and compared > 0),
          f"{label}: {compared} bone positions compared with the file's forward kinematics")
    print(f"{label}: against the file's own forward kinematics ({compared} bone positions): largest gap "
          f"{fk_worst:.2e} (at {fk_where})", flush=True)
    check(fk_worst <= TOLERANCE, f"{label}: a bone is {fk_worst:.2e} of the armature's size from the file's own "
                                 f"forward kinematics at {fk_where}")
    print(f"{label}: {len(armature.pose.bones)} bones, frames 1-{last:g}: largest joint gap {worst:.2e} of the "
          f"armature's size (at frame, bone {where}), largest turn gap {math.degrees(worst_turn):.2e}° "
          f"(at {where_turn})", flush=True)
    check(worst <= TOLERANCE, f"{label}: a bone is {worst:.2e} of the armature's size from nec's joint at {where}")
    check(worst_turn <= TURN_TOLERANCE, f"{label}: a bone turns {math.degrees(worst_turn):.3f}° otherwise than "
                                        f"nec's joint at {where_turn}")


def run(operator, label):
    before = snapshot()
    active = bpy.context.view_layer.objects.active
    result = operator()
    check(result == {'FINISHED'}, f"{label}: the operator returned {result}")
    check(bpy.context.view_layer.objects.active == active and active.select_get(),
          f"{label}: the armature is no longer the selected, active object")
    after = snapshot()
    for name, keys in before.items():
        check(after.get(name) == keys, f"{label}: the existing action {name} changed")
    return [bpy.data.actions[name] for name in after if name not in before]


def check_generate(person):
    settings = bpy.context.scene.nec
    settings.captions.clear()
    for text, seconds in (("a person walks forward", 2.0), ("a person jumps", 1.0)):
        caption = settings.captions.add()
        caption.text, caption.seconds = text, seconds
    settings.seed = 3
    select(person)
    made = run(bpy.ops.nec.generate, "generate")
    check(len(made) == 1 and made[0].name == "a person walks forward / a person jumps",
          f"generate: new actions {[a.name for a in made]}")
    path = os.path.join(newest_work_folder(), "generated.bvh")
    frames, frame_time = frames_of(path)
    check(abs(frames * frame_time - 3.0) < 0.2, f"generate: {frames} frames of {frame_time} s for 2 s + 1 s")
    check_action(person, made[0], path, "generate (CMU armature)")


def limbs_of(armature, first, last):
    """Upper arms' median angle from hanging and the thighs' forward swing (5th to 95th percentile of each thigh's
    angle in the body's forward-down plane, the two sides' mean), in degrees, from the bones' world positions over
    the frames first..last: what `nec info` calls its limbs line, measured here on the armature Blender plays."""
    def head(name):
        return armature.matrix_world @ armature.pose.bones[name].head

    hanging, pitch = [], {"Left": [], "Right": []}
    down = Vector((0.0, 0.0, -1.0))
    for frame in range(first, last + 1):
        bpy.context.scene.frame_set(frame)
        for side in ("Left", "Right"):
            arm = (head(side + "ForeArm") - head(side + "Arm")).normalized()
            hanging.append(math.acos(max(-1.0, min(1.0, arm.dot(down)))))
        across = head("LeftUpLeg") - head("RightUpLeg")
        across.z = 0.0
        forward = across.normalized().cross(-down)
        for side in ("Left", "Right"):
            thigh = (head(side + "Leg") - head(side + "UpLeg")).normalized()
            pitch[side].append(math.atan2(thigh.dot(forward), thigh.dot(down)))

    def quantile(values, q):
        ordered = sorted(values)
        return ordered[min(len(ordered) - 1, int(q * len(ordered)))]

    arms = math.degrees(quantile(hanging, 0.5))
    swing = sum(math.degrees(quantile(p, 0.95) - quantile(p, 0.05)) for p in pitch.values()) / 2
    return arms, swing


def check_tposed_walk():
    """A CMU armature with no action stands in its bind pose, a T-pose: a walk generated onto it must bring the
    arms down (before the stance network they stayed out, 84-87 degrees from hanging) and swing the thighs."""
    person = import_cmu(os.path.join(MODELS, "BVH", "01_01.bvh"))
    person.animation_data_clear()
    for bone in person.pose.bones:
        bone.matrix_basis.identity()
    bpy.context.scene.frame_set(1)
    settings = bpy.context.scene.nec
    settings.captions.clear()
    caption = settings.captions.add()
    caption.text, caption.seconds = "a person walks forward", 4.0
    settings.seed = 1
    select(person)
    made = run(bpy.ops.nec.generate, "generate onto a T-pose")
    check(len(made) == 1, f"generate onto a T-pose: new actions {[a.name for a in made]}")
    check_action(person, made[0], os.path.join(newest_work_folder(), "generated.bvh"), "generate onto a T-pose")
    first, last = (int(f) for f in made[0].frame_range)
    arms, swing = limbs_of(person, first, last)
    print(f"T-posed armature, 'a person walks forward' (4 s, seed 1): upper arms {arms:.1f} degrees from hanging, "
          f"thigh swing {swing:.1f} degrees; {os.path.join(newest_work_folder(), 'generated.bvh')}", flush=True)
    check(arms <= ARMS_FROM_HANGING, f"generate onto a T-pose: the upper arms stay {arms:.1f} degrees from hanging "
                                     f"(at most {ARMS_FROM_HANGING})")
    check(swing >= THIGH_SWING, f"generate onto a T-pose: the thighs swing {swing:.1f} degrees (at least "
                                f"{THIGH_SWING}): the body does not step")
    bpy.data.objects.remove(person, do_unlink=True)


def check_transfer(creature, person):
    settings = bpy.context.scene.nec
    settings.source_file = os.path.join(MODELS, "BVH", "Boxing_Toes.bvh")
    select(creature)
    made = run(bpy.ops.nec.transfer, "transfer from a file")
    check(len(made) == 1 and made[0].name == "transfer: Boxing_Toes.bvh", f"transfer: {[a.name for a in made]}")
    check_action(creature, made[0], os.path.join(newest_work_folder(), "transferred.bvh"), "transfer onto huesitos.fbx")

    # From another armature's action: a short made-up motion of the CMU armature.
    action = bpy.data.actions.new("arms up")
    person.animation_data.action = action
    for frame, angle in ((1, 0.0), (24, 1.2), (48, 0.0)):
        for name in ("LeftArm", "RightArm"):
            bone = person.pose.bones[name]
            bone.rotation_mode = 'XYZ'
            bone.rotation_euler = (0.0, 0.0, angle if name == "LeftArm" else -angle)
            bone.keyframe_insert("rotation_euler", frame=frame)
        person.pose.bones["Hips"].location = (0.0, 0.0, frame * 0.02)
        person.pose.bones["Hips"].keyframe_insert("location", frame=frame)
    settings.source_file = ""
    settings.source_armature = person
    select(creature)
    made = run(bpy.ops.nec.transfer, "transfer from an armature")
    check(len(made) == 1 and made[0].name == f"transfer: {person.name}: arms up",
          f"transfer from an armature: {[a.name for a in made]}")
    check_action(creature, made[0], os.path.join(newest_work_folder(), "transferred.bvh"), "armature onto creature")


def check_search(person):
    settings = bpy.context.scene.nec
    settings.database, settings.query, settings.results = DATABASE, "a person walks", 2
    select(person)
    made = run(bpy.ops.nec.search, "search")
    check(len(made) == 2 and made[0].name.startswith("1. ") and made[1].name.startswith("2. "),
          f"search: {[a.name for a in made]}")
    check_action(person, made[1], os.path.join(newest_work_folder(), "match_2.bvh"), "search match 2")


def expect_error(operator, words, label):
    """Called from Python, an operator that reports an error raises it: the message must name the problem."""
    try:
        result = operator()
    except RuntimeError as error:
        check(words in str(error), f"{label}: the error says '{error}', not '{words}'")
        return
    raise AssertionError(f"{label}: the operator returned {result} without an error")


def check_failures(person):
    settings = bpy.context.scene.nec
    select(person)
    preferences = bpy.context.preferences.addons["nec_blender"].preferences
    before = set(bpy.data.actions)
    preferences.nec_path = "/no/such/nec"
    expect_error(bpy.ops.nec.generate, "the nec binary was not found", "a missing binary")
    preferences.nec_path = NEC
    settings.captions.clear()
    expect_error(bpy.ops.nec.generate, "no caption", "no caption")
    settings.captions.add().text = "?!"
    expect_error(bpy.ops.nec.generate, "nec generate failed (exit 1): nec: error: the caption: no letters in",
                 "a caption nec refuses")
    settings.source_file = "/no/such/walk.bvh"
    expect_error(bpy.ops.nec.transfer, "/no/such/walk.bvh: no such file", "a missing source file")
    check(set(bpy.data.actions) == before, "a failed run added an action")
    print("failures: a missing binary, no caption, a refused caption and a missing file are errors that say so "
          "and add no action", flush=True)


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    install()
    person = import_cmu(os.path.join(MODELS, "BVH", "01_01.bvh"))
    bpy.ops.import_scene.fbx(filepath=os.path.join(MODELS, "FBX", "huesitos.fbx"))
    creature = next(o for o in bpy.data.objects if o.type == 'ARMATURE' and o != person)
    # placed in the scene as users place rigs: turned, scaled and moved (nec works in its armature space)
    creature.rotation_euler, creature.scale, creature.location = (0.3, 0.0, 1.2), (2.0, 2.0, 2.0), (5.0, 0.0, 0.0)
    for armature in (person, creature):  # bone axes of their own (rigs made by hand), unlike those nec's file gets
        roll_bones(armature)
    bpy.context.scene.render.fps = FPS  # after the imports: the FBX importer sets the scene's rate to the file's
    bpy.context.view_layer.update()
    print(f"armatures: {person.name} ({len(person.data.bones)} bones), {creature.name} "
          f"({len(creature.data.bones)} bones, object scale {tuple(round(s, 3) for s in creature.scale)})", flush=True)
    check_generate(person)
    check_transfer(creature, person)
    check_search(person)
    check_failures(person)
    check_tposed_walk()
    print("blender add-on: all checks passed", flush=True)


try:
    main()
except Exception as error:  # a failed check or a Blender error: say it, exit 1
    import traceback
    traceback.print_exc()
    print(f"blender add-on: FAILED: {error}", flush=True)
    sys.exit(1)
