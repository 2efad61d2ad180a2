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
// boxmarch SDF library. `box_half` holds the box's half-extents (a 1 x 0.6 x 0.2 box has
// box_half = (0.5, 0.3, 0.1)), so shapes can be sized without typing numbers. Exactness of an op_
// assumes exact inputs. shaders/generate.py translates it into HLSL and into GLM for the CPU
// reference (cpp/src).

// Half-extents of the box being marched; set by the raymarcher before map() is called.
vec3 box_half = vec3(0.0);

// The smallest and the largest component.
float bm_min3(vec3 v) { return min(v.x, min(v.y, v.z)); }
float bm_max3(vec3 v) { return max(v.x, max(v.y, v.z)); }
// min3 and max3: the same, under the names map() texts use.
float min3(vec3 v) { return bm_min3(v); }
float max3(vec3 v) { return bm_max3(v); }

// ---- primitives, centred at the origin
// Exact.
float sd_sphere(vec3 p, float r) { return length(p) - r; }

// Exact. Half-extents b.
float sd_box(vec3 p, vec3 b)
{
  vec3 q = abs(p) - b;
  return length(max(q, vec3(0.0))) + min(bm_max3(q), 0.0);
}

// Exact for r <= min3(b): the box b with its edges rounded by r (outer size b).
float sd_round_box(vec3 p, vec3 b, float r) { return sd_box(p, b - vec3(r)) - r; }

// Exact. Segment a-b with radius r.
float sd_capsule(vec3 p, vec3 a, vec3 b, float r)
{
  vec3 pa = p - a;
  vec3 ba = b - a;
  float h = clamp(dot(pa, ba) / max(dot(ba, ba), 1e-20), 0.0, 1.0);
  return length(pa - ba * h) - r;
}

// Exact. Capped, axis z.
float sd_cylinder(vec3 p, float r, float half_height)
{
  vec2 d = abs(vec2(length(p.xy), p.z)) - vec2(r, half_height);
  return min(max(d.x, d.y), 0.0) + length(max(d, vec2(0.0)));
}

// Exact. Around axis z.
float sd_torus(vec3 p, float major, float minor)
{
  vec2 q = vec2(length(p.xy) - major, p.z);
  return length(q) - minor;
}

// Exact. Chain link: a ring of radius `ring` in the xy plane stretched by half_length along y.
float sd_link(vec3 p, float half_length, float ring, float thickness)
{
  vec3 q = vec3(p.x, max(abs(p.y) - half_length, 0.0), p.z);
  return length(vec2(length(q.xy) - ring, q.z)) - thickness;
}

// Exact for a unit normal n. Plane with normal n, offset along n.
float sd_plane(vec3 p, vec3 n, float offset) { return dot(p, n) + offset; }

// ---- combinations of two distances
// Exact outside both shapes, a bound inside.
float op_union(float a, float b) { return min(a, b); }
// A bound outside the result, exact inside. a minus b.
float op_subtract(float a, float b) { return max(a, -b); }
// A bound outside the result, exact inside.
float op_intersect(float a, float b) { return max(a, b); }

// Smooth versions: k is the blend radius (box-local units).
// A bound; equals op_union where |a - b| >= k.
float op_smooth_union(float a, float b, float k)
{
  float h = clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
  return mix(b, a, h) - k * h * (1.0 - h);
}
// A bound; equals op_intersect where |a - b| >= k.
float op_smooth_intersect(float a, float b, float k) { return -op_smooth_union(-a, -b, k); }
// A bound; equals op_subtract where |a + b| >= k.
float op_smooth_subtract(float a, float b, float k) { return op_smooth_intersect(a, -b, k); }

// ---- modifiers
// The shape grown by r: exact outside, a bound inside.
float op_round(float d, float r) { return d - r; }
// A shell of half-thickness `thickness` around the surface: exact outside the shell, a bound
// inside it.
float op_onion(float d, float thickness) { return abs(d) - thickness; }

// Finite repetition: copies every `spacing`, `limit` copies each side of the centre per axis.
// Moves p (returns no distance): a shape evaluated at the result stays exact when it is
// mirror-symmetric in each axis and fits its cell (half of `spacing` each side); otherwise it can
// overestimate (neither exact nor a bound: march with relaxation below 1).
// floor(x + 0.5), not round(): GLSL ES 1.00 (WebGL 1) has no round().
vec3 op_repeat_limited(vec3 p, vec3 spacing, vec3 limit)
{
  return p - spacing * clamp(floor(p / spacing + 0.5), -limit, limit);
}

// ---- presets of the preview's SDF menu, sized by the box
// A preset with a preferred axis (capsule, cylinder, torus, link) reads the box's axes by extent,
// not by name, so it fits its box whatever order the bake gave the axes (no bake option needed).

// v with its components in the order that sorts h from the largest to the smallest: called with
// v = p it gives the point, with v = h the sorted half-extents. A later axis moves ahead only when
// its extent is more than 0.1% larger (the bake's tie band), so near-equal extents keep the order
// x, y, z and all boxes of one shape read their axes alike. The order depends on h alone, one
// permutation per box, so a preset that is exact on the sorted axes stays exact.
vec3 bm_by_extent(vec3 v, vec3 h)
{
  vec3 s = h;
  vec3 r = v;
  if (s.y > 1.001 * s.x) {
    s = s.yxz;
    r = r.yxz;
  }
  if (s.z > 1.001 * s.y) {
    s = s.xzy;
    r = r.xzy;
  }
  if (s.y > 1.001 * s.x) {
    s = s.yxz;
    r = r.yxz;
  }
  return r;
}

// v in the box's own axis order from the order bm_by_extent sorts h into (its inverse: the same
// swaps, decided alike, undone in reverse).
vec3 bm_from_extent(vec3 v, vec3 h)
{
  vec3 s = h;
  bool first = s.y > 1.001 * s.x;
  if (first) {
    s = s.yxz;
  }
  bool second = s.z > 1.001 * s.y;
  if (second) {
    s = s.xzy;
  }
  bool third = s.y > 1.001 * s.x;
  vec3 r = v;
  if (third) {
    r = r.yxz;
  }
  if (second) {
    r = r.xzy;
  }
  if (first) {
    r = r.yxz;
  }
  return r;
}

// Exact.
float sdf_preset_box(vec3 p, vec3 h) { return sd_box(p, h); }
// Exact.
float sdf_preset_sphere(vec3 p, vec3 h) { return sd_sphere(p, bm_min3(h)); }
// Exact.
float sdf_preset_rounded_box(vec3 p, vec3 h) { return sd_round_box(p, h, 0.25 * bm_min3(h)); }
// Exact. Along the box's longest axis, radius its smallest half-extent.
float sdf_preset_capsule(vec3 p, vec3 h)
{
  vec3 q = bm_by_extent(p, h);
  vec3 s = bm_by_extent(h, h);
  float r = min(s.y, s.z);
  float a = max(s.x - r, 0.0);
  return sd_capsule(q, vec3(-a, 0.0, 0.0), vec3(a, 0.0, 0.0), r);
}
// Exact. Along the box's longest axis where that holds the larger cylinder (a rod: longest x
// smallest > middle^2), else along its shortest axis (a disc); a cube's stands along local z.
float sdf_preset_cylinder(vec3 p, vec3 h)
{
  vec3 q = bm_by_extent(p, h);
  vec3 s = bm_by_extent(h, h);
  if (s.x * s.z > s.y * s.y) {
    q = q.yzx;
    s = s.yzx;
  }
  return sd_cylinder(q, min(s.x, s.y), s.z);
}
// Exact. Around the box's shortest axis, as wide as its middle half-extent.
float sdf_preset_torus(vec3 p, vec3 h)
{
  vec3 q = bm_by_extent(p, h);
  vec3 s = bm_by_extent(h, h);
  float minor = min(s.z, 0.5 * min(s.x, s.y));
  return sd_torus(q, min(s.x, s.y) - minor, minor);
}
// Exact. Stretched along the box's longest axis, the ring across its middle one, the thickness
// along its shortest.
float sdf_preset_link(vec3 p, vec3 h)
{
  vec3 q = bm_by_extent(p, h);
  vec3 s = bm_by_extent(h, h);
  float thickness = min(s.z, 0.25 * min(s.x, s.y));
  return sd_link(q.yxz, max(s.x - s.y, 0.0), s.y - thickness, thickness);
}

// The SDF preset a shape id picks, sized by the box's half-extents h: the id rounded to the
// nearest whole number indexes the presets in the preview's menu order (0 box, 1 sphere,
// 2 rounded box, 3 capsule, 4 cylinder, 5 torus, 6 link); any other id draws the box. Exact
// (each preset is).
float bm_sdf_by_id(float shape, vec3 p, vec3 h)
{
  float id = floor(shape + 0.5);
  if (id == 1.0) {
    return sdf_preset_sphere(p, h);
  }
  if (id == 2.0) {
    return sdf_preset_rounded_box(p, h);
  }
  if (id == 3.0) {
    return sdf_preset_capsule(p, h);
  }
  if (id == 4.0) {
    return sdf_preset_cylinder(p, h);
  }
  if (id == 5.0) {
    return sdf_preset_torus(p, h);
  }
  if (id == 6.0) {
    return sdf_preset_link(p, h);
  }
  return sdf_preset_box(p, h);
}
