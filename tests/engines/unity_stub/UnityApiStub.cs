// The part of Unity's API that engines/unity/com.boxmarch.boxmarch/Editor calls, declared with
// Unity's names and types (docs.unity3d.com ScriptReference). The package is compiled with it
// by mono's mcs and run under mono by UnityImportHarness.cs (tests/engines/import_helpers.py)
// and SidecarRefusals.cs (tests/test_engine_sidecars.py), never in Unity. What it does is
// modelled, and only as far as the tests need: ModelImporter records every property set on it
// (Recorded), in order; Debug.Log/LogError record their messages (Logged).
using System;
using System.Collections.Generic;

namespace UnityEngine
{
    public class Object
    {
    }

    public static class Debug
    {
        public static readonly List<string> Logged = new List<string>();

        public static void Log(object message) { Logged.Add("log: " + message); }
        public static void LogError(object message) { Logged.Add("error: " + message); }
        public static void LogError(object message, Object context) { LogError(message); }
    }
}

namespace UnityEditor
{
    public enum ModelImporterMeshCompression { Off = 0, Low = 1, Medium = 2, High = 3 }
    public enum ModelImporterNormals { Import = 0, Calculate = 1, None = 2 }
    public enum ModelImporterTangents { Import = 0, CalculateLegacy = 1, CalculateLegacyWithSplitTangents = 4, CalculateMikk = 3, None = 2 }

    public class AssetImporter : UnityEngine.Object
    {
        public string assetPath { get; internal set; }
    }

    public class ModelImporter : AssetImporter
    {
        // (property, value as C# writes it: true, ModelImporterMeshCompression.Off) per assignment.
        public readonly List<KeyValuePair<string, string>> Recorded = new List<KeyValuePair<string, string>>();

        bool readable;
        ModelImporterMeshCompression compression;
        ModelImporterNormals normals;
        ModelImporterTangents tangents;

        void Record(string property, object value)
        {
            string written = value is bool ? ((bool)value ? "true" : "false") : value.GetType().Name + "." + value;
            Recorded.Add(new KeyValuePair<string, string>(property, written));
        }

        public bool isReadable { get { return readable; } set { readable = value; Record("isReadable", value); } }
        public ModelImporterMeshCompression meshCompression
        {
            get { return compression; }
            set { compression = value; Record("meshCompression", value); }
        }
        public ModelImporterNormals importNormals
        {
            get { return normals; }
            set { normals = value; Record("importNormals", value); }
        }
        public ModelImporterTangents importTangents
        {
            get { return tangents; }
            set { tangents = value; Record("importTangents", value); }
        }
    }

    public class AssetPostprocessor
    {
        public string assetPath { get; internal set; }
        public AssetImporter assetImporter { get; internal set; }
        public virtual uint GetVersion() { return 0; }
        public virtual int GetPostprocessOrder() { return 0; }
    }
}
