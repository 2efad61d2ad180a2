// boxmarch_raymarch.hlsl: the box-local sphere tracer. Include boxmarch.hlsl, define
// `float map(float3 p)` (box-local, may use box_half), then include this file.
// Mirrors shaders/glsl/raymarch.glsl (and the fragment logic of preview.frag.glsl).
#ifndef BOXMARCH_RAYMARCH_INCLUDED
#define BOXMARCH_RAYMARCH_INCLUDED

// Optional change of object frame, engine object space from Blender object space (an orthonormal
// 3x3, e.g. the axis conversion of an FBX import); identity by default.
#ifndef BOXMARCH_FRAME
#define BOXMARCH_FRAME float3x3(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
#endif

// Entry (x) and exit (y) distances of the ray ro + t rd with the box |p| <= h.
float2 bm_box_span(float3 ro, float3 rd, float3 h)
{
  float3 s = float3(rd.x < 0.0 ? -1.0 : 1.0, rd.y < 0.0 ? -1.0 : 1.0, rd.z < 0.0 ? -1.0 : 1.0);
  float3 inv = 1.0 / max(abs(rd), float3(1e-12, 1e-12, 1e-12));
  float3 t_near = (-h - s * ro) * inv;
  float3 t_far = (h - s * ro) * inv;
  return float2(max3(t_near), min3(t_far));
}

// Sphere-traces map() from ro along unit rd until a distance falls below epsilon (true), the ray
// passes t_end or max_steps evaluations are spent (false).
bool bm_march(float3 ro, float3 rd, float t_end, int max_steps, float epsilon, float relaxation,
              out float t, out int steps)
{
  t = 0.0;
  steps = max_steps;
  [loop]
  for (int i = 0; i < max_steps; ++i) {
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

float bm_normal_tap(float epsilon, float3 h)
{
  return max(epsilon, 1e-3 * max3(h));
}

// Unit SDF gradient from four tetrahedral taps at distance e.
float3 bm_normal(float3 p, float e)
{
  const float3 a = float3(1.0, -1.0, -1.0);
  const float3 b = float3(-1.0, -1.0, 1.0);
  const float3 c = float3(-1.0, 1.0, -1.0);
  const float3 d = float3(1.0, 1.0, 1.0);
  float3 n = a * map(p + a * e) + b * map(p + b * e) + c * map(p + c * e) + d * map(p + d * e);
  float len = length(n);
  return len > 0.0 ? n / len : float3(0.0, 0.0, 0.0);
}

// The largest half-extent, from the offset scale alone (s = 1 / largest |f| over the submesh;
// for BOUNDS origins that is the box's largest half-extent): a cube that holds the box, for when
// the real half-extents are not available to the engine shader.
float3 BoxmarchCubeHalfExtents(float4 color)
{
  float h = 1.0 / color.a;
  return float3(h, h, h);
}

struct BoxmarchHit {
  bool hit;
  float3 objPos;     // engine object space
  float3 objNormal;  // engine object space, unit
  int steps;
};

// The whole per-fragment raymarch (as the Blender preview does it): objPos = the fragment's
// interpolated object-space position, objCamera = the camera in object space, color/quat = the
// decoded vertex data, halfExtents = the box's half-extents (or BoxmarchCubeHalfExtents),
// frontFacing = SV_IsFrontFace.
BoxmarchHit BoxmarchRaymarch(float3 objPos, float3 objCamera, float4 color, float4 quat, float3 halfExtents,
                             bool frontFacing, int maxSteps, float epsilon, float relaxation, float maxDistance)
{
  BoxmarchHit o;
  o.hit = false;
  o.objPos = objPos;
  o.objNormal = float3(0.0, 0.0, 1.0);
  o.steps = 0;
  float4 q = normalize(quat);
  float3 f = GetFragToOrigin(color);
  box_half = halfExtents;
  float3 ro = -f;
  float3 rayObject = objPos - objCamera;
  float eyeDistance = length(rayObject);
  // engine object space -> Blender object space -> box-local
  float3 rd = normalize(rotate_vector(mul(transpose(BOXMARCH_FRAME), rayObject / eyeDistance), quat_conjugate(q)));
  float2 span = bm_box_span(ro, rd, box_half);
  float tEnd = span.y;
  // entry: front-facing, or (whatever the winding) more box ahead than behind; the far side
  // only marches when the camera is inside the box
  if (!frontFacing && span.x + span.y < 0.0) {
    if (eyeDistance > -span.x) return o;
    ro -= rd * eyeDistance;
    tEnd = eyeDistance;
  }
  float t;
  int steps;
  o.hit = bm_march(ro, rd, min(tEnd, maxDistance), maxSteps, epsilon, relaxation, t, steps);
  o.steps = steps;
  if (!o.hit) return o;
  float3 localHit = ro + rd * t;
  o.objPos = objPos + mul(BOXMARCH_FRAME, rotate_vector(localHit + f, q));
  o.objNormal = mul(BOXMARCH_FRAME, rotate_vector(bm_normal(localHit, bm_normal_tap(epsilon, box_half)), q));
  return o;
}

#endif  // BOXMARCH_RAYMARCH_INCLUDED
