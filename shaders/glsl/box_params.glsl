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
