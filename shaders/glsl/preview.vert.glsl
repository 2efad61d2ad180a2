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
// boxmarch viewport preview, vertex stage: decodes one engine layout's channels
// (addon/boxmarch/formats/layouts.py) with the shipped decode functions (decode.glsl, before this), as
// that engine's shader does. formats/shader_sources.py defines BM_LAYOUT_<name> first; the create-info
// (addon/boxmarch/preview/shader.py) declares the layout's inputs (shader_sources.VERTEX_INPUTS: pos
// and the channels as ch_color, ch_normal, ch_tangent, ch_uv1 .. ch_uv6, plus ch_half where the
// layout carries no per-vertex half-extents, ch_params, the box's parameters as the layout carries
// them, and ch_parent_*), the outputs (shader_sources.STAGE_INTERFACE) and the uniform block
// preview (BoxmarchPreview, see preview.frag.glsl).
// With BM_OCCLUDER_PASS defined (and sdf.glsl, box_params.glsl and raymarch.glsl before it) it is the hidden-box
// pre-pass's vertex stage: each box's vertices pulled in to its occluder box number
// occluder_index (box_params.glsl; the shape id preview.occlusion.y, or the box's own where it is
// negative), none where the eye is inside the drawn box (the marching stage then starts at the
// eye, and an occluder around the eye would hide what lies in front of it).
// preview.occlusion.z picks boxes by whether they hold the eye: the preview culls the back faces
// of closed, outward-wound boxes (the far side, hidden by the box's own front) and draws the few
// boxes holding the eye with both sides in a second draw (preview/draw.py).
void main()
{
#if defined(BM_LAYOUT_CLASSIC) || defined(BM_LAYOUT_UV_FRAME)
  vec4 q = normalize(bm_quaternion(ch_uv1, ch_uv2));
  frag_axis_x = bm_rotate_vector(vec3(1.0, 0.0, 0.0), q);
  frag_axis_y = bm_rotate_vector(vec3(0.0, 1.0, 0.0), q);
  frag_axis_z = bm_rotate_vector(vec3(0.0, 0.0, 1.0), q);
#else
  // NORMAL_*: the frame in the normal and tangent, as skinning leaves them (normalised per
  // fragment, as an engine's interpolated normal is).
  frag_axis_x = ch_tangent.xyz;
  frag_axis_y = bm_axis_y(ch_normal, ch_tangent);
  frag_axis_z = ch_normal;
#endif
#if defined(BM_LAYOUT_CLASSIC)
  // CLASSIC carries only the largest half-extent; ch_half is the preview's own, from the bake.
  frag_offset = bm_offset_from_color(ch_color);
  frag_half = ch_half;
#elif defined(BM_LAYOUT_UV_FRAME)
  frag_offset = bm_offset(ch_uv3, ch_uv4);
  frag_half = bm_half_extents(ch_uv5, ch_uv6);
#elif defined(BM_LAYOUT_NORMAL_FRAME)
  frag_offset = bm_offset(ch_uv1, ch_uv2);
  frag_half = bm_half_extents(ch_uv3, ch_uv4);
#else
  // NORMAL_COLOR: colour = (f, index); ch_half = the box table's texel at that index.
  frag_offset = bm_offset(ch_color.xy, ch_color.zw);
  frag_half = ch_half;
#endif
  frag_params = ch_params;
  // A box with a parent grows by the blend radius (preview.blend.x) when it blends into it: the
  // fillet lies within that distance of its shape. Each vertex moves away from the origin along
  // the box's axes, so f grows by the same amount.
  float grow = ch_parent_half.x < 0.0 ? 0.0 : preview.blend.x;
  vec3 outward = -sign(frag_offset) * grow;
  frag_offset -= outward;
  frag_half += vec3(grow);
  frag_parent_origin = vec4(ch_parent_origin.xyz, preview.blend.x);
  frag_parent_q = ch_parent_q;
  frag_parent_half = ch_parent_half;
  mat3 frame = mat3(preview.frame);
  vec3 grown = pos + transpose(frame) * bm_from_local(outward, frag_axis_x, frag_axis_y, frag_axis_z);
  obj_pos = grown;
  gl_Position = preview.object_to_clip * vec4(grown, 1.0);
  // Whether the eye is inside the box as drawn (perspective views): the box-local vertex is
  // v = -f before the growth, the eye's box-local position the vertex's plus the eye's offset.
  vec3 v = -(frag_offset + outward);
  vec3 eye = bm_to_local(frame * (preview.eye.xyz - pos), frag_axis_x, frag_axis_y, frag_axis_z) + v;
  vec3 beyond = abs(eye) - frag_half;
  bool eye_inside = preview.eye.w > 0.5 && max(beyond.x, max(beyond.y, beyond.z)) <= 0.0;
  // preview.occlusion.z: 1 draws only the boxes not holding the eye (their back faces culled),
  // 2 only those holding it (both sides); a box left out lies outside the clip volume.
  if ((preview.occlusion.z == 1.0 && eye_inside) || (preview.occlusion.z == 2.0 && !eye_inside)) {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
  }
#ifdef BM_OCCLUDER_PASS
  // box-local vertex v in a box of half-extents h (as baked, before the blend's growth), the box's
  // axes and origin in object space
  vec3 h = frag_half - vec3(grow);
  float shape = preview.occlusion.y < 0.0 ? ch_params.x : preview.occlusion.y;
  mat4 m = preview.object_to_clip;
  mat3 to_object = transpose(frame);
  vec3 ax = to_object * normalize(frag_axis_x);
  vec3 ay = to_object * normalize(frag_axis_y);
  vec3 az = to_object * normalize(frag_axis_z);
  vec3 origin = pos - bm_from_local(v, ax, ay, az);
  // The box's least z + w in clip space over its corners (z + w >= 0 on this side of the near
  // plane), and its greatest w (the far side, where a pixel is largest).
  vec4 near_side = vec4(m[0][2] + m[0][3], m[1][2] + m[1][3], m[2][2] + m[2][3], m[3][2] + m[3][3]);
  vec4 w_row = vec4(m[0][3], m[1][3], m[2][3], m[3][3]);
  vec3 near_reach = h * abs(vec3(dot(near_side.xyz, ax), dot(near_side.xyz, ay), dot(near_side.xyz, az)));
  vec3 far_reach = h * abs(vec3(dot(w_row.xyz, ax), dot(w_row.xyz, ay), dot(w_row.xyz, az)));
  float nearest = dot(near_side.xyz, origin) + near_side.w - near_reach.x - near_reach.y - near_reach.z;
  float farthest = dot(w_row.xyz, origin) + w_row.w + far_reach.x + far_reach.y + far_reach.z;
  // A pixel's size at the far side, in box-local units across the faces normal to each axis: the
  // view-space pixel (preview.quality.z: the projection's clip y per view unit) times how many
  // object units a plane normal to the axis lies from its parallel per view unit, |N a| with N the
  // inverse transpose of the object-to-view matrix. Under a non-uniform scale or a shear, a pixel
  // measured along the object-to-clip matrix's y row alone came out up to 5.6 times too small
  // across a squashed axis of a sheared battery scene, and occluders lay in front of their boxes'
  // faces.
  float pixel = bm_pixel_size(farthest, preview.quality.z, preview.quality.y);
  mat3 normal_to_view = mat3(preview.normal_to_view);
  vec3 across = vec3(length(normal_to_view * ax), length(normal_to_view * ay), length(normal_to_view * az));
  vec3 rounding = bm_occluder_rounding(pixel * across, length(pos));
  vec3 extent = bm_occluder_half(shape, h, occluder_index) - rounding;
  // No occluder for a box holding the eye, nor for one that reaches within the rounding of the
  // near plane (the plane cuts its front, so its shape may not be drawn where its occluders would
  // hide what lies behind), nor for one across which a march may run out of max_distance before it
  // reaches the shape (preview.march.z: it draws nothing there), nor where the rounding leaves
  // none. Its vertices go to the occluder's centre, so that its triangles have no area; where the
  // vertices of one box decide differently (each rounds its own arithmetic), what they draw still
  // lies inside the occluder.
  bool drawn = !eye_inside && nearest > bm_max3(rounding) * length(near_side.xyz) && 2.0 * length(frag_half) <= preview.march.z
    && bm_min3(extent) > 0.0;
  vec3 pulled = bm_occluder_centre(shape, h, occluder_index) + (drawn ? v * extent / max(h, vec3(1e-30)) : vec3(0.0));
  vec3 moved = pos + bm_from_local(pulled - v, ax, ay, az);
  vec4 clip = m * vec4(moved, 1.0);
  // pushed back in depth by what float32 rounding may move it (bm_depth_rounding), its place on
  // screen kept: z + k w in clip space adds k to the depth across the whole triangle
  vec2 spread = vec2(dot(abs(vec3(m[0][2], m[1][2], m[2][2])), abs(moved)) + abs(m[3][2]),
                     dot(abs(w_row.xyz), abs(moved)) + abs(w_row.w));
  clip.z += 2.0 * bm_depth_rounding(spread, clip) * clip.w;
  gl_Position = clip;
#endif
}
