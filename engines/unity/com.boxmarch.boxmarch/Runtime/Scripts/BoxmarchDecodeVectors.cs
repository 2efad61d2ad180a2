// The design's "Decode vertex vectors" tool: attach it to a GameObject holding a mesh exported
// with the UNITY preset and select the object. From every vertex the Scene view draws the raw
// baked vector f (light blue: box-local numbers drawn as if they were object-space) and the
// corrected one, f turned by the box's frame (orange). The orange vectors of each box meet at
// the box's origin; where they do not, the import changed the data (docs/UNITY.md). A skinned
// mesh is drawn as posed (its NORMAL_FRAME frame turns with the bones). Compiled against a stub
// of the Unity API it calls (tests/test_engine_unity_vectors.py), not run in Unity.
using System.Collections.Generic;
using UnityEngine;

namespace Boxmarch
{
    [AddComponentMenu("Boxmarch/Decode Vertex Vectors")]
    public class BoxmarchDecodeVectors : MonoBehaviour
    {
        [Tooltip("The layout the export report and the sidecar name (UV_FRAME by default, NORMAL_FRAME when skinned)")]
        public BoxmarchLayout layout = BoxmarchLayout.UV_FRAME;
        public bool showRaw = true;
        public bool showCorrected = true;
        public Color rawColor = new Color(0.55f, 0.8f, 1f, 1f);
        public Color correctedColor = new Color(1f, 0.55f, 0.1f, 1f);
        [Tooltip("Vertices drawn at most (the first ones), to keep the Scene view responsive")]
        public int maxVertices = 20000;

        Mesh posed;

        void OnDrawGizmosSelected()
        {
            Mesh mesh = CurrentMesh();
            if (mesh == null)
                return;
            Vector3[] vertices = mesh.vertices;
            int count = Mathf.Min(vertices.Length, maxVertices);
            float[] raw = new float[3 * vertices.Length], corrected = new float[3 * vertices.Length];
            BoxmarchDecode.DecodeMesh(layout, vertices.Length, Uvs(mesh, 1), Uvs(mesh, 2), Uvs(mesh, 3), Uvs(mesh, 4),
                                      Colors(mesh), Normals(mesh), Tangents(mesh), raw, corrected);
            Gizmos.matrix = transform.localToWorldMatrix;
            for (int i = 0; i < count; i++)
            {
                Vector3 v = vertices[i];
                if (showRaw)
                {
                    Gizmos.color = rawColor;
                    Gizmos.DrawLine(v, v + new Vector3(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]));
                }
                if (showCorrected)
                {
                    Gizmos.color = correctedColor;
                    Gizmos.DrawLine(v, v + new Vector3(corrected[3 * i], corrected[3 * i + 1], corrected[3 * i + 2]));
                }
            }
        }

        // The mesh as drawn now: a skinned mesh baked in its current pose, else the MeshFilter's.
        Mesh CurrentMesh()
        {
            SkinnedMeshRenderer skinned = GetComponent<SkinnedMeshRenderer>();
            if (skinned != null && skinned.sharedMesh != null)
            {
                if (posed == null)
                    posed = new Mesh();
                skinned.BakeMesh(posed);
                return posed;
            }
            MeshFilter filter = GetComponent<MeshFilter>();
            return filter != null ? filter.sharedMesh : null;
        }

        static float[] Uvs(Mesh mesh, int channel)
        {
            List<Vector2> uvs = new List<Vector2>();
            mesh.GetUVs(channel, uvs);
            if (uvs.Count != mesh.vertexCount)
                return new float[2 * mesh.vertexCount];
            float[] flat = new float[2 * uvs.Count];
            for (int i = 0; i < uvs.Count; i++)
            {
                flat[2 * i] = uvs[i].x;
                flat[2 * i + 1] = uvs[i].y;
            }
            return flat;
        }

        static float[] Colors(Mesh mesh)
        {
            Color[] colors = mesh.colors;
            float[] flat = new float[4 * mesh.vertexCount];
            for (int i = 0; i < colors.Length && i < mesh.vertexCount; i++)
            {
                flat[4 * i] = colors[i].r;
                flat[4 * i + 1] = colors[i].g;
                flat[4 * i + 2] = colors[i].b;
                flat[4 * i + 3] = colors[i].a;
            }
            return flat;
        }

        static float[] Normals(Mesh mesh)
        {
            Vector3[] normals = mesh.normals;
            float[] flat = new float[3 * mesh.vertexCount];
            for (int i = 0; i < normals.Length && i < mesh.vertexCount; i++)
            {
                flat[3 * i] = normals[i].x;
                flat[3 * i + 1] = normals[i].y;
                flat[3 * i + 2] = normals[i].z;
            }
            return flat;
        }

        static float[] Tangents(Mesh mesh)
        {
            Vector4[] tangents = mesh.tangents;
            float[] flat = new float[4 * mesh.vertexCount];
            for (int i = 0; i < tangents.Length && i < mesh.vertexCount; i++)
            {
                flat[4 * i] = tangents[i].x;
                flat[4 * i + 1] = tangents[i].y;
                flat[4 * i + 2] = tangents[i].z;
                flat[4 * i + 3] = tangents[i].w;
            }
            return flat;
        }
    }
}
