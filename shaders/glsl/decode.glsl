// boxmarch decode: recover a fragment's box-local frame from the baked vertex data
// (docs/FORMAT.md). Mirrored by shaders/hlsl/boxmarch.hlsl.

// f = vector from the fragment to its submesh's origin, in box-local coordinates.
// color = the BoxOffset colour attribute (rgb = 0.5 + 0.5 * s * f, a = s).
vec3 GetFragToOrigin(vec4 color)
{
  return (color.rgb * 2.0 - 1.0) / color.a;
}

// q = the submesh's frame as a quaternion (x, y, z, w) mapping box-local to object space,
// from the two UV maps BoxQuatXY and BoxQuatZW.
vec4 GetRotation(vec2 quat_xy, vec2 quat_zw)
{
  return vec4(quat_xy, quat_zw);
}

// q v q* for a unit quaternion q; rotate_vector(v, quat_conjugate(q)) is the inverse rotation.
vec3 rotate_vector(vec3 v, vec4 q)
{
  return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v);
}

vec4 quat_conjugate(vec4 q)
{
  return vec4(-q.xyz, q.w);
}
