"""Format-facing code: what the files hold and how each engine reads them, with NumPy and the
standard library only. Nothing in this package imports Blender (bpy, bmesh, gpu, mathutils,
io_scene_fbx); an import-linter contract checks it (pyproject.toml, tests/test_house.py).

layouts: one Layout per engine layout (channels, names, exporter needs, box table).
presets: one Preset per engine preset (axes, units, layouts, import settings, helper).
transforms: the numbers a preset writes (frames, offsets, positions in the target's axes).
glb, godot, fbx: the glTF binary, Godot 3 box table and FBX frame patch writers.
sidecar (+ sidecar.schema.json), import_settings: the files written beside a model.
shader_sources: the preview's GLSL and the interface Blender's create-info declares for it.
files: files that appear only complete (one rename onto the target).
"""
