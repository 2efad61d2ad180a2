"""The one door to Blender mesh data: every read and write of a mesh's geometry, selection, UV
maps and baked layers goes through this package (Edit Mode switching and Blender's own edit-mode
operators are beside it, in ``edit_mode``). One exception, on purpose: the export builds its
temporary, file-shaped mesh copies itself (export/scene.py: which layers a target file holds is
the export's business), reading the artist's meshes through this package.

Everything moves through ``foreach_get``/``foreach_set`` on NumPy buffers of exactly the right
type and size; nothing loops over vertices, corners or faces in Python (but vertex-group
weights: weights.py says why). Layers are always looked up by name right before they are used:
adding a layer may move the others in memory, so no reference to a layer is held across a call
that adds one.

    arrays   geometry, topology, selection flags, UV maps; new meshes from arrays
    baked    the baked layers: compute (prepare_bake), store (PreparedBake.write), read back
    box_layers  per-box parameters and hierarchy: the artist's attributes, the stored layers
    rebuild  replace a mesh's geometry by arrays the core computed, keeping its attributes
    weights  vertex-group weights and the skin of an Armature modifier (preview, export)
"""
from .arrays import (new_mesh, new_zero_uv, one_normal_per_vertex, one_object_per_mesh, read_corner_edges,
                     read_face_selection, read_hidden_vertices, read_point_values, read_positions, read_topology, read_triangles,
                     read_uv, read_vertex_selection, remove_attributes, write_point_flags, write_selection,
                     write_uv)
from .baked import (BAKED_UV_MAPS, FINGERPRINT_ATTRIBUTE, LAYERS_DIGEST, MAX_UV_MAPS, NEUTRAL_BYTE, NEUTRAL_FLOAT,
                    OFFSET_ATTRIBUTE, QUAT_XY_UV, QUAT_ZW_UV, BakedLayers, BakeInputError, BakeSettings,
                    NotBakedError, PreparedBake, modifier_warnings, prepare_bake, read_baked_layers,
                    shape_key_warning, stored_layers_digest, stray_bake_layers)
from .box_layers import (DEPTH_LAYER, PARAM_ATTRIBUTES, PARAMS_COLOUR_ATTRIBUTE, PARAMS_LAYERS, PARENT_ATTRIBUTE,
                         PARENT_LAYER, BoxLayerError, BoxLayers, read_box_layers)
from .rebuild import rebuild_blocker, rebuild_welded
from .weights import Skin, SkinError, check_skin_modifier, read_skin, read_vertex_weights
