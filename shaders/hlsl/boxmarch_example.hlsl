// boxmarch_example.hlsl: a minimal complete raymarching material for a baked mesh (vertex and
// fragment programs). Unity: BoxmarchExample.shader includes it (UnityCG provides the matrices);
// elsewhere the same names are declared below. Compile check:
//   glslangValidator -D -V -e frag -S frag boxmarch_example.hlsl
#include "boxmarch.hlsl"

#ifndef UNITY_CG_INCLUDED
float4x4 unity_ObjectToWorld;
float4x4 unity_WorldToObject;
float4x4 unity_MatrixVP;
float3 _WorldSpaceCameraPos;
float4 _WorldSpaceLightPos0;
#endif

float4 _Color;
float4 _UVChannels;   // xy: UV channels of BoxQuatXY and BoxQuatZW (the bake reports them)
float4 _HalfExtents;  // xyz: box half-extents for the SDF; w = 0: use the cube from the offset scale
int _MaxSteps;
float _Epsilon;
float _Relaxation;
float _MaxDistance;

float map(float3 p)
{
  return op_smooth_union(sdf_preset_sphere(p, box_half), sdf_preset_torus(p, box_half), 0.05 * max3(box_half));
}

#include "boxmarch_raymarch.hlsl"

struct appdata {
  float4 vertex : POSITION;
  float4 color : COLOR;
  float2 uv0 : TEXCOORD0;
  float2 uv1 : TEXCOORD1;
  float2 uv2 : TEXCOORD2;
  float2 uv3 : TEXCOORD3;
};

struct v2f {
  float4 pos : SV_POSITION;
  float3 obj_pos : TEXCOORD0;
  float4 color : TEXCOORD1;
  nointerpolation float4 quat : TEXCOORD2;
};

v2f vert(appdata v)
{
  v2f o;
  o.pos = mul(unity_MatrixVP, mul(unity_ObjectToWorld, float4(v.vertex.xyz, 1.0)));
  o.obj_pos = v.vertex.xyz;
  o.color = v.color;
  o.quat = bm_quaternion_from_channels(v.uv0, v.uv1, v.uv2, v.uv3, _UVChannels.xy);
  return o;
}

float4 frag(v2f i, bool front_facing : SV_IsFrontFace, out float depth : SV_Depth) : SV_Target
{
  float3 obj_camera = mul(unity_WorldToObject, float4(_WorldSpaceCameraPos, 1.0)).xyz;
  float3 half_extents = _HalfExtents.w > 0.5 ? _HalfExtents.xyz : bm_cube_half_extents(i.color);
  bm_hit h = bm_raymarch(i.obj_pos, obj_camera, i.color, i.quat, half_extents, front_facing, _MaxSteps,
                         _Epsilon, _Relaxation, _MaxDistance);
  clip(h.hit ? 1.0 : -1.0);
  float4 clip_pos = mul(unity_MatrixVP, mul(unity_ObjectToWorld, float4(h.obj_pos, 1.0)));
  depth = clip_pos.z / clip_pos.w;
#if defined(UNITY_CG_INCLUDED) && !defined(UNITY_REVERSED_Z)
  depth = depth * 0.5 + 0.5;  // OpenGL-style clip space: z / w in [-1, 1]
#endif
  float3 world_normal = normalize(mul(h.obj_normal, (float3x3)unity_WorldToObject));
  float lambert = max(dot(world_normal, normalize(_WorldSpaceLightPos0.xyz)), 0.0);
  float3 ambient = lerp(float3(0.20, 0.19, 0.18), float3(0.42, 0.45, 0.50), 0.5 + 0.5 * world_normal.y);
  return float4(_Color.rgb * (ambient + 0.8 * lambert), 1.0);
}
