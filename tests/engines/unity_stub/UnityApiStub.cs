// The part of Unity's API that engines/unity/com.boxmarch.boxmarch/Editor calls, declared with
// Unity's names and types (docs.unity3d.com ScriptReference) and no behaviour: the package is
// compiled against it with mono's mcs (tests/test_engine_import_settings.py), never run here.
using System;

namespace UnityEngine
{
    public class Object
    {
    }

    public static class Debug
    {
        public static void Log(object message) { }
        public static void LogError(object message) { }
        public static void LogError(object message, Object context) { }
    }
}

namespace UnityEditor
{
    public enum ModelImporterMeshCompression { Off = 0, Low = 1, Medium = 2, High = 3 }
    public enum ModelImporterNormals { Import = 0, Calculate = 1, None = 2 }
    public enum ModelImporterTangents { Import = 0, CalculateLegacy = 1, CalculateLegacyWithSplitTangents = 4, CalculateMikk = 3, None = 2 }

    public class AssetImporter : UnityEngine.Object
    {
        public string assetPath { get { return null; } }
    }

    public class ModelImporter : AssetImporter
    {
        public bool isReadable { get; set; }
        public ModelImporterMeshCompression meshCompression { get; set; }
        public ModelImporterNormals importNormals { get; set; }
        public ModelImporterTangents importTangents { get; set; }
    }

    public class AssetPostprocessor
    {
        public string assetPath { get { return null; } }
        public AssetImporter assetImporter { get { return null; } }
        public virtual uint GetVersion() { return 0; }
    }
}
