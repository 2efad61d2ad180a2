// boxmarch per-box parameters: decode of the four floats every box carries (shape, material,
// random, user; docs/FORMAT.md), its parent, and the per-box shape switch. Needs decode.glsl
// and sdf.glsl before it. shaders/generate.py translates it into every engine's language and
// into GLM for the CPU reference.

// Parameters of the box being marched (shape, material, random, user); set by the raymarcher
// before map() is called, as box_half is (the preview's PER_BOX map() reads box_params.x).
vec4 box_params = vec4(0.0);

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
// high holding 3 planes of size.y / 3 rows each (docs/ENGINES.md). Integer-valued floats, for
// texelFetch, Load or a texture lookup at (x + 0.5, y + 0.5) / size.
vec2 bm_box_table_texel(float index, float plane, vec2 size)
{
  float row = floor(index / size.x);
  return vec2(index - row * size.x, plane * floor(size.y / 3.0 + 0.5) + row);
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
