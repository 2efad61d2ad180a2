// Runs the package's AssetPostprocessors on model files the way Unity's import pipeline calls
// them (docs.unity3d.com, AssetPostprocessor): every non-abstract subclass, in GetPostprocessOrder
// order, is constructed, given the asset's project-relative assetPath and a ModelImporter, and its
// OnPreprocessModel message is invoked BY NAME through reflection (any accessibility, no
// arguments), as Unity sends messages; an exception it throws is logged, as Unity logs it. Built
// with the stub and the package's Editor sources into one executable
// (tests/engines/import_helpers.py):
//
//   mono boxmarch.exe Assets/a.fbx ...   (run in the project folder)
//     one line per asset: asset <TAB> set <TAB> property=value;... <TAB> logged <TAB> message|...
//   mono boxmarch.exe --constants
//     one line per public constant or static readonly field of the postprocessors: name <TAB> value
using System;
using System.Collections;
using System.Collections.Generic;
using System.Linq;
using System.Reflection;
using UnityEditor;

namespace BoxmarchTests
{
    public static class UnityImportHarness
    {
        const BindingFlags AnyInstance = BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic;

        static List<Type> Postprocessors(Assembly editor)
        {
            return editor.GetTypes()
                .Where(t => typeof(AssetPostprocessor).IsAssignableFrom(t) && !t.IsAbstract)
                .OrderBy(t => ((AssetPostprocessor)Activator.CreateInstance(t)).GetPostprocessOrder())
                .ToList();
        }

        static string Written(object value)
        {
            var list = value as IEnumerable;
            if (list != null && !(value is string))
                return "[" + string.Join(",", list.Cast<object>().Select(Written)) + "]";
            return value is string ? "\"" + value + "\"" : Convert.ToString(value, System.Globalization.CultureInfo.InvariantCulture);
        }

        static string Clean(string text)
        {
            return text.Replace('\t', ' ').Replace('\n', ' ').Replace('|', '/');
        }

        public static int Main(string[] args)
        {
            Assembly editor = Assembly.GetExecutingAssembly();
            if (args.Length == 1 && args[0] == "--constants")
            {
                foreach (Type type in Postprocessors(editor))
                    foreach (FieldInfo field in type.GetFields(BindingFlags.Public | BindingFlags.Static))
                        if (field.IsLiteral || field.IsInitOnly)
                            Console.WriteLine(field.Name + "\t" + Written(field.GetValue(null)));
                return 0;
            }
            foreach (string asset in args)
            {
                var importer = new ModelImporter { assetPath = asset };
                UnityEngine.Debug.Logged.Clear();
                foreach (Type type in Postprocessors(editor))
                {
                    var postprocessor = (AssetPostprocessor)Activator.CreateInstance(type);
                    postprocessor.assetPath = asset;
                    postprocessor.assetImporter = importer;
                    MethodInfo message = type.GetMethod("OnPreprocessModel", AnyInstance, null, Type.EmptyTypes, null);
                    try
                    {
                        if (message != null)
                            message.Invoke(postprocessor, null);
                    }
                    catch (TargetInvocationException thrown)  // Unity logs a message's exception
                    {
                        UnityEngine.Debug.Logged.Add("exception: " + thrown.InnerException.GetType().Name + ": " +
                                                     thrown.InnerException.Message);
                    }
                }
                string set = string.Join(";", importer.Recorded.Select(p => p.Key + "=" + p.Value));
                Console.WriteLine(asset + "\tset\t" + set + "\tlogged\t" +
                                  string.Join("|", UnityEngine.Debug.Logged.Select(Clean)));
            }
            return 0;
        }
    }
}
