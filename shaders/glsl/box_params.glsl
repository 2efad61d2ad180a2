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
// boxmarch per-box shapes: the parameters of the box being marched (decoded by decode.glsl's
// bm_box_params) and the per-box shape switch. Needs decode.glsl and sdf.glsl before it.
// shaders/generate.py translates it into every engine's language and
// into GLM for the CPU reference.

// Parameters of the box being marched (shape, material, random, user); set by the raymarcher
// before map() is called, as box_half is (the preview's PER_BOX map() reads box_params.x).
vec4 box_params = vec4(0.0);
// The parent box, in this box's local coordinates: its origin (xyz) and the blend radius (w),
// its frame as a quaternion, its half-extents (xyz; x < 0: no parent) and its shape id (w).
vec4 box_parent_origin = vec4(0.0);
vec4 box_parent_q = vec4(0.0, 0.0, 0.0, 1.0);
vec4 box_parent_half = vec4(-1.0);

// This box's shape (its shape id, sized by h) blended into its parent's across their boundary:
// the parent's shape evaluated in the parent's frame (parent_origin: its origin in this box's
// local coordinates; parent_q: its frame relative to this box's; parent_half.xyz its
// half-extents, parent_half.w its shape id; parent_half.x < 0: no parent), joined by
// op_smooth_union with blend radius k (k <= 0: the own shape). A bound. Two SDF evaluations
// with a parent, one without; the fillet lies within k of this box's shape, so the box it is
// drawn in must be grown by k.
float bm_sdf_blend_parent(float shape, vec3 p, vec3 h, vec3 parent_origin, vec4 parent_q, vec4 parent_half, float k)
{
  float own = bm_sdf_by_id(shape, p, h);
  if (k <= 0.0 || parent_half.x < 0.0) {
    return own;
  }
  vec3 in_parent = bm_rotate_vector(p - parent_origin, bm_quat_conjugate(parent_q));
  return op_smooth_union(own, bm_sdf_by_id(parent_half.w, in_parent, parent_half.xyz), k);
}

// ---- conservative occluders: boxes inscribed in each preset, for a depth-only pre-pass
// A pre-pass draws every box's occluders (the box mesh pulled in by its vertex stage to each
// occluder box: centre + v * half / h for a box-local vertex v) and keeps their nearest depth. An
// occluder lies inside its shape, so wherever it covers a pixel the visible surface there is at
// least as near: a fragment whose box entry lies behind that depth is hidden and need not march,
// and no march need go past it (docs/PREVIEW.md, "Hidden boxes"). Occluders in the style of
// conservative occluder meshes (contained in the shape, as large as cheaply possible), each shrunk
// by 1/1000 of the box's largest half-extent so that it lies strictly inside and a surface
// touching it keeps its own depth.
//
// bm_occluder_count boxes per preset (index k = 0, 1, ...; at most 4), each clipped to the box
// (the march never leaves it); a half-extent of zero: no box at k. Every box is symmetric about the preset's own axes, so an engine's mirrored frame
// (docs/EXPORT.md) sees the same set. Inscribed, per preset (h: the box's half-extents):
// * box: the box itself (exact).
// * sphere (radius r = min3(h)): three crossed boxes r(0.825, 0.4, 0.4) and their axis turns;
//   each corner lies at 0.825^2 + 2 x 0.4^2 < 1 of r: inside.
// * rounded box (box h - r rounded by r = min3(h) / 4): the three slabs of the box h with two
//   axes pulled in by r; a slab's points lie within r of the inner box h - r: inside.
// The capsule, cylinder, torus and link are placed in the preset's own frame (the box's axes sorted
// by extent, as sdf.glsl's presets read them) and mapped back.
// * capsule (axis x, half-length a, radius r): two crossed boxes (a + 0.62 r, 0.7 r, 0.35 r) and
//   (a + 0.62 r, 0.35 r, 0.7 r); at |x| = a + 0.62 r the cap's section has radius
//   0.785 r >= |(0.7, 0.35)| r = 0.783 r: inside.
// * cylinder (radius r = min(h.x, h.y), half height h.z): boxes (0.866 r, 0.5 r, h.z) and
//   (0.5 r, 0.866 r, h.z), corners on the circle: inside.
// * torus and link: bm_ring_occluder_*; the torus is the link with half-length 0.
// A draw per occluder index: the pre-pass writes depth only, so each is cheap.

// How many occluder boxes shape id `shape` has (bm_sdf_by_id's numbering).
float bm_occluder_count(float shape)
{
  // if chains, not nested ?: (Godot 3's shading language refuses a ?: inside a ?:)
  float id = floor(shape + 0.5);
  if (id == 1.0 || id == 2.0) {
    return 3.0;
  }
  if (id == 3.0 || id == 4.0) {
    return 2.0;
  }
  if (id == 5.0 || id == 6.0) {
    return 4.0;
  }
  return 1.0;
}

// Ring of a link (sd_link: the stadium of half-length `half_length` along x, radius `ring`,
// wire radius `minor`, in the xy plane) or torus (half_length 0): k = 0, 1 the straight wires at
// y = +-ring, k = 2, 3 the ends at x = +-(half_length + ring). Each box has half-extent a = minor / 2
// across the wire (radial and z), so its points lie within w = sqrt(minor^2 - a^2) of the wire's
// circle radially; along the wire it reaches e past the straight part (or either side of the
// end), where sqrt(e^2 + (ring + a)^2) = ring + w: the farthest corner at radius ring + w, the
// nearest at ring - a > ring - w. Inside the tube, exactly.
vec3 bm_ring_occluder_centre(float half_length, float ring, float k)
{
  float side = (k == 1.0 || k == 3.0) ? -1.0 : 1.0;
  return k < 2.0 ? vec3(0.0, side * ring, 0.0) : vec3(side * (half_length + ring), 0.0, 0.0);
}
vec3 bm_ring_occluder_half(float half_length, float ring, float minor, float k)
{
  float a = 0.5 * minor;
  float w = sqrt(max(minor * minor - a * a, 0.0));
  float e = sqrt(max((ring + w) * (ring + w) - (ring + a) * (ring + a), 0.0));
  return k < 2.0 ? vec3(half_length + e, a, a) : vec3(a, e, a);
}

// Centre (centre true) or half-extents of occluder box k of shape id `shape` (bm_sdf_by_id's
// numbering) in a box of half-extents h, in the preset's own frame (sdf.glsl: the capsule,
// cylinder, torus and link read the axes by extent, bm_by_extent) mapped back to the box's axes,
// before bm_occluder_centre and bm_occluder_half clip it to the box.
vec3 bm_occluder_unclipped(float shape, vec3 h, float k, bool centre)
{
  float id = floor(shape + 0.5);
  vec3 s = bm_by_extent(h, h);
  vec3 at = vec3(0.0);
  vec3 extent = k == 0.0 ? h : vec3(0.0);
  // the k-th of a preset's boxes by its axis lengths: (long, short, short) turned so the long one
  // lies along axis k (sphere, rounded box), or the first two of them (capsule, cylinder)
  vec3 turned = k == 1.0 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  if (k == 2.0) {
    turned = vec3(0.0, 0.0, 1.0);
  }
  if (id == 1.0) {
    float r = bm_min3(h);
    extent = k < 3.0 ? r * (vec3(0.4) + 0.425 * turned) : vec3(0.0);
  }
  if (id == 2.0) {
    float r = 0.25 * bm_min3(h);
    extent = k < 3.0 ? h - r * (vec3(1.0) - turned) : vec3(0.0);
  }
  if (id == 3.0) {
    float r = min(s.y, s.z);
    float reach = max(s.x - r, 0.0) + 0.62 * r;
    extent = k == 0.0 ? vec3(reach, 0.7 * r, 0.35 * r) : vec3(reach, 0.35 * r, 0.7 * r);
    extent = k < 2.0 ? bm_from_extent(extent, h) : vec3(0.0);
  }
  if (id == 4.0) {
    // sdf_preset_cylinder: along the sorted x (q.yzx) for a rod, else along the sorted z
    bool rod = s.x * s.z > s.y * s.y;
    vec3 c = rod ? s.yzx : s;
    float r = min(c.x, c.y);
    extent = k == 0.0 ? vec3(0.866 * r, 0.5 * r, c.z) : vec3(0.5 * r, 0.866 * r, c.z);
    extent = k < 2.0 ? bm_from_extent(rod ? extent.zxy : extent, h) : vec3(0.0);
  }
  if (id == 5.0) {
    float minor = min(s.z, 0.5 * min(s.x, s.y));
    at = bm_from_extent(bm_ring_occluder_centre(0.0, min(s.x, s.y) - minor, k), h);
    extent = bm_from_extent(bm_ring_occluder_half(0.0, min(s.x, s.y) - minor, minor, k), h);
  }
  if (id == 6.0) {
    float thickness = min(s.z, 0.25 * min(s.x, s.y));
    at = bm_from_extent(bm_ring_occluder_centre(max(s.x - s.y, 0.0), s.y - thickness, k), h);
    extent = bm_from_extent(bm_ring_occluder_half(max(s.x - s.y, 0.0), s.y - thickness, thickness, k), h);
  }
  return centre ? at : extent;
}

// Occluder box k clipped to the box (a shape that reaches past its box is drawn cut by it: a
// capsule or link box shorter than it is wide), then shrunk by the margin: its centre, and its
// half-extents (zero: none).
vec3 bm_occluder_centre(float shape, vec3 h, float k)
{
  vec3 centre = bm_occluder_unclipped(shape, h, k, true);
  vec3 extent = bm_occluder_unclipped(shape, h, k, false);
  return 0.5 * (max(centre - extent, -h) + min(centre + extent, h));
}
vec3 bm_occluder_half(float shape, vec3 h, float k)
{
  vec3 centre = bm_occluder_unclipped(shape, h, k, true);
  vec3 extent = bm_occluder_unclipped(shape, h, k, false);
  vec3 clipped = 0.5 * (min(centre + extent, h) - max(centre - extent, -h));
  return max(clipped - vec3(1e-3 * bm_max3(h)), vec3(0.0));
}

// How much further (box-local units) the pre-pass pulls every occluder box in than
// bm_occluder_half does, along each of the box's axes, for what the GPU rounds; `pixel`: a
// pixel's size at the box's far side, in box-local units across the faces normal to each axis
// (preview.vert.glsl says how), `reach`: the length of the object-space position its vertices are
// computed from. A rasteriser snaps each vertex to a grid of at most 1/16 of a pixel (GL's least
// sub-pixel precision), which moves a face and the occluder face just behind it sideways by
// different amounts: seen at a slant, their depths at a pixel may swap, and an occluder's edge
// may cover a pixel its box's edge leaves (on SwiftShader, a pile of rotated boxes lost 3 % of its
// pixels with the pre-pass before this rule; moving the faces 1/50 of a pixel apart left 137
// pixels lost, 1/16 none). An eighth of a pixel covers both faces' snapping; 2^-19 of the reach
// covers the float32 rounding of the vertices and of their transform (a few steps of 2^-24 each),
// which no pixel margin bounds when the vertices lie far from the object's origin.
vec3 bm_occluder_rounding(vec3 pixel, float reach)
{
  return 0.125 * pixel + vec3(1.9e-6 * reach);
}
