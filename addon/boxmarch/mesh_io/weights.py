"""Vertex-group weights (the skin a preview or an export follows)."""
from __future__ import annotations

import numpy as np


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
