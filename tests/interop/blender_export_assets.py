# Exports BVH files as FBX and GLB with Blender, as a user would move a rig
# from BVH into an asset pipeline: import (Blender's BVH importer, scene rate
# set to the file's), then File > Export > FBX and glTF 2.0 (binary) with
# their default axes and units, animation baked (FBX without key thinning).
#
#   blender -b --factory-startup --python-exit-code 1 \
#       --python tests/interop/blender_export_assets.py -- OUTDIR SOURCE.bvh...
#
# Writes OUTDIR/STEM.fbx, OUTDIR/STEM_zup.fbx (exported +Z up) and OUTDIR/STEM.glb for every source.
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_import import clear_scene  # noqa: E402  (also installs the importer's 'rU' fix)


def export(source, out_dir):
    clear_scene()
    bpy.ops.import_anim.bvh(filepath=source, rotate_mode='NATIVE', frame_start=1, use_fps_scale=False,
                            update_scene_fps=True, update_scene_duration=True)
    # The importer only ever extends the scene's frame range: set it to this file's keys.
    armature = next(obj for obj in bpy.data.objects if obj.type == 'ARMATURE')
    first, last = armature.animation_data.action.frame_range
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = int(round(first)), int(round(last))
    stem = os.path.splitext(os.path.basename(source))[0]
    bpy.ops.export_scene.fbx(filepath=os.path.join(out_dir, stem + ".fbx"), bake_anim=True,
                             add_leaf_bones=True, bake_anim_use_nla_strips=False, bake_anim_use_all_actions=False,
                             bake_anim_simplify_factor=0.0)  # every frame as it is (the default thins keys)
    # The same with +Z up (3ds Max's convention): nec must apply the FBX axis metadata.
    bpy.ops.export_scene.fbx(filepath=os.path.join(out_dir, stem + "_zup.fbx"), bake_anim=True,
                             add_leaf_bones=True, bake_anim_use_nla_strips=False, bake_anim_use_all_actions=False,
                             bake_anim_simplify_factor=0.0, axis_forward='Y', axis_up='Z')
    bpy.ops.export_scene.gltf(filepath=os.path.join(out_dir, stem + ".glb"), export_format='GLB',
                              export_animations=True, export_optimize_animation_size=False)
    print("blender %s exported %s" % (bpy.app.version_string, stem), flush=True)


def main():
    args = sys.argv[sys.argv.index("--") + 1:]
    out_dir, sources = args[0], args[1:]
    for source in sources:
        export(source, out_dir)


main()
