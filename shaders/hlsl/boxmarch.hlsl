// boxmarch.hlsl: decode + SDF library for engines (Unity built-in / URP shader code, any HLSL).
// The decode is generated from shaders/glsl/decode.glsl (shaders/generate.py); the SDF library
// mirrors sdf.glsl function for function (tests/test_shaders.py compares the lists). See docs/UNITY.md.
#ifndef BOXMARCH_INCLUDED
#define BOXMARCH_INCLUDED

// ---- decode (docs/FORMAT.md, docs/ENGINES.md): generated from shaders/glsl/decode.glsl
#include "boxmarch_decode.hlsl"

// The UV channel `channel` (0..3) of a vertex's first four UV sets.
float2 get_uv_by_channel(float2 uv0, float2 uv1, float2 uv2, float2 uv3, int channel)
{
  return channel == 0 ? uv0 : channel == 1 ? uv1 : channel == 2 ? uv2 : uv3;
}

// GetRotation with configurable UV channels: uv_channels = (channel of BoxQuatXY, of BoxQuatZW);
// the bake reports them; (1, 2) for a mesh that had one UV map.
float4 GetRotationFromChannels(float2 uv0, float2 uv1, float2 uv2, float2 uv3, float2 uv_channels)
{
  return GetRotation(get_uv_by_channel(uv0, uv1, uv2, uv3, (int)uv_channels.x),
                     get_uv_by_channel(uv0, uv1, uv2, uv3, (int)uv_channels.y));
}

// ---- SDF library. Units are box-local; box_half holds the box's half-extents.

// Half-extents of the box being marched; set before map() is called (BoxmarchRaymarch does).
static float3 box_half = float3(0.0, 0.0, 0.0);

float min3(float3 v) { return min(v.x, min(v.y, v.z)); }
float max3(float3 v) { return max(v.x, max(v.y, v.z)); }

float sd_sphere(float3 p, float r) { return length(p) - r; }

float sd_box(float3 p, float3 b)
{
  float3 q = abs(p) - b;
  return length(max(q, float3(0.0, 0.0, 0.0))) + min(max3(q), 0.0);
}

float sd_round_box(float3 p, float3 b, float r) { return sd_box(p, b - float3(r, r, r)) - r; }

// Segment a-b with radius r.
float sd_capsule(float3 p, float3 a, float3 b, float r)
{
  float3 pa = p - a;
  float3 ba = b - a;
  float h = clamp(dot(pa, ba) / max(dot(ba, ba), 1e-20), 0.0, 1.0);
  return length(pa - ba * h) - r;
}

// Axis z.
float sd_cylinder(float3 p, float r, float half_height)
{
  float2 d = abs(float2(length(p.xy), p.z)) - float2(r, half_height);
  return min(max(d.x, d.y), 0.0) + length(max(d, float2(0.0, 0.0)));
}

// Around axis z.
float sd_torus(float3 p, float major, float minor)
{
  float2 q = float2(length(p.xy) - major, p.z);
  return length(q) - minor;
}

// Chain link: a ring of radius `ring` in the xy plane stretched by half_length along y.
float sd_link(float3 p, float half_length, float ring, float thickness)
{
  float3 q = float3(p.x, max(abs(p.y) - half_length, 0.0), p.z);
  return length(float2(length(q.xy) - ring, q.z)) - thickness;
}

// Plane with unit normal n, offset along n.
float sd_plane(float3 p, float3 n, float offset) { return dot(p, n) + offset; }

float op_union(float a, float b) { return min(a, b); }
float op_subtract(float a, float b) { return max(a, -b); }  // a minus b
float op_intersect(float a, float b) { return max(a, b); }

// Smooth versions: k is the blend radius (box-local units).
float op_smooth_union(float a, float b, float k)
{
  float h = clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
  return lerp(b, a, h) - k * h * (1.0 - h);
}
float op_smooth_intersect(float a, float b, float k) { return -op_smooth_union(-a, -b, k); }
float op_smooth_subtract(float a, float b, float k) { return op_smooth_intersect(a, -b, k); }

float op_round(float d, float r) { return d - r; }
float op_onion(float d, float thickness) { return abs(d) - thickness; }

// Finite repetition: copies every `spacing`, `limit` copies each side of the centre per axis.
float3 op_repeat_limited(float3 p, float3 spacing, float3 limit)
{
  return p - spacing * clamp(floor(p / spacing + 0.5), -limit, limit);
}

// Presets of the Blender preview's SDF menu, sized by the box.
float sdf_preset_box(float3 p, float3 h) { return sd_box(p, h); }
float sdf_preset_sphere(float3 p, float3 h) { return sd_sphere(p, min3(h)); }
float sdf_preset_rounded_box(float3 p, float3 h) { return sd_round_box(p, h, 0.25 * min3(h)); }
float sdf_preset_capsule(float3 p, float3 h)
{
  float r = min(h.y, h.z);
  float a = max(h.x - r, 0.0);
  return sd_capsule(p, float3(-a, 0.0, 0.0), float3(a, 0.0, 0.0), r);
}
float sdf_preset_cylinder(float3 p, float3 h) { return sd_cylinder(p, min(h.x, h.y), h.z); }
float sdf_preset_torus(float3 p, float3 h)
{
  float minor = min(h.z, 0.5 * min(h.x, h.y));
  return sd_torus(p, min(h.x, h.y) - minor, minor);
}
float sdf_preset_link(float3 p, float3 h)
{
  float thickness = min(h.z, 0.25 * min(h.x, h.y));
  return sd_link(p.yxz, max(h.x - h.y, 0.0), h.y - thickness, thickness);
}

#endif  // BOXMARCH_INCLUDED
