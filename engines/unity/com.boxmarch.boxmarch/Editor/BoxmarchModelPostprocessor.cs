// boxmarch: the import settings of a model exported by boxmarch's UNITY preset, set before Unity
// imports it. A model is boxmarch's when its sidecar NAME.boxmarch.json lies beside it
// (docs/FORMAT.md); the settings are those docs/ENGINES.md derives, and the sidecar records them
// under import_settings.settings.unity_model_importer:
//   Read/Write on: vertex compression (Player settings) leaves TexCoord2-7 float32 then;
//   Mesh Compression off: it quantizes UVs and colours;
//   Normals and Tangents: Import: the NORMAL_FRAME layout's box frame is the file's normal and
//   tangent, which Calculate would replace.
// A sidecar of another preset or version, a layout Runtime/Shaders does not read, or one that is
// not a sidecar (BoxmarchSidecar.cs) is refused with one error naming it in the Console, and the
// model keeps Unity's settings.
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

        // Raised when the settings below change, so that Unity imports the models again.
        public override uint GetVersion()
        {
            return 1;
        }

        public static string SidecarPath(string modelPath)
        {
            return Path.ChangeExtension(modelPath, null) + SidecarSuffix;
        }

        // Why the model of the sidecar at sidecarPath is not set up by this package, as one line
        // naming the sidecar, or null when it is (BoxmarchSidecar: the checks of every helper).
        public static string Refusal(string sidecarPath)
        {
            return BoxmarchSidecar.Refusal(sidecarPath, FormatVersion, Preset, LayoutsRead);
        }

        void OnPreprocessModel()
        {
            string path = SidecarPath(assetPath);
            if (!File.Exists(path))
                return;  // not a boxmarch export
            string refusal = Refusal(path);
            if (refusal != null)
            {
                Debug.LogError(refusal);
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
