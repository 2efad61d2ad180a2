// Runs the package's sidecar check under mono as OnPreprocessModel runs it
// (BoxmarchModelPostprocessor.Refusal): one line per sidecar path given, "-" when the package
// reads it, else its refusal as base64 of UTF-8 (a message stays one line whatever it holds).
// Compiled with the stub and the package by tests/test_engine_sidecars.py.
using System;
using System.Text;

public static class SidecarRefusals
{
    public static void Main(string[] paths)
    {
        foreach (string path in paths)
        {
            string refusal = Boxmarch.Editor.BoxmarchModelPostprocessor.Refusal(path);
            Console.WriteLine(refusal == null ? "-" : Convert.ToBase64String(Encoding.UTF8.GetBytes(refusal)));
        }
    }
}
