// boxmarch per-box shapes: the parameters of the box being marched (decoded by decode.glsl's
// bm_box_params) and the per-box shape switch. Needs decode.glsl and sdf.glsl before it.
// shaders/generate.py translates it into every engine's language and
// into GLM for the CPU reference.

// Parameters of the box being marched (shape, material, random, user); set by the raymarcher
// before map() is called, as box_half is (the preview's PER_BOX map() reads box_params.x).
vec4 box_params = vec4(0.0);

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
