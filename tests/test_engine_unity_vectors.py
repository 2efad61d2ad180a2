"""The Unity package's Decode Vertex Vectors component (engines/unity/com.boxmarch.boxmarch/Runtime/
Scripts): the design's debug view, raw baked vectors and the same vectors turned by the box's
frame, which meet at each box's origin. Unity cannot run here: the component is compiled with
mono's mcs against a stub of the Unity API it calls (tests/engines/unity_stub/UnityGizmosStub.cs;
a misspelled Unity member must fail), and its decode (BoxmarchDecode.cs, plain C#) is run under
mono on the channels of real UNITY exports as Unity's import hands them (modelled from its
documentation, tests/engine_scene.py), against the generating box centres."""
import subprocess

import numpy as np
import pytest

from tests.engine_scene import UNITY, baked_scene, box_of_vertex, imported
from tests.engines import import_helpers
from tests.fbx_reader import read_fbx_geometry

pytestmark = pytest.mark.slow  # mcs and mono runs, Blender's FBX exporter

SCRIPTS = import_helpers.UNITY_PACKAGE / "Runtime" / "Scripts"
STUB = import_helpers.UNITY_STUB.parent / "UnityGizmosStub.cs"

# Reads "name v v v ..." lines (the layout's name first), decodes, writes "raw ..." and "corrected ...".
DRIVER = """using System; using System.Collections.Generic; using System.Globalization; using System.IO;
public static class DecodeDriver {
  public static int Main(string[] args) {
    var arrays = new Dictionary<string, float[]>();
    string[] lines = File.ReadAllLines(args[0]);
    foreach (string line in lines) {
      string[] parts = line.Split(' ');
      if (parts[0] == "layout") continue;
      var values = new float[parts.Length - 1];
      for (int i = 1; i < parts.Length; i++) values[i - 1] = float.Parse(parts[i], CultureInfo.InvariantCulture);
      arrays[parts[0]] = values;
    }
    var layout = (Boxmarch.BoxmarchLayout)Enum.Parse(typeof(Boxmarch.BoxmarchLayout), lines[0].Split(' ')[1]);
    int n = (int)arrays["count"][0];
    Func<string, float[]> get = name => arrays.ContainsKey(name) ? arrays[name] : null;
    float[] raw = new float[3 * n], corrected = new float[3 * n];
    Boxmarch.BoxmarchDecode.DecodeMesh(layout, n, get("uv1"), get("uv2"), get("uv3"), get("uv4"), get("colors"),
                                       get("normals"), get("tangents"), raw, corrected);
    using (var output = new StreamWriter(args[1])) {
      foreach (var pair in new[] { Tuple.Create("raw", raw), Tuple.Create("corrected", corrected) }) {
        output.Write(pair.Item1);
        foreach (float v in pair.Item2) output.Write(" " + v.ToString("R", CultureInfo.InvariantCulture));
        output.WriteLine();
      }
    }
    return 0;
  }
}
"""


def mcs(sources, out, target="library"):
    return subprocess.run(["mcs", f"-target:{target}", "-warnaserror+", f"-out:{out}", *map(str, sources)],
                          capture_output=True, text=True, timeout=120)


@pytest.fixture
def tools():
    import_helpers.need_mono()


def test_component_compiles_against_the_stub_and_a_misspelled_member_does_not(tools, tmp_path):
    sources = sorted(SCRIPTS.glob("*.cs"))
    built = mcs([STUB, *sources], tmp_path / "vectors.dll")
    assert built.returncode == 0, built.stdout + built.stderr
    component = SCRIPTS / "BoxmarchDecodeVectors.cs"
    text = component.read_text()
    for right, wrong in (("Gizmos.DrawLine(", "Gizmos.DrawLines("), ("skinned.BakeMesh(", "skinned.BakeMeshes("),
                         ("mesh.GetUVs(", "mesh.GetUV(")):
        assert right in text
        changed = tmp_path / component.name
        changed.write_text(text.replace(right, wrong))
        failed = mcs([STUB, SCRIPTS / "BoxmarchDecode.cs", changed], tmp_path / "wrong.dll")
        assert failed.returncode != 0 and "error CS" in failed.stdout + failed.stderr, (wrong, failed.stdout)


def run_decode(tmp_path, layout, channels):
    """BoxmarchDecode.DecodeMesh run under mono on ``channels`` (name -> float array): (raw, corrected) (n, 3)."""
    driver = tmp_path / "DecodeDriver.cs"
    driver.write_text(DRIVER)
    exe = tmp_path / "decode.exe"
    built = mcs([SCRIPTS / "BoxmarchDecode.cs", driver], exe, target="exe")
    assert built.returncode == 0, built.stdout + built.stderr
    count = len(channels["position"])
    lines = [f"layout {layout}", f"count {count}"]
    lines += [f"{name} " + " ".join(repr(float(v)) for v in np.asarray(a, np.float32).reshape(-1))
              for name, a in channels.items() if name != "position"]
    (tmp_path / "in.txt").write_text("\n".join(lines) + "\n")
    run = subprocess.run(["mono", str(exe), str(tmp_path / "in.txt"), str(tmp_path / "out.txt")],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    out = {line.split(" ")[0]: np.array(line.split(" ")[1:], float).reshape(-1, 3)
           for line in (tmp_path / "out.txt").read_text().splitlines()}
    return out["raw"], out["corrected"]


def unity_channels(raw, layout):
    """What Unity's Mesh holds for the FBX's per-corner ``raw`` data: positions with x negated,
    UV channels as written (float32, Read/Write on as the package sets it); NORMAL_FRAME also
    the normals and tangents with x negated, tangent.w the binormal's side."""
    if layout == "UV_FRAME":
        positions, uvs = imported(raw, UNITY)
        return {"position": positions, "uv1": uvs[0], "uv2": uvs[1], "uv3": uvs[2], "uv4": uvs[3]}
    mirror = UNITY["from_file"]
    positions = raw["position"] @ mirror.T
    normal, tangent, binormal = (raw[k] @ mirror.T for k in ("normal", "tangent", "binormal"))
    handedness = np.sign(np.einsum("ni,ni->n", np.cross(normal, tangent), binormal))[:, None]
    return {"position": positions, "uv1": raw["BoxOffsetXY"], "uv2": raw["BoxOffsetZIndex"], "normals": normal,
            "tangents": np.concatenate([tangent, handedness], 1)}


@pytest.mark.parametrize("layout", ["UV_FRAME", "NORMAL_FRAME"])
def test_corrected_vectors_meet_at_each_box_centre_and_raw_ones_do_not(tools, blender, tmp_path, layout):
    _ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path / "boxes.fbx"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="UNITY", layout=layout) == {"FINISHED"}
    channels = unity_channels(read_fbx_geometry(path), layout)
    raw, corrected = run_decode(tmp_path, layout, channels)
    positions = channels["position"]
    box = box_of_vertex(positions, centres, sizes, rotations, UNITY["to_engine"])
    centre = centres[box] @ UNITY["to_engine"].T
    scale = sizes[box].max(axis=1) / 2
    miss = np.linalg.norm(positions + corrected - centre, axis=1) / scale
    assert miss.max() < 1e-5, miss.max()
    # The raw vectors are box-local numbers: they meet at the centre only where the frame is the
    # identity, which no box of this scene has.
    raw_miss = np.linalg.norm(positions + raw - centre, axis=1) / scale
    assert np.median(raw_miss) > 0.1, np.median(raw_miss)
