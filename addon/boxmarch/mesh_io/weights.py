"""Vertex-group weights and the skin they make with an Armature modifier (what a preview or an
export follows)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class SkinError(ValueError):
    """An object's Armature modifier cannot be carried as an engine skin; the message says why."""


@dataclass
class Skin:
    """How an object's Armature modifier deforms its mesh, as an engine skin carries it."""

    armature: object     # the armature object (bpy.types.Object)
    modifier: str        # the Armature modifier's name
    bones: list          # deform bones whose vertex group weights some vertex, in the armature's order
    weights: np.ndarray  # (vertices, len(bones)) float64, each weighted row normalised to sum 1
    unweighted: int      # vertices in no deform bone's group (Blender leaves them at rest)


def read_vertex_weights(ob, group_names) -> tuple[np.ndarray, np.ndarray]:
    """Each vertex's positive weights in the vertex groups of ``ob`` named ``group_names``:
    (slots int64 (N, K), weights float64 (N, K)), slot indexing ``group_names``, unused columns 0,
    K the most groups any vertex is in (at least 1). Raw weights, not normalised.

    The one Python loop over vertices in mesh_io: Blender has no foreach_get for a vertex's
    group memberships (a collection per vertex)."""
    names = list(group_names)
    slot_of_group = {group.index: names.index(group.name) for group in ob.vertex_groups if group.name in names}
    influences = [[(slot_of_group[g.group], g.weight) for g in vertex.groups if g.group in slot_of_group and g.weight > 0]
                  for vertex in ob.data.vertices]
    width = max(1, max((len(i) for i in influences), default=0))
    slots = np.zeros((len(influences), width), np.int64)
    weights = np.zeros((len(influences), width), np.float64)
    for row, pairs in enumerate(influences):
        for column, (slot, value) in enumerate(pairs):
            slots[row, column], weights[row, column] = slot, value
    return slots, weights


def check_skin_modifier(modifier) -> None:
    """Raises SkinError where an engine skin cannot carry how the Armature modifier ``modifier``
    deforms: bone envelopes, or no vertex groups (an engine skin holds vertex weights only). The
    preview and the export refuse the same modifiers."""
    if modifier.use_bone_envelopes or not modifier.use_vertex_groups:
        raise SkinError(f"the Armature modifier '{modifier.name}' deforms by bone envelopes: engine skins carry "
                        "vertex-group weights only (switch Bone Envelopes off and Vertex Groups on)")


def read_skin(ob) -> Skin | None:
    """The skin of ``ob``'s enabled Armature modifier; None without one, or when it has no
    armature or no deform bone weights any vertex (the modifier then moves nothing: the mesh is
    what Blender shows). Raises SkinError where engines cannot carry it: several Armature
    modifiers, bone envelopes or no vertex groups (an engine skin holds vertex weights only)."""
    modifiers = [m for m in getattr(ob, "modifiers", ()) if m.type == "ARMATURE" and (m.show_viewport or m.show_render)]
    if not modifiers:
        return None
    if len(modifiers) > 1:
        raise SkinError(f"{len(modifiers)} Armature modifiers ({', '.join(m.name for m in modifiers)}): an engine "
                        "skin follows one armature")
    modifier = modifiers[0]
    if modifier.object is None:
        return None
    check_skin_modifier(modifier)
    deform = [bone.name for bone in modifier.object.data.bones if bone.use_deform]
    if not deform:
        return None
    slots, raw = read_vertex_weights(ob, deform)
    dense = np.zeros((len(slots), len(deform)))
    np.add.at(dense, (np.repeat(np.arange(len(slots)), slots.shape[1]), slots.ravel()), raw.ravel())
    used = dense.sum(axis=0) > 0
    if not used.any():
        return None
    dense = dense[:, used]
    total = dense.sum(axis=1, keepdims=True)
    return Skin(armature=modifier.object, modifier=modifier.name, bones=[b for b, u in zip(deform, used) if u],
                weights=np.divide(dense, total, out=np.zeros_like(dense), where=total > 0),
                unweighted=int((total[:, 0] <= 0).sum()) if len(total) else 0)
