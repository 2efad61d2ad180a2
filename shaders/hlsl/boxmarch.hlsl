// Conventions of every boxmarch shader (docs/ENGINES.md, Shader conventions), as hg_sdf states its own:
// * Names: bm_ on everything boxmarch adds to an engine's shader (bm plus CamelCase in the stages
//   three.js's JavaScript assembles; BM_ and BOXMARCH_ on macros). The families users' map() texts
//   call: sd_ (distances), op_ (operators), sdf_preset_ (presets); box_ the values of the box being
//   marched that map() reads (box_half, box_index, box_params, box_parent_*); map() is the user's.
//   min3 and max3 are bm_min3 and bm_max3 under the names map() texts use.
// * Units: box-local, p measured from the box's origin along its baked axes, in the mesh's units.
// * Distances: each distance function says whether it is exact (the signed Euclidean distance) or a
//   bound (never more than the exact distance: sphere tracing stays safe, with more steps).
// * Frames: the quaternion q (x, y, z, w; w >= 0) turns box-local into object space; the box's axes
//   are TANGENT (x), cross(NORMAL, TANGENT) * tangent.w (y) and NORMAL (z) where a layout carries
//   them; f is the box-local vector from the fragment to the box's origin.
//
// boxmarch.hlsl: decode + SDF library for engines (Unity built-in / URP shader code, any HLSL).
// Both are generated from shaders/glsl (shaders/generate.py); this file adds what only engines
// need. See docs/UNITY.md.
#ifndef BOXMARCH_INCLUDED
#define BOXMARCH_INCLUDED

// ---- decode (docs/FORMAT.md, docs/ENGINES.md)
#include "boxmarch_decode.hlsl"

// The UV channel `channel` (0..3) of a vertex's first four UV sets.
float2 bm_uv_by_channel(float2 uv0, float2 uv1, float2 uv2, float2 uv3, int channel)
{
  return channel == 0 ? uv0 : channel == 1 ? uv1 : channel == 2 ? uv2 : uv3;
}

// bm_quaternion with configurable UV channels: uv_channels = (channel of BoxQuatXY, of
// BoxQuatZW); the bake reports them; (1, 2) for a mesh that had one UV map.
float4 bm_quaternion_from_channels(float2 uv0, float2 uv1, float2 uv2, float2 uv3, float2 uv_channels)
{
  return bm_quaternion(bm_uv_by_channel(uv0, uv1, uv2, uv3, (int)uv_channels.x),
                       bm_uv_by_channel(uv0, uv1, uv2, uv3, (int)uv_channels.y));
}

// ---- SDF library. Units are box-local; box_half holds the box's half-extents.
#include "boxmarch_sdf.hlsl"
#include "boxmarch_box_params.hlsl"

#endif  // BOXMARCH_INCLUDED
