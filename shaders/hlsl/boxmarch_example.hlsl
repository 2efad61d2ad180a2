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
// boxmarch_example.hlsl: a minimal complete raymarching material for a baked mesh (vertex and
// fragment programs). Unity: BoxmarchExample.shader includes it (UnityCG provides the matrices);
// elsewhere the same names are declared below. Compile check (add -D_LAYOUT_UV_FRAME or
// -D_LAYOUT_NORMAL_FRAME for those layouts):
//   glslangValidator -D -V -e frag -S frag boxmarch_example.hlsl
#include "boxmarch.hlsl"

#ifndef UNITY_CG_INCLUDED
float4x4 unity_ObjectToWorld;
float4x4 unity_WorldToObject;
float4x4 unity_MatrixVP;
float3 _WorldSpaceCameraPos;
float4 _WorldSpaceLightPos0;
float4 _ScreenParams;  // x, y: the render target's width and height in pixels
#endif

float4 _Color;
float4 _UVChannels;   // xy: UV channels of BoxQuatXY and BoxQuatZW (the bake reports them)
float4 _HalfExtents;  // xyz: box half-extents for the SDF; w = 0: use the cube from the offset scale
int _MaxSteps;
float _Epsilon;
float _Relaxation;
float _MaxDistance;
float _Quality;  // the quality knob (bm_quality): 1 = the full march, lower = cheaper, less exact

// The written depth is never nearer than the rasterised face's (frag clamps it), and saying so
// keeps early depth testing on: greater-or-equal in [0, 1] depth, less-or-equal where the depth
// is reversed (UNITY_REVERSED_Z: near = 1).
#if defined(UNITY_REVERSED_Z)
#define BM_CONSERVATIVE_DEPTH SV_DepthLessEqual
#else
#define BM_CONSERVATIVE_DEPTH SV_DepthGreaterEqual
#endif

float map(float3 p)
{
  return op_smooth_union(sdf_preset_sphere(p, box_half), sdf_preset_torus(p, box_half), 0.05 * max3(box_half));
}

#include "boxmarch_raymarch.hlsl"

// The layout the mesh was exported with (docs/ENGINES.md): CLASSIC by default; Unity's
// KeywordEnum _Layout in BoxmarchExample.shader defines _LAYOUT_UV_FRAME or _LAYOUT_NORMAL_FRAME.
// UV_FRAME: TEXCOORD1-2 = quaternion, TEXCOORD3 + 4.x = f, 4.y = box index, TEXCOORD5 + 6.x = h.
// NORMAL_FRAME (skin-safe: Unity's skinning turns the normal and tangent): NORMAL = local z,
// TANGENT = (local x, w), TEXCOORD1 + 2.x = f, 2.y = box index, TEXCOORD3 + 4.x = h.
struct appdata {
  float4 vertex : POSITION;
  float4 color : COLOR;
  float2 uv0 : TEXCOORD0;
  float2 uv1 : TEXCOORD1;
  float2 uv2 : TEXCOORD2;
  float2 uv3 : TEXCOORD3;
  float2 uv4 : TEXCOORD4;
  float2 uv5 : TEXCOORD5;
  float2 uv6 : TEXCOORD6;
  float3 normal : NORMAL;
  float4 tangent : TANGENT;
};

struct v2f {
  float4 pos : SV_POSITION;
  float3 obj_pos : TEXCOORD0;
  float3 offset : TEXCOORD1;                     // f, box-local
  nointerpolation float3 axis_x : TEXCOORD2;     // the box's axes, engine object space
  nointerpolation float3 axis_y : TEXCOORD3;
  nointerpolation float3 axis_z : TEXCOORD4;
  nointerpolation float3 half_extents : TEXCOORD5;
};

v2f vert(appdata v)
{
  v2f o;
  o.pos = mul(unity_MatrixVP, mul(unity_ObjectToWorld, float4(v.vertex.xyz, 1.0)));
  o.obj_pos = v.vertex.xyz;
#if defined(_LAYOUT_NORMAL_FRAME)
  o.offset = bm_offset(v.uv1, v.uv2);
  o.axis_x = v.tangent.xyz;
  o.axis_y = bm_axis_y(v.normal, v.tangent);
  o.axis_z = v.normal;
  o.half_extents = bm_half_extents(v.uv3, v.uv4);
#else
#if defined(_LAYOUT_UV_FRAME)
  float4 q = normalize(bm_quaternion(v.uv1, v.uv2));
  o.offset = bm_offset(v.uv3, v.uv4);
  o.half_extents = bm_half_extents(v.uv5, v.uv6);
#else
  float4 q = normalize(bm_quaternion_from_channels(v.uv0, v.uv1, v.uv2, v.uv3, _UVChannels.xy));
  o.offset = bm_offset_from_color(v.color);
  o.half_extents = _HalfExtents.w > 0.5 ? _HalfExtents.xyz : bm_cube_half_extents(v.color);
#endif
  o.axis_x = mul(BOXMARCH_FRAME, bm_rotate_vector(float3(1.0, 0.0, 0.0), q));
  o.axis_y = mul(BOXMARCH_FRAME, bm_rotate_vector(float3(0.0, 1.0, 0.0), q));
  o.axis_z = mul(BOXMARCH_FRAME, bm_rotate_vector(float3(0.0, 0.0, 1.0), q));
#endif
  return o;
}

float4 frag(v2f i, bool front_facing : SV_IsFrontFace, out float depth : BM_CONSERVATIVE_DEPTH) : SV_Target
{
  float3 obj_camera = mul(unity_WorldToObject, float4(_WorldSpaceCameraPos, 1.0)).xyz;
  float4x4 object_to_clip = mul(unity_MatrixVP, unity_ObjectToWorld);
  float footprint = bm_pixel_size(mul(object_to_clip, float4(i.obj_pos, 1.0)).w, length(object_to_clip[1].xyz),
                                  _ScreenParams.y);
  bm_hit h = bm_raymarch_in_frame(i.obj_pos, obj_camera, i.offset, normalize(i.axis_x), normalize(i.axis_y),
                                  normalize(i.axis_z), i.half_extents, front_facing, _MaxSteps, _Epsilon,
                                  _Relaxation, _MaxDistance, _Quality, footprint);
  clip(h.hit ? 1.0 : -1.0);
  float4 clip_pos = mul(object_to_clip, float4(h.obj_pos, 1.0));
  depth = clip_pos.z / clip_pos.w;
#if defined(UNITY_CG_INCLUDED) && !defined(UNITY_REVERSED_Z)
  depth = depth * 0.5 + 0.5;  // OpenGL-style clip space: z / w in [-1, 1]
#endif
#if defined(UNITY_REVERSED_Z)
  depth = min(depth, i.pos.z);  // i.pos.z: the rasterised face's depth
#else
  depth = max(depth, i.pos.z);
#endif
  float3 world_normal = normalize(mul(h.obj_normal, (float3x3)unity_WorldToObject));
  float lambert = max(dot(world_normal, normalize(_WorldSpaceLightPos0.xyz)), 0.0);
  float3 ambient = lerp(float3(0.20, 0.19, 0.18), float3(0.42, 0.45, 0.50), 0.5 + 0.5 * world_normal.y);
  return float4(_Color.rgb * (ambient + 0.8 * lambert), 1.0);
}
