"""Pose following: a baked mesh deformed by an Armature modifier, previewed as an engine skins it.

The bake stores the rest pose. Posed, the preview draws the evaluated (deformed) vertex positions
from the depsgraph, and moves the layout's NORMAL and TANGENT (the NORMAL_* layouts' frame) by each
vertex's linear-blend skinning matrix, sum_k w_k S_k, as three.js, Godot, Unity and Unreal move
them (the 3 x 3 part of the blended matrix, normalised per fragment). Channels skinning does not
transform (UV maps, colours) stay as baked: a CLASSIC or UV_FRAME frame stays in the rest pose
while its box turns, as it does in every engine.

S_b, bone b's deformation in the mesh object's space, is what Blender's Armature modifier applies:
inverse(premat) @ pose_bone.matrix @ inverse(bone.matrix_local) @ premat, premat = inverse(armature
world matrix) @ mesh world matrix; weights are the vertex groups named after deform bones,
divided by their sum (vertices whose weights sum to 1e-4 or less stay at rest, as Blender leaves
them).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import mesh_io

# Blender's armature deform ignores a vertex whose weights sum to this or less.
MIN_TOTAL_WEIGHT = 1e-4


def armature_modifier(ob):
    """The first Armature modifier of ``ob`` shown in the viewport with an armature object, or None."""
    for modifier in ob.modifiers:
        if (modifier.type == "ARMATURE" and modifier.show_viewport and modifier.object is not None
                and modifier.object.type == "ARMATURE"):
            return modifier
    return None


@dataclass
class SkinWeights:
    """Each vertex's bone influences (what does not change with the pose)."""

    bones: tuple            # deform bone names; ``bone`` indexes them
    bone: np.ndarray        # int64 (N, K)
    weight: np.ndarray      # float64 (N, K), each row summing to 1, or all 0 (the vertex stays at rest)


def rig_key(ob, modifier) -> tuple:
    """What the weights depend on besides the mesh data: the armature object, its deform bones and
    the object's vertex group names (a bone or group renamed, added or removed reads them again)."""
    return (modifier.name, modifier.object.name_full,
            tuple(bone.name for bone in modifier.object.data.bones if bone.use_deform),
            tuple(group.name for group in ob.vertex_groups))


def read_weights(ob, armature) -> SkinWeights:
    """The vertex-group weights of ``ob`` on the deform bones of ``armature`` (bpy.types.Armature)."""
    deform = {bone.name for bone in armature.bones if bone.use_deform}
    bones = tuple(sorted(deform & {group.name for group in ob.vertex_groups}))
    bone, weight = mesh_io.read_vertex_weights(ob, bones)
    total = weight.sum(axis=1, keepdims=True)
    weight = np.where(total > MIN_TOTAL_WEIGHT, weight / np.maximum(total, MIN_TOTAL_WEIGHT), 0.0)
    return SkinWeights(bones=bones, bone=bone, weight=weight)


def bone_deformations(ob, modifier, bones, depsgraph) -> np.ndarray:
    """float64 (B, 4, 4): S_b of each of ``bones`` in ``ob``'s object space, in the evaluated pose."""
    armature = modifier.object.evaluated_get(depsgraph)
    mesh_world = np.array(ob.evaluated_get(depsgraph).matrix_world, np.float64)
    premat = np.linalg.inv(np.array(armature.matrix_world, np.float64)) @ mesh_world
    out = np.empty((len(bones), 4, 4))
    for i, name in enumerate(bones):
        pose = np.array(armature.pose.bones[name].matrix, np.float64)
        rest = np.array(armature.data.bones[name].matrix_local, np.float64)
        out[i] = np.linalg.inv(premat) @ pose @ np.linalg.inv(rest) @ premat
    return out


def skin_linear(weights: SkinWeights, deformations) -> np.ndarray:
    """float32 (N, 3, 3): the linear part of each vertex's blended skinning matrix, in float as an
    engine's vertex shader blends it (identity for a vertex without weights)."""
    linear = np.asarray(deformations, np.float32)[:, :3, :3]
    if len(linear) == 0:
        return np.broadcast_to(np.eye(3, dtype=np.float32), (len(weights.bone), 3, 3)).copy()
    weight = weights.weight.astype(np.float32)
    blended = linear[weights.bone[:, 0]] * weight[:, 0, None, None]
    for k in range(1, weight.shape[1]):
        blended += linear[weights.bone[:, k]] * weight[:, k, None, None]
    blended[weights.weight.sum(axis=1) == 0.0] = np.eye(3, dtype=np.float32)
    return blended


def evaluated_positions(ob, depsgraph, vertex_count: int) -> np.ndarray:
    """float32 (N, 3): the vertex positions of ``ob`` after its modifiers (the pose)."""
    mesh = ob.evaluated_get(depsgraph).data
    if len(mesh.vertices) != vertex_count:
        raise ValueError(f"the modifiers of '{ob.name}' change its vertex count ({vertex_count} -> "
                         f"{len(mesh.vertices)}): the preview follows a pose only on the baked vertices")
    return mesh_io.read_positions(mesh)
