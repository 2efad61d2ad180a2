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
