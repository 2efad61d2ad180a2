// boxmarch viewport preview, vertex stage. Interface (declared by the create-info in
// addon/boxmarch/preview/shader.py): in pos, offset_color, quat, half_extents; out obj_pos,
// frag_offset, frag_quat, frag_half; uniform block preview
// (BoxmarchPreview, see preview.frag.glsl).
void main()
{
  obj_pos = pos;
  frag_offset = offset_color;
  frag_quat = quat;
  frag_half = half_extents;
  gl_Position = preview.object_to_clip * vec4(pos, 1.0);
}
