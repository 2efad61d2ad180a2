"""Raymarch preview of baked meshes: a 3D viewport draw handler and a headless offscreen render.

Objects with ``ob.boxmarch.preview`` on are drawn with the preview shader (shaders/glsl): every
fragment of a submesh decodes its box-local frame and sphere-traces the chosen SDF. See
docs/PREVIEW.md. ``bpy``, ``gpu`` and the drawing modules (draw, shader) are imported inside the
functions that use them, so importing the package loads no GPU module.
"""
from __future__ import annotations

import warnings

import numpy as np

_handler = None
_WIRE_BACKUP = "_boxmarch_display_type"  # leading underscore: hidden in the UI


def _tag_redraw():
    import bpy

    for window in getattr(bpy.context.window_manager, "windows", []):
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def settings_changed(ob):
    """Update callback of ob.boxmarch: the object's own solid drawing would hide the raymarched
    shapes inside it, so a previewed object is displayed as wire (restored when switched off)."""
    if ob.boxmarch.preview and ob.display_type not in {"WIRE", "BOUNDS"}:
        ob[_WIRE_BACKUP] = ob.display_type
        ob.display_type = "WIRE"
    elif not ob.boxmarch.preview and _WIRE_BACKUP in ob:
        ob.display_type = ob[_WIRE_BACKUP]
        del ob[_WIRE_BACKUP]
    _tag_redraw()


def _previewed(ob) -> bool:
    return ob.type == "MESH" and ob.boxmarch.preview and ob.mode != "EDIT"


def _draw_viewport():
    import bpy
    import gpu

    from . import draw

    context = bpy.context
    region_data = context.region_data
    objects = [ob for ob in context.visible_objects if _previewed(ob)]
    if region_data is None or not objects:
        return
    depsgraph = context.evaluated_depsgraph_get()
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(True)
    for ob in objects:
        try:
            draw.draw_object(ob, region_data.view_matrix, region_data.window_matrix, region_data.is_perspective,
                             depsgraph=depsgraph)
        except ValueError:  # noted in draw.errors (the panel shows it); the others still draw
            pass
    gpu.state.depth_test_set("NONE")
    gpu.state.depth_mask_set(False)


def _geometry_changed(scene, depsgraph):
    """depsgraph_update_post handler. A mesh datablock's geometry changed (edited, baked again):
    everything read from it goes. An object's evaluated geometry changed: for an object drawn
    posed, that is its pose (bones moved, the armature or the object moved), so only its posed
    positions and frames are recomputed; for any other object its mesh is read again."""
    import bpy

    from . import draw

    for update in depsgraph.updates:
        if not update.is_updated_geometry:
            continue
        if isinstance(update.id, bpy.types.Object):
            if not draw.pose_changed(update.id.name_full) and update.id.data is not None:
                draw.forget(update.id.data.name_full)
        elif isinstance(update.id, bpy.types.Mesh):
            draw.forget(update.id.name_full)


def _frame_changed(*_args):
    """frame_change_post handler: an action may have moved the bones (scrubbing, playback), and
    Blender reports a frame change's updates to no depsgraph_update_post handler."""
    from . import draw

    draw.pose_changed()


def _data_replaced(*_args):
    """load_post / undo_post / redo_post handler: meshes were replaced wholesale (a new file may
    reuse a mesh name), so every cached batch goes."""
    from . import draw

    draw.forget()


# (handler list, function): all persistent, so loading a file keeps them.
APP_HANDLERS = (("depsgraph_update_post", _geometry_changed), ("frame_change_post", _frame_changed),
                ("load_post", _data_replaced),
                ("undo_post", _data_replaced), ("redo_post", _data_replaced))


def register():
    import bpy

    global _handler
    if _handler is None:
        _handler = bpy.types.SpaceView3D.draw_handler_add(_draw_viewport, (), "WINDOW", "POST_VIEW")
    for list_name, function in APP_HANDLERS:
        handlers = getattr(bpy.app.handlers, list_name)
        if function not in handlers:
            handlers.append(bpy.app.handlers.persistent(function))


def unregister():
    import bpy

    from . import draw, occlusion, resolve, shader

    global _handler
    if _handler is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handler, "WINDOW")
        _handler = None
    for list_name, function in APP_HANDLERS:
        handlers = getattr(bpy.app.handlers, list_name)
        if function in handlers:
            handlers.remove(function)
    draw.forget()
    occlusion.forget()
    resolve.forget()
    shader.clear_cache()


def camera_matrices(scene, camera_object, width, height):
    """(view, projection) float64 4x4 of a camera object for an image of width x height (the
    camera's own sensor fit and shift), as the offscreen render and the CPU reference use them."""
    import bpy

    depsgraph = bpy.context.evaluated_depsgraph_get()
    projection = camera_object.calc_matrix_camera(depsgraph, x=int(width), y=int(height),
                                                  scale_x=scene.render.pixel_aspect_x,
                                                  scale_y=scene.render.pixel_aspect_y)
    return np.array(camera_object.matrix_world.inverted(), np.float64), np.array(projection, np.float64)


def ensure_gpu_context():
    """In ``blender --background`` GPU calls fail until a render has created a context: one
    Workbench render at 8 x 8 pixels does it (the scene's render settings are restored)."""
    import bpy
    import gpu

    if not bpy.app.background:
        return
    if hasattr(gpu, "init"):
        gpu.init()
        return
    try:
        gpu.types.GPUOffScreen(1, 1).free()
        return
    except SystemError:
        pass
    scene = bpy.context.scene
    render = scene.render
    saved = render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage
    render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage = \
        "BLENDER_WORKBENCH", 8, 8, 100
    camera = None
    if scene.camera is None:  # a render needs one: a temporary camera, removed again below
        camera = bpy.data.objects.new("boxmarch_gpu_init", bpy.data.cameras.new("boxmarch_gpu_init"))
        scene.collection.objects.link(camera)
        scene.camera = camera
    try:
        bpy.ops.render.render()
    finally:
        render.engine, render.resolution_x, render.resolution_y, render.resolution_percentage = saved
        if camera is not None:
            camera_data = camera.data
            bpy.data.objects.remove(camera)
            bpy.data.cameras.remove(camera_data)


def _read(buffer, shape):
    # Blender 3.4 exports multi-dimensional Buffers with wrong strides: flatten it first.
    buffer.dimensions = int(np.prod(shape))
    return np.array(buffer, np.float32).reshape(shape)


last_skipped: list = []  # objects the last render() left out, as "name: reason"


def render(scene, camera_object, width, height, *, output="SHADED"):
    """Renders the scene headless from ``camera_object``: ordinary visible meshes in one flat
    colour, previewed objects raymarched (with their outline/vectors when switched on).

    Returns ``(rgba, depth)``: float32 (H, W, 4) and (H, W) window-space depth (0 near plane,
    1.0 far plane and where nothing was drawn), row 0 at the TOP, one sample per pixel centre.
    ``output``: 'SHADED' (the viewport look), 'NORMAL' (object-space normals of raymarched hits
    as 0.5 + 0.5 n), or 'STEPS' (summed over the raymarch fragments run at a pixel: red the march
    steps, green the SDF evaluations, blue the fragments; every fragment of the one-pass march,
    those the depth test leaves of the resolved passes, preview/resolve.py; for the benchmark).

    An object that cannot be drawn (a NaN coordinate, broken baked data) is left out and the
    others still draw; ``last_skipped`` then lists "name: reason" for each, and a RuntimeWarning
    says so."""
    import bpy
    import gpu

    from . import draw
    from ..formats import shader_sources

    width, height = int(width), int(height)
    if width <= 0 or height <= 0:
        raise ValueError(f"width and height must be positive, got {width} x {height}")
    if output not in shader_sources.OUTPUT_MODES:
        raise ValueError(f"output must be one of {shader_sources.OUTPUT_MODES}, got {output!r}")
    if camera_object is None or camera_object.type != "CAMERA":
        raise ValueError("render needs a camera object")
    ensure_gpu_context()
    mode = shader_sources.OUTPUT_MODES.index(output)
    view, projection = camera_matrices(scene, camera_object, width, height)
    perspective = camera_object.data.type != "ORTHO"
    depsgraph = bpy.context.evaluated_depsgraph_get()
    objects = [ob for ob in scene.objects if ob.type == "MESH" and ob.visible_get()]
    offscreen = gpu.types.GPUOffScreen(width, height, format="RGBA32F")
    try:
        with offscreen.bind():
            framebuffer = gpu.state.active_framebuffer_get()
            framebuffer.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
            with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
                gpu.matrix.load_matrix(_matrix(view))
                gpu.matrix.load_projection_matrix(_matrix(projection))
                if mode == 2:
                    gpu.state.blend_set("ADDITIVE")
                    gpu.state.depth_test_set("NONE")
                else:
                    gpu.state.depth_test_set("LESS_EQUAL")
                    gpu.state.depth_mask_set(True)
                skipped = []
                for ob in objects:
                    try:
                        if _previewed(ob):
                            draw.draw_object(ob, view, projection, perspective, mode, depsgraph)
                        elif mode == 0:
                            draw.draw_solid(ob, depsgraph)
                    except (ValueError, RuntimeError) as error:  # one bad object: the rest still draw
                        skipped.append(f"{ob.name}: {error}")
                gpu.state.blend_set("NONE")
                gpu.state.depth_test_set("NONE")
                gpu.state.depth_mask_set(False)
            rgba = _read(framebuffer.read_color(0, 0, width, height, 4, 0, "FLOAT"), (height, width, 4))
            depth = _read(framebuffer.read_depth(0, 0, width, height), (height, width))
    finally:
        offscreen.free()
    last_skipped[:] = skipped
    if skipped:
        warnings.warn("preview.render left out " + "; ".join(skipped), RuntimeWarning, stacklevel=2)
    return np.ascontiguousarray(rgba[::-1]), np.ascontiguousarray(depth[::-1])


def _matrix(array):
    from mathutils import Matrix

    return Matrix(np.asarray(array).tolist())
