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
// fragment whose box entry lies beyond it is hidden; a march stops at it. Plus a quarter of
// `depth_slope`, how much the occluder's depth changes from one pixel to the next (its fragment's
// fwidth(gl_FragCoord.z); 0 for a depth found by casting the ray, as the CPU reference does): a
// rasteriser snaps the corners to its sub-pixel grid (GL asks 4 bits or more: each of x and y
// moves up to 1/32 px) and interpolates the depth plane through the snapped corners, so a pixel
// gets the face's depth at a point up to 1/32 px away in x and in y, off by up to depth_slope / 32.
// A face seen nearly edge-on changes its depth fast: on SwiftShader one at 87 degrees to the view
// (cut battery seed 1285) came out 0.0027 nearer than drawn, in front of its own box's hit. A
// quarter covers 8 times that bound, for the occluder and for its box's face parallel to it (whose
// hit's depth carries its face's error).
float bm_occluder_limit(float occluder_depth, float depth_slope)
{
  return occluder_depth + 4.8e-7 + 0.25 * depth_slope;
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

// Distance t along a ray whose clip-space position is c0 + t c1 from which its points lie deeper
// than ndc_z (GL: 2 x window depth - 1; D3D and Vulkan: the window depth; a depth that grows with
// distance, not reversed Z), so a march can stop there (the occluders' depth): nothing beyond it
// is visible. A hit where clip w is not positive takes depth 0 (bm_hit_depth, a march from the
// eye: c0 the eye's, w 0 give or take rounding), so the bound lies no nearer than where w rises
// above 0. 1e30 (no bound) where the ray does not pass that depth ahead of it: a depth that does
// not grow along the ray, or one past what the projection reaches (a depth beyond the far plane,
// which a perspective ray only approaches), or a ray whose w never rises: a direction rounded
// away from the view (the eye thousands of units from the object's origin in a scene millimetres
// across: cut battery seed 2333, where the crossing, taken where w < 0, cut off a march from the
// eye whose hit had depth 0).
float bm_depth_crossing(vec4 c0, vec4 c1, float ndc_z)
{
  float rate = c1.z - ndc_z * c1.w;
  if (c1.w < 0.0 || (c1.w == 0.0 && c0.w <= 0.0) || !(rate > 1e-30)) {
    return 1e30;
  }
  float t = (ndc_z * c0.w - c0.z) / rate;
  if (t < 0.0) {
    return 1e30;
  }
  return c0.w < 0.0 ? max(t, -c0.w / c1.w) : t;
}

// Whether a fragment marches from the eye rather than from its face: a fragment of its box's far
// side (no less of the box behind it than ahead; span: bm_box_span from the fragment along the ray
// from the eye) that is a back face (outer_face false), or, whatever its winding, whose box holds
// the eye (perspective: the eye a point, eye_distance from the fragment, no farther than the box
// reaches behind it): an inside-out box's far side faces the eye. A back face of the far side
// whose box does not hold the eye draws nothing (the caller drops it): among them a back face
// whose ray meets the box only on its surface (span (0, 0): a pixel centre on the box's silhouette
// edge, which the rasteriser's fill rule may give to the back faces and not to the front ones;
// cut battery seed 3369, an orthographic ray along a box's edge, where a draw culling back faces
// showed the box behind), so that culling changes nothing there.
bool bm_from_eye(vec2 span, bool outer_face, bool perspective, float eye_distance)
{
  return span.x + span.y <= 0.0 && (!outer_face || (perspective && eye_distance <= -span.x));
}

// The window depth a hit writes, from its own (window_depth, the caller's clip z / w mapped to its
// depth range) and its clip w: never nearer than the rasterised face (face_depth), what a stage
// declaring depth GREATER must keep; but a march from the eye (own) writes its hit's own depth,
// in front of the eye, 0 where the eye is in the shape (t = 0, clip w 0 give or take rounding).
// In [0, 1], as a depth buffer clamps what it is given (passes that compare depths read it); -1
// (the caller draws nothing) where a march from its face hits in front of the near plane: what
// lies there is clipped, as the rasteriser clips faces. A rasteriser may still hand a face a hair
// in front of that plane (llvmpipe: window depth -9e-6; SwiftShader: -7e-3, a face nearly edge-on
// whose winding came out reversed, cut battery seed 3188): drawn there at depth 0, its hit would
// show where a draw culling back faces leaves the box behind.
float bm_hit_depth(float window_depth, float clip_w, float face_depth, bool own)
{
  if (own) {
    return clamp(clip_w > 0.0 ? window_depth : 0.0, 0.0, 1.0);
  }
  float depth = max(window_depth, face_depth);
  return depth < 0.0 ? -1.0 : min(depth, 1.0);
}

// ---- closed-form hits of the presets
// Where map() is a preset (sdf.glsl sdf_preset_*, or bm_sdf_by_id of each box's shape id) the
// fragment solves its first hit in closed form instead of marching (Quilez's ray intersectors):
// one solve per fragment, the exact surface (no epsilon fattening the silhouette), and the unit
// normal from the same solution (no map() taps). Each bm_hit_* takes a ray ro + t rd (rd unit)
// in the shape's own frame and returns (unit normal, t) of its first surface point at t >= 0, or
// w = -1.0 where the ray misses. The ray starts outside the shape or on its surface (at a box
// face; a fragment whose eye may lie inside the shape tests map() there itself). Measured against
// float64 in docs/ACCURACY.md ("Closed-form hits").

// The nearer of hit `best` and the surface point (n, t), for t >= -slack: a root a rounding behind
// the start (a ray starting on the surface, where a shape touches its box's face) hits at 0.
vec4 bm_nearer_hit(vec4 best, vec3 n, float t, float slack)
{
  if (t >= -slack && (best.w < 0.0 || max(t, 0.0) < best.w)) {
    return vec4(n, max(t, 0.0));
  }
  return best;
}

// The hit of a ray whose start ro, on a face of the box |p| <= h, lies inside the shape: at once,
// with that face's normal (the shape's own where it touches the face). A fragment's start is its
// box face's point rounded, by about 1e-4 units where the vertices lie 1,300 units from the
// object's origin: where the shape touches that face the start may lie a rounding inside it, where
// the solves answer late (a farther piece's root) or with no normal (issue 36, cut battery seeds
// 2 and 80: a NaN colour). Callers test the start with the shape's SDF. A face the ray leaves by
// (the start and the ray on one side of the centre along its axis) gives way to a face it enters by
// lying within 1e-4 of the half-extent as near: at a box's silhouette a start on the entered face
// rounds onto the face beside it, seen from behind (cut battery seed 2387: the front face's
// fragment shaded with the far face's normal, the far face's fragment with the near one's).
vec4 bm_face_hit(vec3 ro, vec3 rd, vec3 h)
{
  vec3 a = abs(ro) / h - 1e-4 * vec3(ro.x * rd.x >= 0.0 ? 1.0 : 0.0, ro.y * rd.y >= 0.0 ? 1.0 : 0.0,
                                      ro.z * rd.z >= 0.0 ? 1.0 : 0.0);
  vec3 n = vec3(0.0, 0.0, ro.z < 0.0 ? -1.0 : 1.0);
  if (a.x >= a.y && a.x >= a.z) {
    n = vec3(ro.x < 0.0 ? -1.0 : 1.0, 0.0, 0.0);
  }
  else if (a.y >= a.z) {
    n = vec3(0.0, ro.y < 0.0 ? -1.0 : 1.0, 0.0);
  }
  return vec4(n, 0.0);
}

// Nearer root of a t^2 + 2 b t + c = 0 (a > 0; h = b^2 - a c >= 0), without the cancellation of
// (-b - sqrt(h)) / a where the origin lies near the surface.
float bm_near_root(float a, float b, float c, float h)
{
  return b < 0.0 ? c / (sqrt(h) - b) : (-b - sqrt(h)) / a;
}

// Sphere of radius r at the origin; the discriminant from the ray's closest approach (no digits
// lost for a far origin).
vec4 bm_hit_sphere(vec3 ro, vec3 rd, float r)
{
  float b = dot(ro, rd);
  vec3 closest = ro - b * rd;
  float h = r * r - dot(closest, closest);
  if (h < 0.0 || sqrt(h) - b < 0.0) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  float t = max(bm_near_root(1.0, b, dot(ro, ro) - r * r, h), 0.0);
  return vec4(normalize(ro + rd * t), t);
}

// Box of half-extents b (slabs: bm_box_span); the normal is the entered face's.
vec4 bm_hit_box(vec3 ro, vec3 rd, vec3 b)
{
  vec2 span = bm_box_span(ro, rd, b);
  if (span.x > span.y || span.y < 0.0) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  vec3 s = vec3(rd.x < 0.0 ? -1.0 : 1.0, rd.y < 0.0 ? -1.0 : 1.0, rd.z < 0.0 ? -1.0 : 1.0);
  vec3 t_near = (-b - s * ro) / max(abs(rd), vec3(1e-12));
  vec3 n = vec3(0.0, 0.0, -s.z);
  if (t_near.x >= t_near.y && t_near.x >= t_near.z) {
    n = vec3(-s.x, 0.0, 0.0);
  }
  else if (t_near.y >= t_near.z) {
    n = vec3(0.0, -s.y, 0.0);
  }
  return vec4(n, max(span.x, 0.0));
}

// sd_round_box(p, b, r): the box b - r grown by r (Quilez's): where the ray enters the box b in a
// face's flat part, that point; else the nearest of the corner sphere and the three edge
// cylinders of the octant it enters (a piece's surface outside its own part lies inside the shape).
vec4 bm_hit_round_box(vec3 ro, vec3 rd, vec3 b, float r)
{
  vec2 span = bm_box_span(ro, rd, b);
  if (span.x > span.y || span.y < 0.0) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  vec3 size = b - vec3(r);
  // where the ray enters the box, or its start inside it
  float t = max(span.x, 0.0);
  vec3 entry = ro + rd * t;
  vec3 s = vec3(entry.x < 0.0 ? -1.0 : 1.0, entry.y < 0.0 ? -1.0 : 1.0, entry.z < 0.0 ? -1.0 : 1.0);
  vec3 flat_part = abs(entry) - size;
  flat_part = max(flat_part, flat_part.yzx);
  if (bm_min3(flat_part) >= 0.0) {
    // in the octant's frame (s flips it into the first); o: from the inner corner
    vec3 o = ro * s - size;
    vec3 d = rd * s;
    t = -1.0;
    float b2 = dot(o, d);
    float h = b2 * b2 - dot(o, o) + r * r;
    if (h >= 0.0 && sqrt(h) - b2 >= 0.0) {
      t = max(bm_near_root(1.0, b2, dot(o, o) - r * r, h), 0.0);
    }
    // edge along x: the cylinder around the line o.yz = 0, within |p.x| <= size.x
    vec3 a = vec3(d.y * d.y + d.z * d.z, d.z * d.z + d.x * d.x, d.x * d.x + d.y * d.y);
    vec3 bb = vec3(o.y * d.y + o.z * d.z, o.z * d.z + o.x * d.x, o.x * d.x + o.y * d.y);
    vec3 cc = vec3(o.y * o.y + o.z * o.z, o.z * o.z + o.x * o.x, o.x * o.x + o.y * o.y) - vec3(r * r);
    vec3 hh = bb * bb - a * cc;
    if (hh.x >= 0.0 && a.x > 0.0) {
      float te = (-bb.x - sqrt(hh.x)) / a.x;
      if (te >= 0.0 && (t < 0.0 || te < t) && abs(ro.x + rd.x * te) <= size.x) {
        t = te;
      }
    }
    if (hh.y >= 0.0 && a.y > 0.0) {
      float te = (-bb.y - sqrt(hh.y)) / a.y;
      if (te >= 0.0 && (t < 0.0 || te < t) && abs(ro.y + rd.y * te) <= size.y) {
        t = te;
      }
    }
    if (hh.z >= 0.0 && a.z > 0.0) {
      float te = (-bb.z - sqrt(hh.z)) / a.z;
      if (te >= 0.0 && (t < 0.0 || te < t) && abs(ro.z + rd.z * te) <= size.z) {
        t = te;
      }
    }
    if (t < 0.0) {
      return vec4(0.0, 0.0, 0.0, -1.0);
    }
  }
  t = max(t, 0.0);
  vec3 p = ro + rd * t;
  vec3 outward = max(abs(p) - size, vec3(0.0));
  vec3 sp = vec3(p.x < 0.0 ? -1.0 : 1.0, p.y < 0.0 ? -1.0 : 1.0, p.z < 0.0 ? -1.0 : 1.0);
  return vec4(sp * outward / max(length(outward), 1e-30), t);
}

// sd_round_box(p, b, r)'s hit for a fragment's ray: a start inside the shape hits at once
// (bm_face_hit), else bm_hit_round_box's (three.js's and Godot 3's default map).
vec4 bm_round_box_hit(vec3 ro, vec3 rd, vec3 b, float r)
{
  if (sd_round_box(ro, b, r) > 0.0) {
    return bm_hit_round_box(ro, rd, b, r);
  }
  return bm_face_hit(ro, rd, b);
}

// Capsule along x: the segment |x| <= half_length, radius r. The cylinder around the axis where
// its entry lies along the segment, else the end sphere on that side (a ray along the axis enters
// the cap it travels towards).
vec4 bm_hit_capsule(vec3 ro, vec3 rd, float half_length, float r)
{
  float a = rd.y * rd.y + rd.z * rd.z;
  float b = ro.y * rd.y + ro.z * rd.z;
  float c = ro.y * ro.y + ro.z * ro.z - r * r;
  float h = b * b - a * c;
  if (h < 0.0 || (a < 1e-20 && c > 0.0)) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  // (if chains, not nested ?: here and below: Godot 3's shading language refuses a ?: inside a ?:)
  float t = -1e30;
  if (a >= 1e-20) {
    t = bm_near_root(a, b, c, h);
  }
  float x = ro.x + rd.x * t;
  // entering the side ahead, or starting on it (a root a rounding behind)
  bool on_side = t < 0.0 && (c <= 0.0 || t >= -1e-4 * r) && abs(ro.x) <= half_length;
  if ((t >= 0.0 && abs(x) <= half_length) || on_side) {
    t = max(t, 0.0);
    vec3 p = ro + rd * t;
    return vec4(normalize(vec3(0.0, p.y, p.z)), t);
  }
  // else the cap of the side the ray enters at (the start's side where the entry lies behind)
  float side = a < 1e-20 ? -rd.x : ro.x;
  if (t >= 0.0) {
    side = x;
  }
  return bm_hit_sphere(ro - vec3(side < 0.0 ? -half_length : half_length, 0.0, 0.0), rd, r);
}

// Capped cylinder around z: radius r, |z| <= half_height. The span inside the infinite cylinder
// meets the caps' slab; the normal is that of whichever was entered last.
vec4 bm_hit_cylinder(vec3 ro, vec3 rd, float r, float half_height)
{
  float a = rd.x * rd.x + rd.y * rd.y;
  float b = ro.x * rd.x + ro.y * rd.y;
  float c = ro.x * ro.x + ro.y * ro.y - r * r;
  float h = b * b - a * c;
  if (h < 0.0 || (a < 1e-20 && c > 0.0)) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  float side_in = -1e30;
  float side_out = 1e30;
  if (a >= 1e-20) {
    side_in = bm_near_root(a, b, c, h);
    side_out = b < 0.0 ? (sqrt(h) - b) / a : c / (-b - sqrt(h));
  }
  float s = rd.z < 0.0 ? -1.0 : 1.0;
  float inv = 1.0 / max(abs(rd.z), 1e-12);
  float cap_in = (-half_height - s * ro.z) * inv;
  float cap_out = (half_height - s * ro.z) * inv;
  float t_in = max(side_in, cap_in);
  if (t_in > min(side_out, cap_out) || min(side_out, cap_out) < 0.0) {
    return vec4(0.0, 0.0, 0.0, -1.0);
  }
  float t = max(t_in, 0.0);
  vec3 p = ro + rd * t;
  vec3 n = side_in > cap_in ? normalize(vec3(p.x, p.y, 0.0)) : vec3(0.0, 0.0, -s);
  return vec4(n, t);
}

// Unit gradient of sd_link(p, half_length, ring, minor) (half_length 0: sd_torus's): away from the
// nearest point of the ring's centre line.
vec3 bm_link_normal(vec3 p, float half_length, float ring)
{
  vec3 q = vec3(p.x, p.y - clamp(p.y, -half_length, half_length), p.z);
  float radial = length(q.xy);
  return normalize(vec3(q.xy * ((radial - ring) / max(radial, 1e-30)), q.z));
}

// The torus around z (radii major, minor) centred at `centre` on the y axis, its points with
// side * (y - centre) >= 0 (side 0: all), as hits nearer than `best` (their t; the normal is
// bm_hit_link's). The quartic in t is solved
// in a frame scaled by 1 / major with the origin moved to the ray's closest approach to the centre,
// where it is depressed (no cubic term) and its coefficients are of order 1 whatever the box's size
// and distance; Ferrari's factorisation into two quadratics from the largest root of the resolvent
// cubic (closed form, one Newton step). Roots within the rounding of the order-1 coefficients;
// bm_hit_link polishes the nearest on the SDF.
vec4 bm_hit_torus_part(vec3 ro, vec3 rd, float major, float minor, float centre, float side, vec4 best)
{
  // the part's bounding box (grown by a rounding): a ray that misses it, or enters it beyond
  // `best`, skips the quartic
  float reach = major + minor;
  float half_y = side == 0.0 ? reach : 0.5 * reach;
  vec2 span = bm_box_span(ro - vec3(0.0, centre + side * half_y, 0.0), rd,
                          vec3(reach, half_y, minor) + vec3(1e-4 * major));
  if (span.x > span.y || span.y < 0.0 || (best.w >= 0.0 && span.x > best.w)) {
    return best;
  }
  vec3 o = (ro - vec3(0.0, centre, 0.0)) / major;
  float r = minor / major;
  float t0 = -dot(o, rd);
  o += rd * t0;
  float m = dot(o, o);
  if (m > (1.0 + r) * (1.0 + r)) {
    return best;
  }
  // t^4 + P t^2 + Q t + S = 0
  float k = m - 1.0 - r * r;
  float P = 2.0 * k + 4.0 * rd.z * rd.z;
  float Q = 8.0 * o.z * rd.z;
  float S = k * k - 4.0 * r * r + 4.0 * o.z * o.z;
  // largest root of y^3 + A y^2 + B y + C (Ferrari's resolvent): depressed by y = x - A / 3
  float A = -0.5 * P;
  float B = -S;
  float C = 0.5 * P * S - 0.125 * Q * Q;
  float p3 = (B - A * A / 3.0) / 3.0;
  float q2 = 0.5 * (2.0 * A * A * A / 27.0 - A * B / 3.0 + C);
  float disc = q2 * q2 + p3 * p3 * p3;
  float x = 0.0;
  if (disc < 0.0) {
    // three real roots (p3 < 0): the largest
    float root = sqrt(-p3);
    x = 2.0 * root * cos(acos(clamp(-q2 / (root * root * root), -1.0, 1.0)) / 3.0);
  }
  else {
    // one: Cardano's, the cube root taken of the sum that does not cancel
    float w = -q2 + (q2 > 0.0 ? -sqrt(disc) : sqrt(disc));
    float u = (w < 0.0 ? -1.0 : 1.0) * pow(abs(w), 1.0 / 3.0);
    x = u == 0.0 ? 0.0 : u - p3 / u;
  }
  float y = x - A / 3.0;
  float slope = (3.0 * y + 2.0 * A) * y + B;
  y -= abs(slope) > 1e-20 ? (((y + A) * y + B) * y + C) / slope : 0.0;
  // (t^2 + y)^2 = (a t - c)^2: t^2 - a t + y + c = 0 and t^2 + a t + y - c = 0
  float a = sqrt(max(2.0 * y - P, 0.0));
  float e = sqrt(max(y * y - S, 0.0));
  float c = Q < 0.0 ? -e : e;
  if (a > e) {
    c = 0.5 * Q / a;
  }
  vec4 found = best;
  for (int i = 0; i < 2; ++i) {
    float half_a = i == 0 ? 0.5 * a : -0.5 * a;
    float h = half_a * half_a - (i == 0 ? y + c : y - c);
    if (h >= 0.0) {
      for (int j = 0; j < 2; ++j) {
        float t = major * (t0 + half_a + (j == 0 ? -sqrt(h) : sqrt(h)));
        vec3 p = ro + rd * t;
        if (side * (p.y - centre) >= 0.0) {
          found = bm_nearer_hit(found, vec3(0.0), t, 1e-4 * major);
        }
      }
    }
  }
  return found;
}

// sd_link(p, half_length, ring, minor): the two straight tubes (cylinders along y at x = +-ring,
// |y| <= half_length) and the two half-tori at y = +-half_length, the nearest; then one Newton step
// on sd_link along the ray (the quartic's root to float precision: a second one changes the error
// by less than its noise, bench_closed_form; skipped where the ray grazes the surface, within 0.06
// degrees), the normal its gradient there. A torus: half_length 0.
vec4 bm_hit_link(vec3 ro, vec3 rd, float half_length, float ring, float minor)
{
  vec4 best = vec4(0.0, 0.0, 0.0, -1.0);
  float a = rd.x * rd.x + rd.z * rd.z;
  for (int i = 0; i < 2; ++i) {
    float x0 = i == 0 ? ring : -ring;
    float b = (ro.x - x0) * rd.x + ro.z * rd.z;
    float c = (ro.x - x0) * (ro.x - x0) + ro.z * ro.z - minor * minor;
    float h = b * b - a * c;
    if (h >= 0.0 && a >= 1e-20 && half_length > 0.0) {
      float t = bm_near_root(a, b, c, h);
      if (abs(ro.y + rd.y * t) <= half_length) {
        best = bm_nearer_hit(best, vec3(0.0), t, 1e-4 * minor);
      }
    }
  }
  if (half_length > 0.0) {
    // the end the ray travels away from first (usually the nearer, whose hit can spare the other)
    float first = rd.y < 0.0 ? 1.0 : -1.0;
    best = bm_hit_torus_part(ro, rd, ring, minor, first * half_length, first, best);
    best = bm_hit_torus_part(ro, rd, ring, minor, -first * half_length, -first, best);
  }
  else {
    best = bm_hit_torus_part(ro, rd, ring, minor, 0.0, 0.0, best);
  }
  if (best.w < 0.0) {
    return best;
  }
  float t = best.w;
  for (int i = 0; i < 1; ++i) {
    vec3 p = ro + rd * t;
    float slope = dot(bm_link_normal(p, half_length, ring), rd);
    if (slope < -1e-3) {
      float q = sd_link(p, half_length, ring, minor);
      t = max(t - clamp(q / slope, -minor, minor), 0.0);
    }
  }
  return vec4(bm_link_normal(ro + rd * t, half_length, ring), t);
}

// bm_preset_hit's solve for a start outside the shape: each preset in its own frame as sdf.glsl
// sizes it.
vec4 bm_preset_solve(float shape, vec3 ro, vec3 rd, vec3 h)
{
  float id = floor(shape + 0.5);
  if (id == 1.0) {
    return bm_hit_sphere(ro, rd, bm_min3(h));
  }
  if (id == 2.0) {
    return bm_hit_round_box(ro, rd, h, 0.25 * bm_min3(h));
  }
  if (id < 3.0 || id > 6.0) {
    return bm_hit_box(ro, rd, h);
  }
  vec3 o = bm_by_extent(ro, h);
  vec3 d = bm_by_extent(rd, h);
  vec3 s = bm_by_extent(h, h);
  vec4 hit = vec4(0.0);
  if (id == 3.0) {
    float r = min(s.y, s.z);
    hit = bm_hit_capsule(o, d, max(s.x - r, 0.0), r);
  }
  if (id == 4.0) {
    bool rod = s.x * s.z > s.y * s.y;
    vec3 c = rod ? s.yzx : s;
    hit = bm_hit_cylinder(rod ? o.yzx : o, rod ? d.yzx : d, min(c.x, c.y), c.z);
    hit.xyz = rod ? hit.zxy : hit.xyz;
  }
  if (id == 5.0) {
    float minor = min(s.z, 0.5 * min(s.x, s.y));
    hit = bm_hit_link(o, d, 0.0, min(s.x, s.y) - minor, minor);
  }
  if (id == 6.0) {
    float thickness = min(s.z, 0.25 * min(s.x, s.y));
    hit = bm_hit_link(o.yxz, d.yxz, max(s.x - s.y, 0.0), s.y - thickness, thickness);
    hit.xyz = hit.yxz;
  }
  return vec4(bm_from_extent(hit.xyz, h), hit.w);
}

// The first hit of the preset shape id `shape` picks (bm_sdf_by_id's numbering) sized by the box's
// half-extents h, box-local: (unit normal, t), w = -1.0 where the ray misses; a start inside the
// shape hits at once (bm_face_hit).
vec4 bm_preset_hit(float shape, vec3 ro, vec3 rd, vec3 h)
{
  if (bm_sdf_by_id(shape, ro, h) > 0.0) {
    return bm_preset_solve(shape, ro, rd, h);
  }
  return bm_face_hit(ro, rd, h);
}
