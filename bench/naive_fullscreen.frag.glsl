// Benchmark baseline: the usual "one big SDF" full-screen raymarch. Every pixel marches from the
// camera and every step evaluates the SDF of ALL boxes (texture `boxes`: per box three texels:
// origin, quaternion, half-extents). Comes after decode.glsl and sdf.glsl.
// Push constants: clip_to_object (inverse of object_to_clip), march (epsilon, relaxation,
// max_distance, max_steps), sizes (box count, width, height).
float scene_map(vec3 p)
{
  float d = 1e30;
  for (int b = 0; b < sizes.x; ++b) {
    vec3 c = texelFetch(boxes, ivec2(0, b), 0).xyz;
    vec4 q = texelFetch(boxes, ivec2(1, b), 0);
    vec3 h = texelFetch(boxes, ivec2(2, b), 0).xyz;
    d = min(d, sdf_preset_sphere(bm_rotate_vector(p - c, bm_quat_conjugate(q)), h));
  }
  return d;
}

void main()
{
  vec2 ndc = gl_FragCoord.xy / vec2(sizes.yz) * 2.0 - 1.0;
  vec4 near = clip_to_object * vec4(ndc, -1.0, 1.0);
  vec4 far = clip_to_object * vec4(ndc, 1.0, 1.0);
  vec3 ro = near.xyz / near.w;
  vec3 rd = normalize(far.xyz / far.w - ro);
  float t_end = min(length(far.xyz / far.w - ro), march.z);
  float t = 0.0;
  int steps = int(march.w);
  bool hit = false;
  for (int i = 0; i < int(march.w); ++i) {
    float d = scene_map(ro + rd * t);
    if (d < march.x) {
      hit = true;
      steps = i + 1;
      break;
    }
    t += march.y * d;
    if (t > t_end) {
      steps = i + 1;
      break;
    }
  }
  frag_color = vec4(hit ? 1.0 : 0.0, float(steps), 0.0, 1.0);
}
