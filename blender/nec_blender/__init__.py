"""nec in Blender: motion from text, motion transfer and text search for the selected armature. Each result comes
back as a new action on that armature (its bones and rest pose unchanged); the `nec` binary does the work, in
one `nec worker` process kept for the Blender session so that the models load once (Preferences → Add-ons →
nec: its path, an optional models folder, whether to keep the models loaded)."""
bl_info = {
    "name": "nec",
    "description": "Motion from text, transfer and search for any armature, with the nec binary",
    "author": "the nec authors",
    "blender": (3, 4, 0),
    "version": (0, 1, 0),
    "location": "3D View → Sidebar → nec",
    "category": "Animation",
}

import os

import bpy

from . import runner, scene_io


class NecPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__
    nec_path: bpy.props.StringProperty(name="nec binary", subtype='FILE_PATH',
                                       description="the nec executable; empty: `nec` on the PATH")
    models: bpy.props.StringProperty(name="Models", subtype='DIR_PATH',
                                     description="a folder with gpt/, diffusion/ and evaluator/ models; "
                                                 "empty: nec's default models")
    threads: bpy.props.IntProperty(name="Threads", default=0, min=0, description="torch threads; 0: all cores")
    keep_loaded: bpy.props.BoolProperty(name="Keep models loaded", default=True,
                                        description="run nec in one process kept for the Blender session, which "
                                                    "loads the models once (the next generation is fast); off: a new "
                                                    "nec process for every command")

    def draw(self, context):
        for name in ("nec_path", "models", "threads", "keep_loaded"):
            self.layout.prop(self, name)


class NecCaption(bpy.types.PropertyGroup):
    text: bpy.props.StringProperty(name="Caption", default="a person walks forward")
    seconds: bpy.props.FloatProperty(name="Seconds", default=4.0, min=0.5, max=60.0)


def _is_armature(_, obj):
    return obj.type == 'ARMATURE'


class NecSettings(bpy.types.PropertyGroup):
    captions: bpy.props.CollectionProperty(type=NecCaption)
    model: bpy.props.EnumProperty(name="Model", items=[("gpt", "GPT", "motion tokens, decoded by the tokenizer"),
                                                       ("diffusion", "Diffusion", "denoised on the joints")])
    seed: bpy.props.IntProperty(name="Seed", default=0, min=0)
    samples: bpy.props.IntProperty(name="Samples", default=1, min=1, max=8, description="one action each")
    guidance: bpy.props.FloatProperty(name="Guidance", default=2.5, min=1.0, max=10.0)
    source_file: bpy.props.StringProperty(name="From file", subtype='FILE_PATH',
                                          description="a BVH, FBX, GLB or Collada file whose motion is transferred")
    source_armature: bpy.props.PointerProperty(name="From armature", type=bpy.types.Object, poll=_is_armature,
                                               description="another armature whose current action is transferred "
                                                           "(used when no file is given)")
    database: bpy.props.StringProperty(name="Database", subtype='DIR_PATH',
                                       description="a dataset cache made by `nec prepare`")
    query: bpy.props.StringProperty(name="Search", default="a person jumps")
    results: bpy.props.IntProperty(name="Results", default=3, min=1, max=10, description="one action each")


def preferences(context):
    return context.preferences.addons[__package__].preferences


def model_args(context, kind):
    """--model for `kind` (gpt, diffusion): the preferences' models folder, else nec's default model of that kind."""
    models = bpy.path.abspath(preferences(context).models)
    return ["--model", os.path.join(models, kind) if models else kind]


def common_args(context):
    return ["--threads", str(preferences(context).threads)]


class NecOperator(bpy.types.Operator):
    """Runs nec for the selected armature: modal in the UI (progress in the status bar, Esc cancels), at once in
    the background (blender -b runs no timers); the files it writes are baked onto the armature as new actions."""
    bl_options = {'REGISTER', 'UNDO'}
    _run = None
    _timer = None

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == 'ARMATURE'

    def steps(self, context, nec, rig, folder):
        """-> (commands for runner.NecRun, function returning [(BVH file, action name), ...] once they ran)."""
        raise NotImplementedError

    def prepare(self, context):
        nec = runner.find_nec(preferences(context).nec_path)
        if nec is None:
            raise runner.NecError("the nec binary was not found: set its path in Preferences → Add-ons → nec")
        self._nec = nec if preferences(context).keep_loaded else None
        self._armature = context.active_object
        self._folder = scene_io.work_folder()
        rig = scene_io.export_rig_bvh(self._armature, os.path.join(self._folder, "rig.bvh"))
        self._steps, self._outputs = self.steps(context, nec, rig, self._folder)

    def finish(self, context):
        made = []
        for bvh, name in self._outputs():
            action, missing = scene_io.bake_bvh_onto(self._armature, bvh, name)
            made.append(action.name)
            if missing:
                self.report({'WARNING'}, f"{len(missing)} bones without motion: {', '.join(missing[:5])}")
        self.report({'INFO'}, "nec: new actions: " + ", ".join(made))
        return {'FINISHED'}

    def execute(self, context):
        try:
            self.prepare(context)
            runner.NecRun(self._steps, cwd=self._folder, nec=self._nec).wait()
            return self.finish(context)
        except (runner.NecError, RuntimeError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}

    def invoke(self, context, event):
        try:
            self.prepare(context)
            self._run = runner.NecRun(self._steps, cwd=self._folder, nec=self._nec)
        except (runner.NecError, RuntimeError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        self._timer = context.window_manager.event_timer_add(0.2, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        if event.type == 'ESC':
            self._run.cancel()
            self._stop(context, "cancelled")
            return {'CANCELLED'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        lines, code = self._run.poll()
        if lines:
            context.workspace.status_text_set("nec: " + lines[-1][:120] + "   (Esc: cancel)")
        if code is None:
            return {'RUNNING_MODAL'}
        self._stop(context, None)
        if code != 0:
            self.report({'ERROR'}, self._run.error_message(code))
            return {'CANCELLED'}
        try:
            return self.finish(context)
        except (RuntimeError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}

    def cancel(self, context):
        if self._run is not None:
            self._run.cancel()
        self._stop(context, "cancelled")

    def _stop(self, context, message):
        if self._timer is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        context.workspace.status_text_set(None)
        if message:
            self.report({'INFO'}, "nec: " + message)


class NEC_OT_generate(NecOperator):
    """Motion from the captions, one segment each in order, for the selected armature"""
    bl_idname = "nec.generate"
    bl_label = "Generate"

    def steps(self, context, nec, rig, folder):
        settings = context.scene.nec
        captions = [c for c in settings.captions if c.text.strip()]
        if not captions:
            raise runner.NecError("no caption: add one and write what the motion shows")
        out = os.path.join(folder, "generated.bvh")
        argv = [nec, "generate", *[c.text for c in captions], "--skeleton", rig, "-o", out,
                "--seconds", ",".join(f"{c.seconds:g}" for c in captions), "--seed", str(settings.seed),
                "--samples", str(settings.samples), "--guidance", f"{settings.guidance:g}",
                *model_args(context, settings.model), *common_args(context)]
        name = scene_io.action_name_for(" / ".join(c.text for c in captions))
        if settings.samples == 1:
            outputs = [(out, name)]
        else:
            outputs = [(os.path.join(folder, f"generated_{i}.bvh"), f"{name} #{i}")
                       for i in range(1, settings.samples + 1)]
        return [argv], lambda: outputs


class NEC_OT_transfer(NecOperator):
    """The motion of a file, or of another armature's action, on the selected armature"""
    bl_idname = "nec.transfer"
    bl_label = "Transfer"

    def steps(self, context, nec, rig, folder):
        settings = context.scene.nec
        source = bpy.path.abspath(settings.source_file) if settings.source_file else ""
        if source:
            if not os.path.isfile(source):
                raise runner.NecError(f"{source}: no such file")
            label = os.path.basename(source)
        else:
            other = settings.source_armature
            if other is None or other == context.active_object:
                raise runner.NecError("choose a file or another armature to transfer from")
            action = other.animation_data.action if other.animation_data else None
            if action is None:
                raise runner.NecError(f"{other.name} has no action to transfer")
            source = scene_io.export_motion_bvh(other, action, os.path.join(folder, "source.bvh"))
            label = f"{other.name}: {action.name}"
        out = os.path.join(folder, "transferred.bvh")
        argv = [nec, "transfer", source, "--to", rig, "-o", out, *common_args(context)]
        return [argv], lambda: [(out, scene_io.action_name_for("transfer: " + label))]


class NEC_OT_search(NecOperator):
    """The database's clips that best match the text, each moved onto the selected armature"""
    bl_idname = "nec.search"
    bl_label = "Search"

    def steps(self, context, nec, rig, folder):
        settings = context.scene.nec
        database = bpy.path.abspath(settings.database) if settings.database else ""
        if not database or not os.path.isdir(database):
            raise runner.NecError(f"choose a database folder (a cache from `nec prepare`): '{database}'")
        if not settings.query.strip():
            raise runner.NecError("write what to search for")
        found = os.path.join(folder, "found")
        models = bpy.path.abspath(preferences(context).models)
        evaluator = ["--evaluator", os.path.join(models, "evaluator")] if models else []
        search = [nec, "retrieve", settings.query, "--db", database, "-k", str(settings.results), "--save", found,
                  *evaluator]

        def matches():
            ranks = sorted(int(f[:-4]) for f in os.listdir(found) if f.endswith(".bvh") and f[:-4].isdigit())
            return [(rank, os.path.join(found, f"{rank}.bvh"), os.path.join(folder, f"match_{rank}.bvh"))
                    for rank in ranks]

        def transfers():
            return [[nec, "transfer", clip, "--to", rig, "-o", out, *common_args(context)]
                    for _, clip, out in matches()]

        def outputs():
            made = []
            for rank, clip, out in matches():
                with open(clip[:-4] + ".txt", encoding="utf-8") as caption:
                    text = caption.read().strip() or settings.query
                made.append((out, scene_io.action_name_for(f"{rank}. {text}")))
            return made

        return [search, transfers], outputs


class NEC_OT_caption_add(bpy.types.Operator):
    """Add a caption to the end of the timeline"""
    bl_idname = "nec.caption_add"
    bl_label = "Add caption"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):
        context.scene.nec.captions.add()
        return {'FINISHED'}


class NEC_OT_caption_remove(bpy.types.Operator):
    """Remove the last caption of the timeline"""
    bl_idname = "nec.caption_remove"
    bl_label = "Remove caption"
    bl_options = {'REGISTER', 'UNDO'}

    def execute(self, context):
        captions = context.scene.nec.captions
        if len(captions):
            captions.remove(len(captions) - 1)
        return {'FINISHED'}


class NEC_PT_panel(bpy.types.Panel):
    bl_label = "nec"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "nec"

    def draw(self, context):
        settings = context.scene.nec
        layout = self.layout
        if context.active_object is None or context.active_object.type != 'ARMATURE':
            layout.label(text="Select an armature")
        box = layout.box()
        box.label(text="Generate")
        for caption in settings.captions:
            row = box.row()
            row.prop(caption, "text", text="")
            row.prop(caption, "seconds", text="s")
        row = box.row()
        row.operator("nec.caption_add", text="Add caption")
        row.operator("nec.caption_remove", text="Remove")
        for name in ("model", "seed", "samples", "guidance"):
            box.prop(settings, name)
        box.operator("nec.generate")
        box = layout.box()
        box.label(text="Transfer")
        box.prop(settings, "source_file")
        box.prop(settings, "source_armature")
        box.operator("nec.transfer")
        box = layout.box()
        box.label(text="Search")
        for name in ("database", "query", "results"):
            box.prop(settings, name)
        box.operator("nec.search")


classes = (NecPreferences, NecCaption, NecSettings, NEC_OT_generate, NEC_OT_transfer, NEC_OT_search,
           NEC_OT_caption_add, NEC_OT_caption_remove, NEC_PT_panel)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.nec = bpy.props.PointerProperty(type=NecSettings)


def unregister():
    runner.close_workers()
    del bpy.types.Scene.nec
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
