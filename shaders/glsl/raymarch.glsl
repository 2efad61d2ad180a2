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
  return vec2(bm_max3(t_near), bm_min3(t_far));
}

// Sphere-traces map() from ro along unit rd until a distance falls below epsilon (true), the ray
// passes t_end or step_limit evaluations (at most 512) are spent (false). Where a distance is under
// secant.x and smaller than the last one, the step is the secant's instead (the line through the
// last two distances along the ray, extended to zero), at most secant.y times the distance: near
// a surface met at a slant the distances shrink geometrically and the secant skips that tail, and
// the hit test stays epsilon, so the silhouette does not move (secant.x = 0: plain sphere tracing).
// A step under 2^-23 t ends the march as a hit: float32 moves t by at most one float step for it,
// so the march would spend its whole budget in place and miss a surface within the step's reach
// (an epsilon finer than float32 resolves at t: 1e-4 in a box 2,000 units long).
// t: distance travelled; steps: map() evaluations; d: the last map() value (at a hit, the hit's
// own distance, which bm_normal reuses). The loop's bound is a constant, as GLSL ES 1.00 (WebGL 1)
// requires.
bool bm_march(vec3 ro, vec3 rd, float t_end, int step_limit, float epsilon, float relaxation, vec2 secant,
              out float t, out int steps, out float d)
{
  t = 0.0;
  steps = step_limit;
  d = 0.0;
  float last_d = 0.0;
  float last_advance = 0.0;
  for (int i = 0; i < 512; ++i) {
    if (i >= step_limit) {
      break;
    }
    d = map(ro + rd * t);
    if (d < epsilon) {
      steps = i + 1;
      return true;
    }
    float advance = relaxation * d;
    if (d < secant.x && d < last_d) {
      advance = min(d * last_advance / (last_d - d), secant.y * d);
    }
    if (advance < 1.2e-7 * t) {
      steps = i + 1;
      return true;
    }
    last_d = d;
    last_advance = advance;
    t += advance;
    if (t > t_end) {
      steps = i + 1;
      return false;
    }
  }
  return false;
}

// Level of detail for a box a few pixels wide: one map() evaluation where the ray passes nearest
// the box's centre (within its span) stands for the march; a hit when that point lies within half
// a pixel (footprint, box-local units) of the surface or inside. t: that point's distance along
// the ray; d: its map() value (for bm_normal).
bool bm_one_tap(vec3 ro, vec3 rd, float t_end, float footprint, out float t, out float d)
{
  t = clamp(-dot(ro, rd), 0.0, t_end);
  d = map(ro + rd * t);
  return d < 0.5 * footprint;
}

// The quality knob q (0 < q <= 1) as the four settings it stands for. x: distance, as a share of a
// pixel's footprint, under which the march takes secant steps (bm_march's secant.x); w: the
// longest secant step, as a multiple of the distance (secant.y): longer steps save more and may
// land further inside the surface (a hit there shades from a point under it); y: steps allowed
// per pixel of the box's size on screen (bm_step_limit); z: size on screen in pixels under which a
// box takes one tap (bm_one_tap). The hit distance stays the epsilon at every q; q = 1 leaves the
// march as the epsilon and step limit set it.
vec4 bm_quality(float q)
{
  float loss = 1.0 - clamp(q, 0.0, 1.0);
  return vec4(0.5 * loss, 8.0 / max(loss, 1e-9), 4.0 * loss, 1.0 + 2.0 * loss);
}

// Size of one pixel, in object units, at a point whose clip-space w is clip_w: row_y = length of
// the object-to-clip matrix's y row (xyz), height = viewport height in pixels. Perspective and
// orthographic alike (w = 1 there).
float bm_pixel_size(float clip_w, float row_y, float height)
{
  return 2.0 * clip_w / (height * row_y);
}

// Step limit of a box box_pixels wide on screen: steps_per_pixel per pixel, at least 16, at most
// step_cap (a float holding a whole number).
float bm_step_limit(float box_pixels, float steps_per_pixel, float step_cap)
{
  return min(step_cap, max(16.0, floor(steps_per_pixel * box_pixels)));
}

// Tap distance of bm_normal, 3/10,000 of the box: a forward difference errs by about half the tap
// times the surface's curvature, and closer taps lose the gradient in float rounding (measured in
// docs/ACCURACY.md, "GPU cost against error": the normal error column).
float bm_normal_tap(vec3 h)
{
  return 3e-4 * bm_max3(h);
}

// Unit SDF gradient at p from forward differences: d = map(p), which the march has already
// computed (bm_march's d), so the normal costs three map() calls; taps at distance e.
vec3 bm_normal(vec3 p, float d, float e)
{
  vec3 n = vec3(map(p + vec3(e, 0.0, 0.0)), map(p + vec3(0.0, e, 0.0)), map(p + vec3(0.0, 0.0, e))) - d;
  float len = length(n);
  return len > 0.0 ? n / len : vec3(0.0);
}

// Hidden boxes (box_params.glsl, conservative occluders): an occluder's window depth (0 near, 1
// far; GL's depth range) made safe to compare with: 2^-21 farther, eight float steps at the far
// plane. That covers the rounding of window depths near 1 (a float step there spans about 1 cm at
// 140 units with a 0.1 near plane), where an occluder pulled in by a fraction of a pixel lies
// fewer float steps behind its box's face than the face's depth and a hit's are rounded by, and a
// 24-bit depth buffer's step. The pre-pass writes it as each occluder's depth, so the marching
// stage's test and the depth test of passes that write no depth compare with the same limit: a
// fragment whose box entry lies beyond it is hidden; a march stops at it.
float bm_occluder_limit(float occluder_depth)
{
  return occluder_depth + 4.8e-7;
}

// How far float32 rounding may move a point's window depth, for the pre-pass to push its occluders
// back by it: `spread` the sums of the magnitudes of the terms of the point's clip z (x) and clip
// w (y), the object-to-clip matrix's rows times its object-space coordinates; `clip` its clip
// position. Each of z and w is a sum of products of rounded matrix entries and a rounded
// coordinate, off by a few steps of 2^-24 of that sum, and z / w loses those steps whole where
// the two nearly cancel (vertices far from the object's origin, a near plane far nearer than the
// boxes: 1,000 units out, with a near plane of 0.01, a face came out 5e-5 deeper than drawn, three
// times the depth its occluder lay behind it). 2^-22 covers four steps of each, for the face and
// for the occluder behind it.
float bm_depth_rounding(vec2 spread, vec4 clip)
{
  return 2.4e-7 * (spread.x + abs(clip.z / clip.w) * spread.y) / abs(clip.w);
}

// How far (window depth) from the nearest hit kept at a pixel a pass that shades only that hit
// (the preview's resolved passes, three.js's useBoxmarchVisibility) looks for the fragment that
// made it: 2^-18, 64 float steps at the far plane. The march's hit depth and the inversion of a
// depth into a distance along the ray (bm_depth_crossing) round differently; on the preview's
// cloud of spheres a margin of 2^-21 (bm_occluder_limit's) lost 10 of 22,614 pixels, 2^-20 lost
// none.
float bm_shade_margin()
{
  return 3.8e-6;
}

// Distance t along a ray whose clip-space position is c0 + t c1 at which its clip depth z / w
// reaches ndc_z (GL: 2 x window depth - 1; D3D and Vulkan: the window depth), so a march can
// stop at the occluders' depth: nothing beyond it is visible. 1e30 (no bound) where the ray does
// not reach that depth ahead of it: a depth that does not change along the ray, or one past what
// the projection reaches (a depth beyond the far plane, which a perspective ray only approaches).
float bm_depth_crossing(vec4 c0, vec4 c1, float ndc_z)
{
  float rate = c1.z - ndc_z * c1.w;
  float t = abs(rate) > 1e-30 ? (ndc_z * c0.w - c0.z) / rate : -1.0;
  return t >= 0.0 ? t : 1e30;
}
