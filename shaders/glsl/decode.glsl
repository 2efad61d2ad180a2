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
// boxmarch decode: recover a fragment's box-local frame from the baked vertex data
// (docs/FORMAT.md). shaders/generate.py translates it into every engine's language.
// The blog post's shader has its own GetFragToOrigin,
// GetRotation and rotate_vector; bm_offset_from_color, bm_quaternion and bm_rotate_vector compute
// the same, so that shader reads the CLASSIC layout unchanged (docs/FORMAT.md names the pairs).

// f = vector from the fragment to its submesh's origin, in box-local coordinates.
// color = the BoxOffset colour attribute (rgb = 0.5 + 0.5 * s * f, a = s).
vec3 bm_offset_from_color(vec4 color)
{
  return (color.rgb * 2.0 - 1.0) / color.a;
}

// q = the submesh's frame as a quaternion (x, y, z, w) mapping box-local to object space,
// from the two UV maps BoxQuatXY and BoxQuatZW.
vec4 bm_quaternion(vec2 quat_xy, vec2 quat_zw)
{
  return vec4(quat_xy, quat_zw);
}

// q v q* for a unit quaternion q; bm_rotate_vector(v, bm_quat_conjugate(q)) is the inverse
// rotation.
vec3 bm_rotate_vector(vec3 v, vec4 q)
{
  return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

// The inverse rotation of a unit quaternion.
vec4 bm_quat_conjugate(vec4 q)
{
  return vec4(-q.xyz, q.w);
}

// ---- Engine layouts (docs/ENGINES.md). The NORMAL_* layouts carry the frame in the normal
// (local z) and the tangent (local x, w = +1), the two vectors every engine's skinning
// transforms; UV_FRAME carries the quaternion as CLASSIC does. The offset f, the box index and
// the half-extents h ride in float channels: UVa = f.xy, UVb = (f.z, index), UVc = h.xy,
// UVd = (h.z, 0) (NORMAL_COLOR: colour = (f, index), h from the box table).

// Local y axis of a NORMAL_* frame: the glTF bitangent cross(normal, tangent.xyz) * tangent.w.
vec3 bm_axis_y(vec3 normal, vec4 tangent)
{
  return cross(normal, tangent.xyz) * tangent.w;
}

// Box-local coordinates of v, given the frame's unit axes x, y, z in v's space.
vec3 bm_to_local(vec3 v, vec3 x, vec3 y, vec3 z)
{
  return vec3(dot(v, x), dot(v, y), dot(v, z));
}

// The vector with box-local coordinates l, in the space of the axes x, y, z.
vec3 bm_from_local(vec3 l, vec3 x, vec3 y, vec3 z)
{
  return x * l.x + y * l.y + z * l.z;
}

// f from the offset pair of channels (f.xy, (f.z, index)).
vec3 bm_offset(vec2 offset_xy, vec2 offset_z_index)
{
  return vec3(offset_xy, offset_z_index.x);
}

// The box number from its interpolated channel (constant over a box; rounding absorbs
// interpolation round-off).
float bm_box_index(float channel)
{
  return floor(channel + 0.5);
}

// h from the half-extent pair of channels (h.xy, (h.z, 0)).
vec3 bm_half_extents(vec2 half_xy, vec2 half_z)
{
  return vec3(half_xy, half_z.x);
}

// ---- Per-box parameters and parents (docs/ENGINES.md: which channels or box-table plane hold
// them in each layout).

// The box's parameters (shape, material, random, user) from the layout's two channels
// (shape, material) and (random, user) (docs/ENGINES.md), or from the box table's plane 1 texel
// passed as (texel.xy, texel.zw).
vec4 bm_box_params(vec2 shape_material, vec2 random_user)
{
  return vec4(shape_material, random_user);
}

// The parent's box number from its interpolated channel, -1 for a root (rounding absorbs
// interpolation round-off, as bm_box_index does).
float bm_parent_index(float channel)
{
  return floor(channel + 0.5);
}

// Texel (x, y) of box `index` in plane `plane` of the box table, an image `size` texels wide and
// high holding 5 planes of size.y / 5 rows each (docs/ENGINES.md): 0 (h, parent), 1 (shape,
// material, random, user), 2 (depth, 0, 0, 0), 3 (origin, 0), 4 the frame's quaternion.
// Integer-valued floats, for texelFetch, Load or a texture lookup at (x + 0.5, y + 0.5) / size.
vec2 bm_box_table_texel(float index, float plane, vec2 size)
{
  float row = floor(index / size.x);
  return vec2(index - row * size.x, plane * floor(size.y / 5.0 + 0.5) + row);
}
