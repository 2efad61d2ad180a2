// boxmarch: the import settings of a model exported by boxmarch's UNITY preset, set before Unity
// imports it. A model is boxmarch's when its sidecar NAME.boxmarch.json lies beside it
// (docs/FORMAT.md); the settings are those docs/ENGINES.md derives, and the sidecar records them
// under import_settings.settings.unity_model_importer:
//   Read/Write on: vertex compression (Player settings) leaves TexCoord2-7 float32 then;
//   Mesh Compression off: it quantizes UVs and colours;
//   Normals and Tangents: Import: the NORMAL_FRAME layout's box frame is the file's normal and
//   tangent, which Calculate would replace.
// A sidecar of another preset or version, or a layout Runtime/Shaders does not read, is refused
// with an error in the Console and the model keeps Unity's settings.
using System;
using System.IO;
using UnityEditor;
using UnityEngine;

namespace Boxmarch.Editor
{
    public class BoxmarchModelPostprocessor : AssetPostprocessor
    {
        public const int FormatVersion = 1;
        public const string Preset = "UNITY";
        public const string SidecarSuffix = ".boxmarch.json";
        public static readonly string[] LayoutsRead = { "UV_FRAME", "NORMAL_FRAME", "CLASSIC" };

        // The keys every boxmarch helper reads first (docs/FORMAT.md).
        [Serializable]
        public class Sidecar
        {
            public int format_version;
            public string preset;
            public string layout;
            public bool skinned;
            public int box_count;
        }

        // Raised when the settings below change, so that Unity imports the models again.
        public override uint GetVersion()
        {
            return 1;
        }

        public static string SidecarPath(string modelPath)
        {
            return Path.ChangeExtension(modelPath, null) + SidecarSuffix;
        }

        // Why the sidecar's model is not set up by this package, or null when it is.
        public static string Refusal(Sidecar sidecar)
        {
            if (sidecar == null)
                return "the sidecar is not a boxmarch sidecar";
            if (sidecar.format_version != FormatVersion)
                return "the sidecar has format version " + sidecar.format_version + "; this package reads version " + FormatVersion;
            if (sidecar.preset != Preset)
                return "the model was exported with the " + sidecar.preset + " preset, whose axes are not Unity's: export with the UNITY preset";
            if (Array.IndexOf(LayoutsRead, sidecar.layout) < 0)
                return "layout " + sidecar.layout + " is not read by the boxmarch material (it reads " + string.Join(", ", LayoutsRead) + ")";
            return null;
        }

        static Sidecar ReadSidecar(string path)
        {
            try
            {
                return JsonUtility.FromJson<Sidecar>(File.ReadAllText(path));
            }
            catch (ArgumentException)  // JsonUtility's answer to text that is not JSON
            {
                return null;
            }
        }

        void OnPreprocessModel()
        {
            string path = SidecarPath(assetPath);
            if (!File.Exists(path))
                return;  // not a boxmarch export
            string refusal = Refusal(ReadSidecar(path));
            if (refusal != null)
            {
                Debug.LogError("boxmarch: " + assetPath + ": " + refusal + " (" + path + ")");
                return;
            }
            ModelImporter importer = assetImporter as ModelImporter;
            if (importer == null)
                return;
            importer.isReadable = true;
            importer.meshCompression = ModelImporterMeshCompression.Off;
            importer.importNormals = ModelImporterNormals.Import;
            importer.importTangents = ModelImporterTangents.Import;
        }
    }
}
