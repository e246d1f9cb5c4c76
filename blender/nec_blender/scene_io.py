"""Armatures out to BVH for nec, and nec's BVH back onto the same armature as a new action (bpy)."""
import math
import tempfile

import bpy
import io_anim_bvh.import_bvh
from mathutils import Euler, Matrix


def _open_without_u(file, mode="r", *args, **kwargs):
    return open(file, mode.replace("U", ""), *args, **kwargs)


# Blender 3.4's BVH importer opens files with mode 'rU', which Python 3.11 (Debian's Blender) refuses; text mode
# already reads universal newlines, so the importer gets an open() without the 'U'.
io_anim_bvh.import_bvh.open = _open_without_u


def _export_bvh(armature, path, first, last):
    scene = bpy.context.scene
    frame_before = scene.frame_current
    with bpy.context.temp_override(selected_objects=[armature], active_object=armature, object=armature,
                                   selected_editable_objects=[armature]):
        bpy.ops.export_anim.bvh(filepath=path, check_existing=False, frame_start=first, frame_end=last,
                                root_transform_only=False, global_scale=1.0)
    scene.frame_set(frame_before)
    return path


def export_rig_bvh(armature, path):
    """The armature's skeleton as a one-frame BVH in its armature space (bone names, rest offsets), the file nec
    generates for (`--skeleton`) or transfers onto (`--to`); nec writes its results in the same axes and units."""
    frame = bpy.context.scene.frame_current
    return _export_bvh(armature, path, frame, frame)


def export_motion_bvh(armature, action, path):
    """The armature playing `action` (its current one) over the action's frames, as BVH: a source for transfer."""
    first, last = action.frame_range
    return _export_bvh(armature, path, int(math.floor(first)), int(math.ceil(last)))


def _hierarchy(armature):
    """Pose bones, parents before children."""
    ordered = []

    def visit(bone):
        ordered.append(armature.pose.bones[bone.name])
        for child in bone.children:
            visit(child)

    for bone in armature.data.bones:
        if bone.parent is None:
            visit(bone)
    return ordered


def _import_bvh(path):
    """Imports nec's BVH as its own armature, axes as written (the rig was exported in armature space), keys at the
    scene's frame rate from frame 1. Returns the new armature object and everything the import added."""
    before_objects = set(bpy.data.objects)
    before_actions = set(bpy.data.actions)
    bpy.ops.import_anim.bvh(filepath=path, axis_forward='Y', axis_up='Z', rotate_mode='NATIVE', frame_start=1,
                            use_fps_scale=True, update_scene_fps=False, update_scene_duration=False,
                            global_scale=1.0)
    created = [o for o in bpy.data.objects if o not in before_objects]
    armatures = [o for o in created if o.type == 'ARMATURE']
    if not armatures or armatures[0].animation_data is None or armatures[0].animation_data.action is None:
        _remove(created, [a for a in bpy.data.actions if a not in before_actions])
        raise RuntimeError(f"{path}: Blender's importer made no animated armature of it")
    return armatures[0], created, [a for a in bpy.data.actions if a not in before_actions]


def _remove(objects, actions):
    for obj in objects:
        data = obj.data
        bpy.data.objects.remove(obj, do_unlink=True)
        if isinstance(data, bpy.types.Armature) and data.users == 0:
            bpy.data.armatures.remove(data)
    for action in actions:
        bpy.data.actions.remove(action)


def _rotation_channels(pose_bone, quaternion, previous):
    """The bone's rotation in its own rotation mode, continuous with `previous` (the last frame's values)."""
    mode = pose_bone.rotation_mode
    if mode == 'QUATERNION':
        if previous is not None and sum(a * b for a, b in zip(quaternion, previous)) < 0:
            quaternion = -quaternion
        return "rotation_quaternion", tuple(quaternion)
    if mode == 'AXIS_ANGLE':
        axis, angle = quaternion.to_axis_angle()
        return "rotation_axis_angle", (angle, *axis)
    euler = quaternion.to_euler(mode) if previous is None else quaternion.to_euler(mode, Euler(previous, mode))
    return "rotation_euler", tuple(euler)


def bake_bvh_onto(armature, bvh_path, action_name):
    """Bakes the motion of `bvh_path` (written by nec for this armature: its bone names, rest offsets and armature
    axes) onto `armature` as a new action called `action_name`, one key per frame of the scene's rate from frame 1.
    Each bone turns as its namesake does relative to its rest pose, whatever the two armatures' bone rolls; every
    bone that may move is placed at its namesake's head. The armature's previous action is kept (fake user) and
    nothing else in the file changes. Returns the action and the names of bones nec's file has no joint for."""
    scene = bpy.context.scene
    frame_before = scene.frame_current
    layer = bpy.context.view_layer
    active_before, selected_before = layer.objects.active, [o for o in layer.objects if o.select_get()]
    source, created, imported_actions = _import_bvh(bvh_path)
    try:
        first, last = source.animation_data.action.frame_range
        frames = list(range(int(math.floor(first)), int(math.ceil(last)) + 1))
        bones = _hierarchy(armature)
        missing = [b.name for b in bones if b.name not in source.pose.bones]
        if len(missing) == len(bones):
            raise RuntimeError(f"{bvh_path}: none of its joints is a bone of {armature.name}")
        rest = {b.name: b.bone.matrix_local.copy() for b in bones}
        source_rest = {b.name: source.data.bones[b.name].matrix_local.to_quaternion() for b in bones
                       if b.name not in missing}
        # basis of each bone at each frame: the pose that puts it where nec's joint is (armature space)
        keys = {b.name: [] for b in bones}
        for frame in frames:
            scene.frame_set(frame)
            posed = {}
            for pose_bone in bones:
                name = pose_bone.name
                parent = pose_bone.parent
                if name in source_rest:
                    joint = source.pose.bones[name].matrix
                    turn = joint.to_quaternion() @ source_rest[name].inverted()
                    target = Matrix.LocRotScale(joint.translation, turn @ rest[name].to_quaternion(), None)
                elif parent is not None:  # no joint: keep its rest pose under its parent
                    target = posed[parent.name] @ rest[parent.name].inverted() @ rest[name]
                else:
                    target = rest[name]
                posed[name] = target
                parent_space = rest[name] if parent is None else \
                    posed[parent.name] @ rest[parent.name].inverted() @ rest[name]
                keys[name].append(parent_space.inverted() @ target)
        action = _write_action(armature, bones, frames, keys, action_name)
    finally:
        _remove(created, imported_actions)
        scene.frame_set(frame_before)
        for obj in selected_before:
            obj.select_set(True)
        layer.objects.active = active_before
    return action, missing


def _write_action(armature, bones, frames, keys, action_name):
    action = bpy.data.actions.new(action_name)
    for pose_bone in bones:
        name = pose_bone.name
        path = f'pose.bones["{bpy.utils.escape_identifier(name)}"]'
        channels = {}
        previous = None
        for basis in keys[name]:
            location, quaternion, _ = basis.decompose()
            rotation_path, values = _rotation_channels(pose_bone, quaternion, previous)
            previous = values
            channels.setdefault(rotation_path, []).append(values)
            if not pose_bone.bone.use_connect:
                channels.setdefault("location", []).append(tuple(location))
        for channel, samples in channels.items():
            for index in range(len(samples[0])):
                curve = action.fcurves.new(f"{path}.{channel}", index=index, action_group=name)
                curve.keyframe_points.add(len(frames))
                curve.keyframe_points.foreach_set("co", [v for f, s in zip(frames, samples) for v in (f, s[index])])
                for point in curve.keyframe_points:
                    point.interpolation = 'LINEAR'
                curve.update()
    if armature.animation_data is None:
        armature.animation_data_create()
    elif armature.animation_data.action is not None:
        armature.animation_data.action.use_fake_user = True
    armature.animation_data.action = action
    return action


def action_name_for(caption, limit=60):
    text = " ".join(caption.split())
    return (text[: limit - 1] + "…") if len(text) > limit else text


def work_folder():
    """A fresh folder for one run's files (the rig, nec's output) inside Blender's session temp folder."""
    return tempfile.mkdtemp(prefix="nec_", dir=bpy.app.tempdir or None)
