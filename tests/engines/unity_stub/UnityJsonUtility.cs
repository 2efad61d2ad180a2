// Unity's JsonUtility.FromJson for the stub of tests/engines/unity_stub/UnityApiStub.cs, modelled
// only as far as the tests need: it fills the public fields of T from a JSON object and throws
// ArgumentException for text that is not JSON (as Unity documents); a value whose JSON type does
// not match its field is not modelled (NotSupportedException), so no test relies on a guess of
// what Unity does with it.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Reflection;
using System.Text;

namespace UnityEngine
{
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
