// COPIED by shaders/generate.py from shaders/hlsl/BoxmarchExample.shader: edit that file, not this copy
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
