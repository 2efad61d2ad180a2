// COPIED by shaders/generate.py from shaders/hlsl/boxmarch_raymarch.hlsl: edit that file, not this copy
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
// boxmarch_raymarch.hlsl: the box-local sphere tracer. Include boxmarch.hlsl, define
// `float map(float3 p)` (box-local, may use box_half), then include this file. The march is
// generated from shaders/glsl/raymarch.glsl (boxmarch_march.hlsl); bm_raymarch is the fragment
// logic of shaders/glsl/preview.frag.glsl in engine terms.
#ifndef BOXMARCH_RAYMARCH_INCLUDED
#define BOXMARCH_RAYMARCH_INCLUDED

// Optional change of object frame, engine object space from Blender object space (an orthonormal
// 3x3, e.g. the axis conversion of an FBX import); identity by default.
#ifndef BOXMARCH_FRAME
#define BOXMARCH_FRAME float3x3(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
#endif

#include "boxmarch_march.hlsl"

// The largest half-extent, from the offset scale alone (s = 1 / largest |f| over the submesh;
// for BOUNDS origins that is the box's largest half-extent): a cube that holds the box, for when
// the real half-extents are not available to the engine shader.
float3 bm_cube_half_extents(float4 color)
{
  float h = 1.0 / color.a;
  return float3(h, h, h);
}

struct bm_hit {
  bool hit;
  float3 obj_pos;     // engine object space
  float3 obj_normal;  // engine object space, unit
  int steps;
};

// The whole per-fragment raymarch (as the Blender preview does it), in any layout:
// obj_pos = the fragment's interpolated object-space position, obj_camera = the camera in object
// space, f = the decoded box-local vector to the box origin, x, y, z = the box's unit axes in
// engine object space, half_extents = the box's half-extents, front_facing = SV_IsFrontFace;
// max_steps up to 512 (bm_march's bound); quality = the quality knob (bm_quality; 1 = the full
// march) and footprint = one pixel's size in object units at the fragment (bm_pixel_size).
bm_hit bm_raymarch_in_frame(float3 obj_pos, float3 obj_camera, float3 f, float3 x, float3 y, float3 z,
                            float3 half_extents, bool front_facing, int max_steps, float epsilon,
                            float relaxation, float max_distance, float quality, float footprint)
{
  bm_hit o;
  o.hit = false;
  o.obj_pos = obj_pos;
  o.obj_normal = float3(0.0, 0.0, 1.0);
  o.steps = 0;
  box_half = half_extents;
  float3 ro = -f;
  float3 ray_object = obj_pos - obj_camera;
  float eye_distance = length(ray_object);
  // a fragment whose position rounds to the camera's (vertices far from the object's origin, the
  // near plane close) has no ray: it draws nothing rather than a NaN
  if (!(eye_distance > 0.0)) return o;
  float3 rd = normalize(bm_to_local(ray_object / eye_distance, x, y, z));
  float2 span = bm_box_span(ro, rd, box_half);
  float t_end = span.y;
  // entry: front-facing, or (whatever the winding) more box ahead than behind; the far side
  // only marches when the camera is inside the box (bm_from_eye: an inside-out box's far side
  // too; the camera taken as a point, as the test below always took it)
  bool from_eye = bm_from_eye(span, front_facing, true, eye_distance);
  if (from_eye) {
    if (eye_distance > -span.x) return o;
    ro -= rd * eye_distance;
    t_end = eye_distance;
  }
  float t;
  int steps = 1;
#ifdef BM_CLOSED_FORM
  // map() is a preset: its hit in closed form (boxmarch_march.hlsl bm_preset_hit), no march and no
  // normal taps; an eye inside the shape hits at once. Define BM_CLOSED_FORM before including this
  // file as the preset's hit, e.g. bm_preset_hit(6.0, ro, rd, box_half) for sdf_preset_link.
  float4 closed = BM_CLOSED_FORM;
  if (from_eye && map(ro) <= 0.0) closed = float4(-rd, 0.0);
  t = closed.w;
  o.hit = t >= 0.0 && t <= min(t_end, max_distance);
#else
  // the quality knob, as the preview applies it (shaders/glsl/preview.frag.glsl)
  float4 knob = bm_quality(quality);
  float box_pixels = 2.0 * bm_max3(box_half) / footprint;
  float d;
  if (box_pixels < knob.z)
    o.hit = bm_one_tap(ro, rd, min(t_end, max_distance), footprint, t, d);
  else
    o.hit = bm_march(ro, rd, min(t_end, max_distance), int(bm_step_limit(box_pixels, knob.y, float(max_steps))),
                     epsilon, relaxation, float2(knob.x * footprint, knob.w), t, steps, d);
#endif
  o.steps = steps;
  if (!o.hit) return o;
  float3 local_hit = ro + rd * t;
  o.obj_pos = obj_pos + bm_from_local(local_hit + f, x, y, z);
#ifdef BM_CLOSED_FORM
  o.obj_normal = bm_from_local(closed.xyz, x, y, z);
#else
  o.obj_normal = bm_from_local(bm_normal(local_hit, d, bm_normal_tap(box_half)), x, y, z);
#endif
  return o;
}

// bm_raymarch_in_frame for the CLASSIC layout: color = the BoxOffset colour, quat = the
// decoded quaternion (Blender's object frame, turned into the engine's by BOXMARCH_FRAME).
bm_hit bm_raymarch(float3 obj_pos, float3 obj_camera, float4 color, float4 quat, float3 half_extents,
                   bool front_facing, int max_steps, float epsilon, float relaxation, float max_distance,
                   float quality, float footprint)
{
  float4 q = normalize(quat);
  return bm_raymarch_in_frame(obj_pos, obj_camera, bm_offset_from_color(color),
                              mul(BOXMARCH_FRAME, bm_rotate_vector(float3(1.0, 0.0, 0.0), q)),
                              mul(BOXMARCH_FRAME, bm_rotate_vector(float3(0.0, 1.0, 0.0), q)),
                              mul(BOXMARCH_FRAME, bm_rotate_vector(float3(0.0, 0.0, 1.0), q)),
                              half_extents, front_facing, max_steps, epsilon, relaxation, max_distance,
                              quality, footprint);
}

#endif  // BOXMARCH_RAYMARCH_INCLUDED
