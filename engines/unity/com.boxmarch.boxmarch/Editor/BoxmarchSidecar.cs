// boxmarch: a sidecar NAME.boxmarch.json read as every boxmarch helper reads it (docs/FORMAT.md,
// "How a helper reads the sidecar"): at most MaxBytes, UTF-8, brackets nested at most MaxDepth
// deep (counted before anything is parsed), strict JSON (RFC 8259: no NaN, no comments, nothing
// after the value), an object whose format_version, preset, layout, skinned and box_count have the
// schema's types and values the helper reads. Unity's JsonUtility is not used: it reads into typed
// fields (an int format_version), where the type the file gave a value is no longer seen.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Text;

namespace Boxmarch.Editor
{
    public static class BoxmarchSidecar
    {
        public const int MaxBytes = 1 << 24;
        public const int MaxDepth = 32;

        // Why the sidecar at path does not describe a model that the helper of preset reads in one
        // of layoutsRead, as one line naming the file ("boxmarch: PATH: why"), or null when it does.
        public static string Refusal(string path, int formatVersion, string preset, string[] layoutsRead)
        {
            string why = FileRefusal(path, formatVersion, preset, layoutsRead);
            return why == null ? null : "boxmarch: " + path + ": " + OneLine(why);
        }

        static string FileRefusal(string path, int formatVersion, string preset, string[] layoutsRead)
        {
            byte[] data;
            try
            {
                if (new FileInfo(path).Length > MaxBytes)
                    return "larger than " + MaxBytes + " bytes, not a boxmarch sidecar";
                data = File.ReadAllBytes(path);
            }
            catch (Exception e) when (e is IOException || e is UnauthorizedAccessException)
            {
                return "cannot be read (" + e.Message + ")";
            }
            string text;
            // A byte order mark is no part of the JSON text: one is skipped (docs/FORMAT.md).
            int start = data.Length >= 3 && data[0] == 0xEF && data[1] == 0xBB && data[2] == 0xBF ? 3 : 0;
            try
            {
                text = new UTF8Encoding(false, true).GetString(data, start, data.Length - start);
            }
            catch (DecoderFallbackException)
            {
                return "not UTF-8 text";
            }
            if (Nesting(data) > MaxDepth)
                return "brackets nested more than " + MaxDepth + " deep";
            object sidecar;
            try
            {
                sidecar = new Parser(text).Document();
            }
            catch (FormatException e)
            {
                return "not JSON (" + e.Message + ")";
            }
            return ValueRefusal(sidecar as Dictionary<string, object>, formatVersion, preset, layoutsRead);
        }

        // The checks on the parsed sidecar, in the order every helper makes them.
        static string ValueRefusal(Dictionary<string, object> sidecar, int formatVersion, string preset, string[] layoutsRead)
        {
            if (sidecar == null)
                return "not a JSON object";
            object value;
            sidecar.TryGetValue("format_version", out value);
            if (!(value is double) || (double)value != formatVersion)
                return "format_version must be " + formatVersion + " (the format this package reads), not " + Shown(sidecar, "format_version");
            sidecar.TryGetValue("preset", out value);
            if (!(value is string) || (string)value != preset)
                return "preset must be \"" + preset + "\", not " + Shown(sidecar, "preset") + ": export with the " + preset + " preset, whose axes are Unity's";
            sidecar.TryGetValue("layout", out value);
            if (!(value is string) || Array.IndexOf(layoutsRead, (string)value) < 0)
                return "layout must be one of " + string.Join(", ", layoutsRead) + " (what the boxmarch material reads), not " + Shown(sidecar, "layout");
            sidecar.TryGetValue("skinned", out value);
            if (!(value is bool))
                return "skinned must be true or false, not " + Shown(sidecar, "skinned");
            sidecar.TryGetValue("box_count", out value);
            if (!(value is double) || !((double)value >= 0 && (double)value <= int.MaxValue) || (double)value != Math.Floor((double)value))
                return "box_count must be a whole number from 0 to 2147483647, not " + Shown(sidecar, "box_count");
            return null;
        }

        // why, on one line: each control character and line or paragraph separator (what a JSON
        // string may hold) written as its JSON escape.
        static string OneLine(string why)
        {
            var result = new StringBuilder();
            foreach (char c in why)
            {
                if (c < 0x20 || (c >= 0x7F && c <= 0x9F) || c == '\u2028' || c == '\u2029')
                    result.Append("\\u").Append(((int)c).ToString("x4"));
                else
                    result.Append(c);
            }
            return result.ToString();
        }

        // The value at key as JSON (a string cut to 40 characters, arrays and objects named; a
        // number beyond a double's range, 1e400 parsed as an infinity, in words), or "missing".
        static string Shown(Dictionary<string, object> sidecar, string key)
        {
            object value;
            if (!sidecar.TryGetValue(key, out value))
                return "missing";
            if (value == null)
                return "null";
            if (value is bool)
                return (bool)value ? "true" : "false";
            if (value is double && double.IsInfinity((double)value))
                return "a number beyond the range of a double";
            if (value is double)
                return ((double)value).ToString("R", CultureInfo.InvariantCulture);
            if (value is string)
                return ((string)value).Length <= 38 ? "\"" + value + "\"" : "\"" + ((string)value).Substring(0, 39) + "...";
            return value is List<object> ? "an array" : "an object";
        }

        // The deepest nesting of brackets in JSON text (UTF-8 bytes), strings skipped: known
        // before a parser recurses into them.
        static int Nesting(byte[] data)
        {
            int depth = 0, deepest = 0;
            bool inString = false, escaped = false;
            foreach (byte c in data)
            {
                if (inString)
                {
                    if (escaped)
                        escaped = false;
                    else if (c == '\\')
                        escaped = true;
                    else if (c == '"')
                        inString = false;
                }
                else if (c == '"')
                    inString = true;
                else if (c == '[' || c == '{')
                    deepest = Math.Max(deepest, ++depth);
                else if (c == ']' || c == '}')
                    depth--;
            }
            return deepest;
        }

        // Strict JSON into Dictionary<string, object>, List<object>, double, string, bool and null;
        // throws FormatException saying where. Nesting is bounded by the caller.
        class Parser
        {
            readonly string text;
            int at;

            public Parser(string text)
            {
                this.text = text;
            }

            public object Document()
            {
                object value = Value();
                Space();
                if (at != text.Length)
                    throw Error("text after the value");
                return value;
            }

            FormatException Error(string what)
            {
                return new FormatException(what + " at character " + at);
            }

            void Space()
            {
                while (at < text.Length && (text[at] == ' ' || text[at] == '\t' || text[at] == '\n' || text[at] == '\r'))
                    at++;
            }

            object Value()
            {
                Space();
                if (at >= text.Length)
                    throw Error("unexpected end");
                char c = text[at];
                if (c == '{')
                    return Object();
                if (c == '[')
                    return Array();
                if (c == '"')
                    return String();
                if (c == '-' || (c >= '0' && c <= '9'))
                    return Number();
                foreach (var word in new[] { "true", "false", "null" })
                {
                    if (string.CompareOrdinal(text, at, word, 0, word.Length) == 0)
                    {
                        at += word.Length;
                        return word == "null" ? null : (object)(word == "true");
                    }
                }
                throw Error("unexpected character '" + c + "'");
            }

            Dictionary<string, object> Object()
            {
                var result = new Dictionary<string, object>();
                at++;
                Space();
                if (at < text.Length && text[at] == '}')
                {
                    at++;
                    return result;
                }
                while (true)
                {
                    Space();
                    if (at >= text.Length || text[at] != '"')
                        throw Error("expected a name in quotes");
                    string name = String();
                    Space();
                    if (at >= text.Length || text[at] != ':')
                        throw Error("expected ':'");
                    at++;
                    result[name] = Value();
                    Space();
                    if (at < text.Length && text[at] == ',')
                    {
                        at++;
                        continue;
                    }
                    if (at < text.Length && text[at] == '}')
                    {
                        at++;
                        return result;
                    }
                    throw Error("expected ',' or '}'");
                }
            }

            List<object> Array()
            {
                var result = new List<object>();
                at++;
                Space();
                if (at < text.Length && text[at] == ']')
                {
                    at++;
                    return result;
                }
                while (true)
                {
                    result.Add(Value());
                    Space();
                    if (at < text.Length && text[at] == ',')
                    {
                        at++;
                        continue;
                    }
                    if (at < text.Length && text[at] == ']')
                    {
                        at++;
                        return result;
                    }
                    throw Error("expected ',' or ']'");
                }
            }

            string String()
            {
                var result = new StringBuilder();
                at++;
                while (at < text.Length)
                {
                    char c = text[at++];
                    if (c == '"')
                        return result.ToString();
                    if (c < ' ')
                        throw Error("a control character in a string");
                    if (c != '\\')
                    {
                        result.Append(c);
                        continue;
                    }
                    if (at >= text.Length)
                        break;
                    char e = text[at++];
                    int escape = "\"\\/bfnrt".IndexOf(e);
                    if (escape >= 0)
                        result.Append("\"\\/\b\f\n\r\t"[escape]);
                    else if (e == 'u' && at + 4 <= text.Length && ushort.TryParse(text.Substring(at, 4), NumberStyles.AllowHexSpecifier, CultureInfo.InvariantCulture, out ushort unit))
                    {
                        result.Append((char)unit);
                        at += 4;
                    }
                    else
                        throw Error("a bad escape '\\" + e + "'");
                }
                throw Error("a string without its closing quote");
            }

            double Number()
            {
                int start = at;
                if (text[at] == '-')
                    at++;
                if (at < text.Length && text[at] == '0')
                    at++;
                else if (!Digits())
                    throw Error("a number without digits");
                if (at < text.Length && text[at] == '.')
                {
                    at++;
                    if (!Digits())
                        throw Error("a number without digits after '.'");
                }
                if (at < text.Length && (text[at] == 'e' || text[at] == 'E'))
                {
                    at++;
                    if (at < text.Length && (text[at] == '+' || text[at] == '-'))
                        at++;
                    if (!Digits())
                        throw Error("a number without exponent digits");
                }
                string number = text.Substring(start, at - start);
                try
                {
                    return double.Parse(number, NumberStyles.Float, CultureInfo.InvariantCulture);
                }
                catch (OverflowException)
                {
                    return number[0] == '-' ? double.NegativeInfinity : double.PositiveInfinity;
                }
            }

            bool Digits()
            {
                int start = at;
                while (at < text.Length && text[at] >= '0' && text[at] <= '9')
                    at++;
                return at > start;
            }
        }
    }
}
