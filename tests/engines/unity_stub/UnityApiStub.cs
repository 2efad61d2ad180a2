// The part of Unity's API that engines/unity/com.boxmarch.boxmarch/Editor calls, declared with
// Unity's names and types (docs.unity3d.com ScriptReference). The package is compiled against it
// with mono's mcs and run under mono by UnityImportHarness.cs (tests/engines/import_helpers.py),
// never in Unity. What it does is modelled, and only as far as the tests need:
//   ModelImporter records every property set on it (Recorded), in order;
//   Debug.Log/LogError record their messages (Logged);
//   JsonUtility.FromJson fills the public fields of T from a JSON object and throws
//   ArgumentException for text that is not JSON (as Unity documents); a value whose JSON type
//   does not match its field is not modelled (NotSupportedException), so no test relies on a
//   guess of what Unity does with it.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Reflection;
using System.Text;

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

    public static class JsonUtility
    {
        public static T FromJson<T>(string json)
        {
            var reader = new JsonText(json);
            object value = reader.ReadDocument();
            var fields = value as Dictionary<string, object>;
            if (fields == null)
                throw new ArgumentException("JSON must represent an object type.");
            var result = Activator.CreateInstance<T>();
            foreach (FieldInfo field in typeof(T).GetFields(BindingFlags.Public | BindingFlags.Instance))
            {
                object given;
                if (fields.TryGetValue(field.Name, out given))
                    field.SetValue(result, JsonText.Convert(given, field.FieldType, field.Name));
            }
            return result;
        }
    }

    // A JSON reader (RFC 8259) for the stub's FromJson: objects as Dictionary<string, object>,
    // arrays as List<object>, numbers as double.
    class JsonText
    {
        readonly string text;
        int at;

        public JsonText(string text)
        {
            if (text == null)
                throw new ArgumentException("JSON parse error: no text.");
            this.text = text;
        }

        public object ReadDocument()
        {
            object value = ReadValue(0);
            SkipSpace();
            if (at != text.Length)
                Fail("text after the value");
            return value;
        }

        public static object Convert(object given, Type type, string name)
        {
            if (type == typeof(string) && (given == null || given is string))
                return given;
            if (type == typeof(bool) && given is bool)
                return given;
            if ((type == typeof(int) || type == typeof(float) || type == typeof(double)) && given is double)
            {
                double number = (double)given;
                if (type != typeof(int))
                    return System.Convert.ChangeType(number, type, CultureInfo.InvariantCulture);
                if (number == Math.Floor(number) && Math.Abs(number) <= int.MaxValue)
                    return (int)number;
            }
            throw new NotSupportedException("stub of JsonUtility: field " + name + " given " + (given ?? "null") +
                                            " is not modelled");
        }

        void Fail(string what)
        {
            throw new ArgumentException("JSON parse error: " + what + " at character " + at + ".");
        }

        void SkipSpace()
        {
            while (at < text.Length && (text[at] == ' ' || text[at] == '\t' || text[at] == '\n' || text[at] == '\r'))
                ++at;
        }

        bool Take(string word)
        {
            if (string.CompareOrdinal(text, at, word, 0, word.Length) != 0)
                return false;
            at += word.Length;
            return true;
        }

        object ReadValue(int depth)
        {
            if (depth > 256)
                Fail("nesting deeper than 256");
            SkipSpace();
            if (at >= text.Length)
                Fail("end of text");
            char c = text[at];
            if (c == '{')
                return ReadObject(depth);
            if (c == '[')
                return ReadArray(depth);
            if (c == '"')
                return ReadString();
            if (Take("true"))
                return true;
            if (Take("false"))
                return false;
            if (Take("null"))
                return null;
            return ReadNumber();
        }

        Dictionary<string, object> ReadObject(int depth)
        {
            var found = new Dictionary<string, object>();
            ++at;
            SkipSpace();
            if (at < text.Length && text[at] == '}')
            {
                ++at;
                return found;
            }
            while (true)
            {
                SkipSpace();
                if (at >= text.Length || text[at] != '"')
                    Fail("a key expected");
                string key = ReadString();
                SkipSpace();
                if (at >= text.Length || text[at] != ':')
                    Fail("':' expected");
                ++at;
                found[key] = ReadValue(depth + 1);
                SkipSpace();
                if (at < text.Length && text[at] == ',')
                {
                    ++at;
                    continue;
                }
                if (at < text.Length && text[at] == '}')
                {
                    ++at;
                    return found;
                }
                Fail("',' or '}' expected");
            }
        }

        List<object> ReadArray(int depth)
        {
            var items = new List<object>();
            ++at;
            SkipSpace();
            if (at < text.Length && text[at] == ']')
            {
                ++at;
                return items;
            }
            while (true)
            {
                items.Add(ReadValue(depth + 1));
                SkipSpace();
                if (at < text.Length && text[at] == ',')
                {
                    ++at;
                    continue;
                }
                if (at < text.Length && text[at] == ']')
                {
                    ++at;
                    return items;
                }
                Fail("',' or ']' expected");
            }
        }

        string ReadString()
        {
            var built = new StringBuilder();
            ++at;
            while (at < text.Length && text[at] != '"')
            {
                char c = text[at++];
                if (c < ' ')
                    Fail("a control character in a string");
                if (c != '\\')
                {
                    built.Append(c);
                    continue;
                }
                if (at >= text.Length)
                    break;
                char e = text[at++];
                int simple = "\"\\/bfnrt".IndexOf(e);
                if (simple >= 0)
                    built.Append("\"\\/\b\f\n\r\t"[simple]);
                else if (e == 'u' && at + 4 <= text.Length)
                {
                    built.Append((char)int.Parse(text.Substring(at, 4), NumberStyles.HexNumber));
                    at += 4;
                }
                else
                    Fail("a bad escape");
            }
            if (at >= text.Length)
                Fail("an unterminated string");
            ++at;
            return built.ToString();
        }

        double ReadNumber()
        {
            int start = at;
            while (at < text.Length && "+-0123456789.eE".IndexOf(text[at]) >= 0)
                ++at;
            double number = 0.0;
            if (at == start || !double.TryParse(text.Substring(start, at - start), NumberStyles.Float,
                                                CultureInfo.InvariantCulture, out number))
                Fail("a value expected");
            return number;
        }
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
