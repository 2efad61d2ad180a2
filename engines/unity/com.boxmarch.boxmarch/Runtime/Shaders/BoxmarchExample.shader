// COPIED by shaders/generate.py from shaders/hlsl/BoxmarchExample.shader: edit that file, not this copy
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
// Unity (built-in pipeline; URP works the same with an unlit pass) material raymarching inside
// every submesh of a mesh baked by boxmarch. Put every .hlsl file of shaders/hlsl next to this
// file. See docs/UNITY.md.
Shader "Boxmarch/Example"
{
  Properties
  {
    [KeywordEnum(Classic, UV_Frame, Normal_Frame)] _Layout ("Layout (the export report names it)", Float) = 1
    _Color ("Color", Color) = (0.8, 0.8, 0.8, 1)
    _UVChannels ("Classic: UV channels of BoxQuatXY, BoxQuatZW", Vector) = (1, 2, 0, 0)
    _HalfExtents ("Classic: half-extents (w = 1 to use them)", Vector) = (0.5, 0.5, 0.5, 0)
    _MaxSteps ("Max steps", Int) = 64
    _Epsilon ("Hit epsilon", Float) = 0.001
    _Relaxation ("Step relaxation", Range(0.1, 2)) = 1
    _MaxDistance ("Max distance", Float) = 1000
    _Quality ("Quality (1 = full march)", Range(0.05, 1)) = 1
  }
  SubShader
  {
    Tags { "RenderType" = "Opaque" "Queue" = "Geometry" }
    Cull Off
    Pass
    {
      Tags { "LightMode" = "ForwardBase" }
      CGPROGRAM
      #pragma vertex vert
      #pragma fragment frag
      #pragma target 4.5
      #pragma shader_feature_local _LAYOUT_CLASSIC _LAYOUT_UV_FRAME _LAYOUT_NORMAL_FRAME
      #include "UnityCG.cginc"
      #include "boxmarch_example.hlsl"
      ENDCG
    }
  }
}
