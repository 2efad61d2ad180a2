// The decode of the layouts the UNITY export preset writes (docs/ENGINES.md, "What every layout
// carries"), over plain float arrays so that it runs outside Unity too (tests/test_engine_unity_vectors.py
// runs it under mono on a real export). Everything is in the mesh's object frame as Unity imports
// it: the preset writes the box data already converted into Unity's left-handed frame.
namespace Boxmarch
{
    // The layouts of the UNITY preset, as the export report and the sidecar name them.
    public enum BoxmarchLayout
    {
        UV_FRAME = 0,
        NORMAL_FRAME = 1,
        CLASSIC = 2,
    }

    public static class BoxmarchDecode
    {
        // For every vertex i of a mesh, from its channels as Unity's Mesh hands them (uv1, uv2, uv3:
        // TexCoord 1..3 as x, y pairs; colors: r, g, b, a; normals: x, y, z; tangents: x, y, z, w;
        // arrays a layout does not read may be null):
        //   raw[3i..3i+2]       = f, the vector from the vertex to its box's origin in box-local
        //                         coordinates, as stored (the design's light-blue vectors);
        //   corrected[3i..3i+2] = f turned into the mesh's object frame by the box's frame (the
        //                         orange vectors): vertex + corrected = the box's origin, so the
        //                         corrected vectors of a box meet at one point.
        // UV_FRAME:     q = (uv1, uv2), f = (uv3, uv4.x)       corrected = q f q*
        // NORMAL_FRAME: f = (uv1, uv2.x), axes x = tangent.xyz, z = normal,
        //               y = cross(z, x) * tangent.w            corrected = x f.x + y f.y + z f.z
        // CLASSIC:      q = (uv1, uv2), f = (rgb * 2 - 1) / a  corrected = q f q*
        // uv4 is read by UV_FRAME only.
        public static void DecodeMesh(BoxmarchLayout layout, int vertexCount, float[] uv1, float[] uv2, float[] uv3,
                                      float[] uv4, float[] colors, float[] normals, float[] tangents, float[] raw,
                                      float[] corrected)
        {
            for (int i = 0; i < vertexCount; i++)
            {
                float fx, fy, fz;
                if (layout == BoxmarchLayout.UV_FRAME)
                {
                    fx = uv3[2 * i];
                    fy = uv3[2 * i + 1];
                    fz = uv4[2 * i];
                }
                else if (layout == BoxmarchLayout.NORMAL_FRAME)
                {
                    fx = uv1[2 * i];
                    fy = uv1[2 * i + 1];
                    fz = uv2[2 * i];
                }
                else
                {
                    float a = colors[4 * i + 3];
                    fx = (colors[4 * i] * 2f - 1f) / a;
                    fy = (colors[4 * i + 1] * 2f - 1f) / a;
                    fz = (colors[4 * i + 2] * 2f - 1f) / a;
                }
                raw[3 * i] = fx;
                raw[3 * i + 1] = fy;
                raw[3 * i + 2] = fz;
                if (layout == BoxmarchLayout.NORMAL_FRAME)
                    FromFrame(fx, fy, fz, normals, tangents, i, corrected);
                else
                    RotateVector(fx, fy, fz, uv1[2 * i], uv1[2 * i + 1], uv2[2 * i], uv2[2 * i + 1], corrected, i);
            }
        }

        // q v q* for the unit quaternion q = (x, y, z, w), as the shaders' bm_rotate_vector:
        // v + 2 cross(q.xyz, cross(q.xyz, v) + q.w v), written into output[3i..3i+2].
        static void RotateVector(float vx, float vy, float vz, float qx, float qy, float qz, float qw, float[] output,
                                 int i)
        {
            float cx = qy * vz - qz * vy + qw * vx;
            float cy = qz * vx - qx * vz + qw * vy;
            float cz = qx * vy - qy * vx + qw * vz;
            output[3 * i] = vx + 2f * (qy * cz - qz * cy);
            output[3 * i + 1] = vy + 2f * (qz * cx - qx * cz);
            output[3 * i + 2] = vz + 2f * (qx * cy - qy * cx);
        }

        // x f.x + y f.y + z f.z for the frame of vertex i: x = tangent.xyz, z = normal, y = cross(z, x)
        // * tangent.w (the shaders' bm_axis_y and bm_from_local).
        static void FromFrame(float fx, float fy, float fz, float[] normals, float[] tangents, int i, float[] output)
        {
            float zx = normals[3 * i], zy = normals[3 * i + 1], zz = normals[3 * i + 2];
            float xx = tangents[4 * i], xy = tangents[4 * i + 1], xz = tangents[4 * i + 2], w = tangents[4 * i + 3];
            float yx = (zy * xz - zz * xy) * w, yy = (zz * xx - zx * xz) * w, yz = (zx * xy - zy * xx) * w;
            output[3 * i] = xx * fx + yx * fy + zx * fz;
            output[3 * i + 1] = xy * fx + yy * fy + zy * fz;
            output[3 * i + 2] = xz * fx + yz * fy + zz * fz;
        }
    }
}
