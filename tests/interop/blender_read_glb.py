# Imports a GLB written by nec with Blender's glTF importer and prints the world
# position of every bone's head in every frame of one animation, in glTF's
# axes (+Y up), for test_asset_roundtrip.cpp to compare with nec's own FK.
#
#   blender -b --factory-startup --python-exit-code 1 \
#       --python tests/interop/blender_read_glb.py -- IN.glb ANIMATION FPS OUT.tsv
#
# OUT rows: frame index (0 = the animation's first key), bone name, x, y, z.
# Also prints the meshes imported and the vertex groups (skin) of the first.
import sys

import bpy
import numpy

# Debian bookworm's Blender 3.4 glTF importer calls numpy.bool, which its numpy
# (1.24) no longer has: importing any glTF with a mesh fails with
# "module 'numpy' has no attribute 'bool'". numpy.bool was the builtin bool.
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    path, animation, fps, out_path = args[0], args[1], int(args[2]), args[3]
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    bpy.context.scene.render.fps = fps
    bpy.context.scene.render.fps_base = 1.0
    bpy.ops.import_scene.gltf(filepath=path)
    armatures = [obj for obj in bpy.data.objects if obj.type == 'ARMATURE']
    meshes = [obj for obj in bpy.data.objects if obj.type == 'MESH']
    if len(armatures) != 1:
        raise RuntimeError("expected one armature, found %d" % len(armatures))
    armature = armatures[0]
    actions = [a for a in bpy.data.actions if a.name == animation or a.name.startswith(animation + "_")]
    if not actions:
        raise RuntimeError("no action '%s' among %s" % (animation, [a.name for a in bpy.data.actions]))
    armature.animation_data.action = actions[0]
    first, last = (int(round(f)) for f in actions[0].frame_range)
    groups = len(meshes[0].vertex_groups) if meshes else 0
    print("blender %s: %d mesh(es), %d vertex groups on the first, action '%s' frames %d-%d"
          % (bpy.app.version_string, len(meshes), groups, actions[0].name, first, last), flush=True)
    scene = bpy.context.scene
    with open(out_path, "w") as out:
        for frame in range(first, last + 1):
            scene.frame_set(frame)
            for bone in armature.pose.bones:
                p = armature.matrix_world @ bone.head
                out.write("%d\t%s\t%.7g\t%.7g\t%.7g\n" % (frame - first, bone.name, p.x, p.z, -p.y))


main()
