// boxmarch raymarcher: sphere tracing inside one box, box-local coordinates.
// Needs decode.glsl and sdf.glsl before it and a `float map(vec3 p)` after it.
// shaders/generate.py translates it into HLSL, and bm_box_span and bm_normal_tap into GLM for the
// CPU reference (cpp/src/raymarch.cpp writes bm_march and bm_normal around its preset switch).

float map(vec3 p);

// Entry (x) and exit (y) distances of the ray ro + t rd with the box |p| <= h.
vec2 bm_box_span(vec3 ro, vec3 rd, vec3 h)
{
  vec3 s = vec3(rd.x < 0.0 ? -1.0 : 1.0, rd.y < 0.0 ? -1.0 : 1.0, rd.z < 0.0 ? -1.0 : 1.0);
  vec3 inv = 1.0 / max(abs(rd), vec3(1e-12));
  vec3 t_near = (-h - s * ro) * inv;
  vec3 t_far = (h - s * ro) * inv;
  return vec2(max3(t_near), min3(t_far));
}

// Sphere-traces map() from ro along unit rd until a distance falls below epsilon (true), the ray
// passes t_end or step_limit evaluations (at most 512) are spent (false). t: distance travelled;
// steps: map() evaluations. The loop's bound is a constant, as GLSL ES 1.00 (WebGL 1) requires.
bool bm_march(vec3 ro, vec3 rd, float t_end, int step_limit, float epsilon, float relaxation,
              out float t, out int steps)
{
  t = 0.0;
  steps = step_limit;
  for (int i = 0; i < 512; ++i) {
    if (i >= step_limit) {
      break;
    }
    float d = map(ro + rd * t);
    if (d < epsilon) {
      steps = i + 1;
      return true;
    }
    t += relaxation * d;
    if (t > t_end) {
      steps = i + 1;
      return false;
    }
  }
  return false;
}

// Tap distance of bm_normal: taps closer than a thousandth of the box lose the gradient in float
// rounding, so small epsilons do not shrink them further.
float bm_normal_tap(float epsilon, vec3 h)
{
  return max(epsilon, 1e-3 * max3(h));
}

// Unit SDF gradient from four tetrahedral taps at distance e.
vec3 bm_normal(vec3 p, float e)
{
  const vec3 a = vec3(1.0, -1.0, -1.0);
  const vec3 b = vec3(-1.0, -1.0, 1.0);
  const vec3 c = vec3(-1.0, 1.0, -1.0);
  const vec3 d = vec3(1.0, 1.0, 1.0);
  vec3 n = a * map(p + a * e) + b * map(p + b * e) + c * map(p + c * e) + d * map(p + d * e);
  float len = length(n);
  return len > 0.0 ? n / len : vec3(0.0);
}
