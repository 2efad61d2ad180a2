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
// boxmarch viewport preview, fragment stage: one fragment of a rasterised submesh takes its box
// frame, offset and half-extents from the vertex stage (which decoded the layout's channels),
// sphere-traces map() inside the box, writes the hit's depth and shades it.
// Comes after decode.glsl, sdf.glsl, raymarch.glsl and a map() definition.
// Uniform block `preview` (BoxmarchPreview): object_to_clip; normal_to_view (inverse transpose
// of the object-to-view rotation part); frame (the baked data's object frame from Blender's object
// frame: identity, or an export preset's orthonormal axis change); eye (object-space camera position with w = 1, or for
// orthographic views the object-space view direction with w = 0); march (epsilon, relaxation,
// max_distance, max_steps); base_color; mode.x (0 shaded, 1 object-space normal as colour,
// 2 steps of every fragment in red, 1 in blue, with alpha 1, for Blender's ADDITIVE blend: src *
// alpha + dst); mode.y (1: the object's matrix mirrors, so its boxes' outer faces are the ones
// gl_FrontFacing calls back faces);
// quality (x: the quality knob of bm_quality, y: the viewport height in pixels, z: the projection's
// clip y per view-space unit, its [1][1]);
// blend.x (the blend radius of PER_BOX_BLEND, else 0); blend.y (1: colour each box by its
// material id); occlusion.x (1: the hidden-box pre-pass ran and occluder_depth holds the nearest
// window depth of the occluders at each pixel, docs/PREVIEW.md "Hidden boxes"; 0: none),
// occlusion.y (the pre-pass's shape id, preview.vert.glsl). With the pre-pass a fragment whose box
// entry lies behind the occluders returns before marching (every renderer runs it: this does not
// rest on the driver's early depth test) and no march goes past the occluders' depth. In mode 2
// the green channel counts every map() evaluation (march steps plus a hit's 3 normal taps) and
// the blue one every fragment run.
// The written depth is never nearer than the rasterised face's (clamped): the create-info
// declares it (depth_write GREATER, Blender 4+), which allows a driver to keep its early depth
// test; NVIDIA's GL driver, Mesa llvmpipe and SwiftShader were measured not to (docs/BENCHMARKS.md).
// But a march from the eye (a fragment of the far side of a box holding the eye) hits nearer than
// its fragment: with BM_EYE_BOXES defined it is the stage that draws the boxes holding the eye
// (preview/draw.py draws them apart in every perspective view), compiled without that declaration
// (depth_write ANY), and writes such a hit's own depth; clamped to its far side, a box nested in
// the eye's box between the hit and that far side would show through the hit's surface.
// Mirrored by cpp/src/raymarch.cpp (render_boxes); bm_shade is translated into it by
// shaders/generate.py.
//
// With BM_RESOLVED defined it is the stage of the preview's resolved passes (preview/resolve.py,
// docs/PREVIEW.md "Hidden boxes"), which write no depth, so that the depth test runs before the
// fragment stage on every renderer (declared: early_fragment_tests) and hidden fragments are never
// run: preview.occlusion.w = 1, the visibility pass, tested against the occluders' depth, keeps the
// nearest hit's window depth of each pixel in the image hit_min (as uint bits: for depths >= 0
// their order is the floats'); 2, the shade pass, tested against that depth, shades only the
// fragment whose march gives that very depth, the same program making the same march.

#ifdef BM_RESOLVED
layout(early_fragment_tests) in;

// BM_NO_HIT (defined by formats/shader_sources.py, as for preview_resolve.glsl): hit_min's value
// where no hit was kept, the bits of 2.0, above every depth kept.
#endif

// Ends a fragment that draws nothing: thrown away, or in mode 2 (STEPS) counted, with the SDF
// evaluations it made before it stopped, as one fragment run.
void bm_drop(float evaluations)
{
  if (preview.mode.x == 2) {
    frag_color = vec4(evaluations, evaluations, 1.0, 1.0);
  }
  else {
    discard;
  }
}

// Lambert from a light fixed in view space plus a sky/ground hemisphere, like the viewport's
// studio look.
vec3 bm_shade(vec3 n_view, vec3 base)
{
  const vec3 light = normalize(vec3(0.35, 0.45, 0.82));
  float lambert = max(dot(n_view, light), 0.0);
  vec3 ambient = mix(vec3(0.20, 0.19, 0.18), vec3(0.42, 0.45, 0.50), 0.5 + 0.5 * n_view.y);
  return base * (ambient + 0.8 * lambert);
}

// A distinct colour per material id (golden-ratio hues), for the preview's Colour by Material.
vec3 bm_material_colour(float material)
{
  vec3 phase = vec3(0.0, 0.33, 0.67) + vec3(0.618034 * floor(material + 0.5));
  return vec3(0.55) + 0.4 * vec3(cos(6.283185 * phase.x), cos(6.283185 * phase.y), cos(6.283185 * phase.z));
}

void main()
{
  // The box frame's axes (the vertex stage decoded them from the layout's channels).
  vec3 x = normalize(frag_axis_x);
  vec3 y = normalize(frag_axis_y);
  vec3 z = normalize(frag_axis_z);
  vec3 f = frag_offset;
  box_params = frag_params;
  box_parent_origin = frag_parent_origin;
  box_parent_q = frag_parent_q;
  box_parent_half = frag_parent_half;
  // The box as drawn (grown by the blend radius where it blends into a parent) bounds the march;
  // the shapes are sized by the box itself.
  vec3 drawn_half = frag_half;
  box_half = frag_half - vec3(frag_parent_half.x < 0.0 ? 0.0 : preview.blend.x);
  vec3 ro = -f;
  vec3 ray_object = preview.eye.w > 0.5 ? obj_pos - preview.eye.xyz : preview.eye.xyz;
  float eye_distance = length(ray_object);
  // a fragment whose position rounds to the eye's (vertices far from the object's origin, the near
  // plane close: cut battery seed 948) has no ray: it draws nothing rather than a NaN
  if (!(eye_distance > 0.0)) {
    bm_drop(0.0);
    return;
  }
  mat3 frame = mat3(preview.frame);
  vec3 rd = normalize(bm_to_local(frame * (ray_object / eye_distance), x, y, z));

  // A fragment where the ray enters: an outer face (front-facing, or back-facing in a mirrored
  // object: preview.mode.y), or (whatever the winding) more of the box ahead than behind. A
  // fragment of the far side only marches when the eye is inside the box (from the eye,
  // bm_from_eye: an inside-out box's far side too).
  vec2 span = bm_box_span(ro, rd, drawn_half);
  float t_end = span.y;
  bool outer_face = gl_FrontFacing != (preview.mode.y == 1);
  bool from_eye = bm_from_eye(span, outer_face, preview.eye.w > 0.5, eye_distance);
  if (from_eye) {
    if (preview.eye.w < 0.5 || eye_distance > -span.x) {
      bm_drop(0.0);
      return;
    }
    ro -= rd * eye_distance;
    t_end = eye_distance;
  }

  // The ray in clip space, c0 + t c1 from the march's start: where it reaches a depth kept by the
  // pre-pass or the resolved passes, a march may stop (bm_depth_crossing), and at a hit, its depth.
  // From the face, the start's clip z and w are the rasteriser's own (gl_FragCoord), not obj_pos
  // through the matrix, a product that loses digits as the vertices lie far from the object's
  // origin (1,000 units out, the shade pass of the resolved passes then missed 9 of 24,695 pixels
  // whose hit the visibility pass had kept); x and y are never read.
  float face_w = 1.0 / gl_FragCoord.w;
  vec4 c0 = from_eye ? preview.object_to_clip * vec4(preview.eye.xyz, 1.0)
                     : vec4(0.0, 0.0, (2.0 * gl_FragCoord.z - 1.0) * face_w, face_w);
  vec4 c1 = preview.object_to_clip * vec4(ray_object / eye_distance, 0.0);
  // Hidden boxes: behind the occluders' depth nothing is visible (a march from the eye is only
  // bounded: its box's own entry is the eye). The pre-pass wrote each occluder's depth as the limit
  // to compare with (bm_occluder_limit); 1 where it drew none.
  float hidden_from = preview.occlusion.x > 0.5 ? texelFetch(occluder_depth, ivec2(gl_FragCoord.xy), 0).r : 1.0;
  if (hidden_from < 1.0) {
    if (!from_eye && gl_FragCoord.z > hidden_from) {
      bm_drop(0.0);
      return;
    }
    t_end = min(t_end, bm_depth_crossing(c0, c1, 2.0 * hidden_from - 1.0));
  }
#ifdef BM_RESOLVED
  // The nearest hit kept so far at this pixel (hit_min): the visibility pass needs no march past
  // it (the boxes are drawn about front to back, so most marches find one already kept); for the
  // shade pass it is the pixel's nearest hit, and only a box whose march ends there can have made
  // it: the box must reach that depth (its exit beyond it, less the margin), and the shape must
  // lie within the margin's distance plus the hit distance of the ray's point at that depth (its
  // map() is 1-Lipschitz: an exact distance or a bound), one map() instead of a march.
  uint winner = imageLoad(hit_min, ivec2(gl_FragCoord.xy)).x;
  if (winner < BM_NO_HIT) {
    float nearest = uintBitsToFloat(winner);
    float reach = bm_depth_crossing(c0, c1, 2.0 * (nearest - bm_shade_margin()) - 1.0);
    // a kept 1.0 stands for every hit at or past the far plane (clamped, as the plain draw's depth
    // is): no bound beyond it, nor a tap at it (issue 36, cut battery seeds 381 and 485: hits past
    // the far plane, t beyond the crossing of depth 1 + the margin, were never shaded)
    float beyond = nearest < 1.0 ? bm_depth_crossing(c0, c1, 2.0 * (nearest + bm_shade_margin()) - 1.0) : 1e30;
    bool hidden = !from_eye && gl_FragCoord.z > nearest + bm_shade_margin();
    int taps = 0;
    // (a march from the eye takes no test: its fragment is its box's far side, behind its hit;
    // the equality of its hit's depth with the kept one decides, as for every fragment)
    if (!hidden && !from_eye && preview.occlusion.w == 2.0) {
      // the box's exit nearer than that depth, compared as depths (the crossing, reach, inverts a
      // depth into a distance, which loses every digit where the near plane is far nearer than
      // the boxes: cut battery, depth-hostile seed 138, a winner's reach came out beyond its exit).
      // Along the ray the depth is monotonic while w keeps its sign, so every hit_depth below
      // (the face's depth or more) is at most the greater of the face's and the exit's, whatever
      // the rounding of the ray's direction; clamped to [0, 1] as every kept depth is (a box
      // wholly in front of the near plane whose face's fragment came out below 0, drawn by the
      // one-pass draw at depth 0, is kept at 0: three.js, cut battery seed 851)
      vec4 exit_clip = c0 + c1 * t_end;
      hidden = exit_clip.w > 0.0
        && clamp(max(gl_FragCoord.z, 0.5 + 0.5 * exit_clip.z / exit_clip.w), 0.0, 1.0) < nearest - bm_shade_margin();
      if (!hidden && beyond < 1e30) {
        float at = min(bm_depth_crossing(c0, c1, 2.0 * nearest - 1.0), beyond);
        taps = 1;
        hidden = map(ro + rd * at) > preview.march.x + beyond - (reach < 1e30 ? reach : 0.0);
      }
    }
    if (hidden) {
      bm_drop(float(taps));
      return;
    }
    t_end = min(t_end, beyond);
  }
  else if (preview.occlusion.w == 2.0) {
    bm_drop(0.0);
    return;
  }
#endif

  float t;
  float d;
  int steps = 1;
#ifdef BM_CLOSED_FORM
  // map() is a preset (formats/shader_sources.py defines BM_CLOSED_FORM as its bm_preset_hit):
  // its hit in closed form, no march and no normal taps; an eye inside the shape hits at once.
  vec4 closed = BM_CLOSED_FORM;
  if (from_eye && map(ro) <= 0.0) {
    closed = vec4(-rd, 0.0);
  }
  t = closed.w;
  d = 0.0;
  bool hit = t >= 0.0 && t <= min(t_end, preview.march.z);
  int normal_taps = 0;
#else
  // The quality knob: a pixel's size at the rasterised face, the box's size on screen from it.
  vec4 quality = bm_quality(preview.quality.x);
  vec3 row_y = vec3(preview.object_to_clip[0][1], preview.object_to_clip[1][1], preview.object_to_clip[2][1]);
  float footprint = bm_pixel_size(1.0 / gl_FragCoord.w, length(row_y), preview.quality.y);
  float box_pixels = 2.0 * bm_max3(box_half) / footprint;
  int max_steps = int(bm_step_limit(box_pixels, quality.y, preview.march.w));
  bool hit = box_pixels < quality.z
    ? bm_one_tap(ro, rd, min(t_end, preview.march.z), footprint, t, d)
    : bm_march(ro, rd, min(t_end, preview.march.z), max_steps, preview.march.x, preview.march.y,
               vec2(quality.x * footprint, quality.w), t, steps, d);
  int normal_taps = 3;
#endif
  vec3 local_hit = ro + rd * t;
  vec4 clip = c0 + c1 * t;
  float window_depth = clip.z / clip.w * 0.5 + 0.5;
  // The hit's depth (bm_hit_depth): a march from the eye writes its hit's own depth only in the
  // draw of the boxes holding the eye (occlusion.z 2, as the vertex stage picked them). A fragment
  // of another box that the test above still sends from the eye (its box's face a rounding from
  // the eye, vertices far from the origin) keeps its face's depth in every pass, as the one-pass
  // draw's declaration makes it: the resolved passes kept its hit at depth 0 where the one-pass
  // draw wrote its face's, and shaded nothing there (cut battery, depth-hostile seed 138). In
  // [0, 1]: a face the near plane clips may rasterise a hair in front of it (llvmpipe: window
  // depth -9e-6), and a negative float's bits sort after every other depth's as uint, so that hit
  // was never kept; a hit at or past the far plane is kept at 1.0, as the plain draw keeps it.
  float hit_depth = bm_hit_depth(window_depth, clip.w, gl_FragCoord.z, from_eye && preview.occlusion.z == 2.0);
  // (-1: a hit in front of the near plane, clipped)
  hit = hit && hit_depth >= 0.0;
#ifdef BM_RESOLVED
  // the visibility pass counts the march alone (no normal); the shade pass its march and, for the
  // one fragment it shades, the normal's taps
  bool shaded = hit && preview.occlusion.w == 2.0 && floatBitsToUint(hit_depth) == winner;
  if (hit && preview.occlusion.w == 1.0) {
    imageAtomicMin(hit_min, ivec2(gl_FragCoord.xy), floatBitsToUint(hit_depth));
  }
  if (preview.mode.x == 2) {
    frag_color = vec4(float(steps), float(steps + (shaded ? normal_taps : 0)), 1.0, 1.0);
    return;
  }
  if (!shaded) {
    discard;
  }
#else
  if (preview.mode.x == 2) {
    frag_color = vec4(float(steps), float(steps + (hit ? normal_taps : 0)), 1.0, 1.0);
    return;
  }
  if (!hit) {
    discard;
  }
#ifdef BM_EYE_BOXES
  gl_FragDepth = hit_depth;
#else
  // hit_depth, written as what the stage declares (depth_write GREATER): occlusion.z is not 2 here
  gl_FragDepth = max(window_depth, gl_FragCoord.z);
#endif
#endif

#ifdef BM_CLOSED_FORM
  vec3 n_local = closed.xyz;
#else
  vec3 n_local = bm_normal(local_hit, d, bm_normal_tap(box_half));
#endif
  vec3 n_object = transpose(frame) * bm_from_local(n_local, x, y, z);
  if (preview.mode.x == 1) {
    frag_color = vec4(n_object * 0.5 + 0.5, 1.0);
  }
  else {
    vec3 n_view = normalize(mat3(preview.normal_to_view) * n_object);
    vec3 base = preview.blend.y > 0.5 ? bm_material_colour(box_params.y) : preview.base_color.rgb;
    frag_color = vec4(bm_shade(n_view, base), preview.base_color.a);
  }
}
