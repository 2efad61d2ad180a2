// The part of Unity's API that engines/unity/com.boxmarch.boxmarch/Runtime/Scripts calls (the
// Decode Vertex Vectors component), declared with Unity's names and signatures
// (docs.unity3d.com ScriptReference) and no behaviour: those scripts are compiled against this
// file alone with mono's mcs (tests/test_engine_unity_vectors.py), never run here. Kept apart from
// UnityApiStub.cs (the Editor postprocessor's), which is compiled without it.
using System;
using System.Collections.Generic;

namespace UnityEngine
{
    public class Object
    {
        public static implicit operator bool(Object exists) { return exists != null; }
    }

    public class Component : Object
    {
        public Transform transform { get { return null; } }
        public T GetComponent<T>() { return default(T); }
    }

    public class Behaviour : Component
    {
    }

    public class MonoBehaviour : Behaviour
    {
    }

    public class Transform : Component
    {
        public Matrix4x4 localToWorldMatrix { get { return default(Matrix4x4); } }
    }

    public struct Matrix4x4
    {
    }

    public struct Vector2
    {
        public float x;
        public float y;
    }

    public struct Vector3
    {
        public float x;
        public float y;
        public float z;
        public Vector3(float x, float y, float z) { this.x = x; this.y = y; this.z = z; }
        public static Vector3 operator +(Vector3 a, Vector3 b) { return default(Vector3); }
    }

    public struct Vector4
    {
        public float x;
        public float y;
        public float z;
        public float w;
    }

    public struct Color
    {
        public float r;
        public float g;
        public float b;
        public float a;
        public Color(float r, float g, float b, float a) { this.r = r; this.g = g; this.b = b; this.a = a; }
    }

    public static class Mathf
    {
        public static int Min(int a, int b) { return 0; }
    }

    public sealed class Mesh : Object
    {
        public int vertexCount { get { return 0; } }
        public Vector3[] vertices { get { return null; } }
        public Vector3[] normals { get { return null; } }
        public Vector4[] tangents { get { return null; } }
        public Color[] colors { get { return null; } }
        public void GetUVs(int channel, List<Vector2> uvs) { }
    }

    public sealed class MeshFilter : Component
    {
        public Mesh sharedMesh { get { return null; } }
    }

    public class Renderer : Component
    {
    }

    public class SkinnedMeshRenderer : Renderer
    {
        public Mesh sharedMesh { get { return null; } }
        public void BakeMesh(Mesh mesh) { }
    }

    public static class Gizmos
    {
        public static Color color { get; set; }
        public static Matrix4x4 matrix { get; set; }
        public static void DrawLine(Vector3 from, Vector3 to) { }
    }

    [AttributeUsage(AttributeTargets.Class)]
    public sealed class AddComponentMenu : Attribute
    {
        public AddComponentMenu(string menuName) { }
    }

    [AttributeUsage(AttributeTargets.Field)]
    public class PropertyAttribute : Attribute
    {
    }

    [AttributeUsage(AttributeTargets.Field)]
    public class TooltipAttribute : PropertyAttribute
    {
        public TooltipAttribute(string tooltip) { }
    }
}
