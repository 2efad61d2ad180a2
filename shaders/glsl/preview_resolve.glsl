// boxmarch viewport preview, the full-screen stages of the resolved passes (preview/resolve.py,
// docs/PREVIEW.md "Hidden boxes"); the vertex stage takes a triangle covering the viewport (pos,
// in clip space). BM_RESOLVE_DEPTH: writes each pixel's nearest hit (the image hit_min's uint
// bits of a window depth, preview.frag.glsl) as its depth, so that the shade pass's depth test
// leaves only the boxes reaching it; none where no hit was kept. BM_COMPOSITE: writes the shaded
// colour and depth (the textures shaded_colour and shaded_depth) into the viewport, none where
// nothing was shaded; with BM_COMPOSITE_STEPS the evaluation counts of every pixel instead.

#ifdef BM_VERTEX
void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
#endif

#ifdef BM_RESOLVE_DEPTH
void main()
{
  uint nearest = imageLoad(hit_min, ivec2(gl_FragCoord.xy)).x;
  if (nearest >= BM_NO_HIT) {  // formats/shader_sources.py defines it: the bits of 2.0, no hit
    discard;
  }
  gl_FragDepth = uintBitsToFloat(nearest);
  frag_color = vec4(0.0);
}
#endif

#ifdef BM_COMPOSITE
void main()
{
  ivec2 pixel = ivec2(gl_FragCoord.xy);
  frag_color = texelFetch(shaded_colour, pixel, 0);
#ifdef BM_COMPOSITE_STEPS
  // Blender's ADDITIVE blend adds colour times alpha and keeps the target's alpha: the counts
  // summed in shaded_colour's rgb are added once
  frag_color.a = 1.0;
#else
  // nothing shaded: the target as cleared (a hit kept at the far plane has depth 1.0 too)
  float depth = texelFetch(shaded_depth, pixel, 0).r;
  if (depth >= 1.0 && frag_color.a <= 0.0) {
    discard;
  }
  gl_FragDepth = depth;
#endif
}
#endif
