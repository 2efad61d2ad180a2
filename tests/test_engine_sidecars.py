"""Every engine helper reads the sidecar (NAME.boxmarch.json) the same way, in its own runtime:
the one table of hostile sidecars (tests/helpers/hostile_sidecars.py: wrong types and values of
the keys every helper reads first, not UTF-8, not JSON, 100,000 nested brackets, larger than
16 MiB) refused by each with one line naming the file, and the table's valid sidecars read.
three.js: loadBoxmarch (r111 and r180 in Chromium, over a loopback HTTP server) with its URL
forms and its material options; Godot 3: the plug-in's check in godot3-server, and the editor
with the plug-in enabled on the sidecars that crashed or stopped it; Unity: the postprocessor's
check compiled with mcs against the Unity API stub and run under mono; Unreal: the import script
under a stub ``unreal`` module that fails on any use."""
import base64
import http.server
import json
import shutil
import subprocess
import sys
import threading
import time
import types

import pytest

from tests.engines import godot3, import_helpers, threejs
from tests.helpers import hostile_sidecars
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium, Godot, mono


def written_cases(folder, preset, layout):
    """Writes the table's sidecars into ``folder`` as cNN.boxmarch.json; {case: stem}."""
    stems = {}
    for number, (name, (data, _words)) in enumerate(hostile_sidecars.cases(preset, layout).items()):
        stems[name] = f"c{number:02d}"
        (folder / f"{stems[name]}.boxmarch.json").write_bytes(data)
    return stems


# --- three.js ---------------------------------------------------------------------------------

def loader_job(url, options="{}"):
    """The message loadBoxmarch(``url``) rejects with; null when it is the .glb's failure to load
    ("boxmarch: URL: GLTFLoader did not load it", no case serves a .glb): the sidecar was read."""
    return ("async function () { try { await loadBoxmarch(THREE, GLTFLoader, " + json.dumps(url) + ", " + options
            + "); return 'loaded'; } catch (e) { var m = String(e && e.message || e);"
            " return m.indexOf('boxmarch: ' + " + json.dumps(url) + " + ': GLTFLoader did not load it (') === 0 ? null : m; } }")


# createBoxmarchMaterial's options: refused (words of the message) or drawn as given (None).
MATERIAL_OPTIONS = {
    "{quality: 0}": "option quality must be a number from 0.05 to 1",
    "{quality: 1.5}": "option quality must be",
    "{quality: NaN}": "option quality must be",
    "{maxSteps: 0}": "option maxSteps must be a whole number from 1 to 512",
    "{maxSteps: -5}": "option maxSteps must be",
    "{maxSteps: 2.5}": "option maxSteps must be",
    "{maxSteps: '64'}": "option maxSteps must be",
    "{epsilon: -1e-4}": "option epsilon must be a number from 1e-7 to 1",
    "{epsilon: 0}": "option epsilon must be",
    "{map: ''}": "option map must be",
    "{map: 42}": "option map must be",
    "{occluders: 'SQUARE'}": "option occluders must be one of BOX, SPHERE",
    "{occluders: 1}": "option occluders must be",
    "{occluders: 'LINK'}": None,
    "{occluders: false}": None,
    "{visibilityPass: 'no'}": "option visibilityPass must be true or false, not no",
    "{visibilityPass: 0}": "option visibilityPass must be true or false",
    "{visibilityPass: false}": None,
    "{cullBackFaces: 'no'}": "option cullBackFaces must be true or false, not no",
    "{cullBackFaces: 1}": "option cullBackFaces must be true or false",
    "{cullBackFaces: false}": None,
    "{}": None,
    "{quality: 0.05, maxSteps: 1, epsilon: 1e-7}": None,
    "{quality: 1, maxSteps: 512, epsilon: 1}": None,
}
# What each accepted option set leaves in the material: bmMarch (epsilon, max steps) and the knob.
DRAWN = {"{}": [1e-4, 96, 1], "{quality: 0.05, maxSteps: 1, epsilon: 1e-7}": [1e-7, 1, 0.05],
         "{quality: 1, maxSteps: 512, epsilon: 1}": [1, 512, 1], "{occluders: 'LINK'}": [1e-4, 96, 1],
         "{occluders: false}": [1e-4, 96, 1], "{visibilityPass: false}": [1e-4, 96, 1],
         "{cullBackFaces: false}": [1e-4, 96, 1]}


def options_job():
    entries = ",\n".join(f"[{json.dumps(text)}, {text}]" for text in MATERIAL_OPTIONS)
    return ("function () { var out = {}; [" + entries + "].forEach(function (entry) {"
            " try { var u = createBoxmarchMaterial(THREE, entry[1]).uniforms;"
            " out[entry[0]] = [u.bmMarch.value.x, u.bmMarch.value.y, u.bmQuality.value.x]; }"
            " catch (e) { out[entry[0]] = String(e.message); } }); return out; }")


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def threejs_page(request, tmp_path_factory):
    """One Chromium page per release: every table sidecar through loadBoxmarch, the URL forms,
    the material options."""
    release = request.param
    need(threejs.available(release))
    folder = tmp_path_factory.mktemp("threejs-sidecars")
    stems = written_cases(folder, "GLTF", "NORMAL_FRAME")
    served = {path.name: path.read_bytes() for path in folder.iterdir()}
    null_version = stems["version null"]
    jobs = {name: loader_job(f"{stem}.glb") for name, stem in stems.items()}
    jobs.update({
        "query": loader_job("c00.glb?v=2"), "fragment": loader_job("c00.glb#part"),
        "query and fragment, refused": loader_job(f"{null_version}.glb?v=2#part"),
        "options refused before any fetch": loader_job("missing.glb", "{quality: 0}"),
        "options": options_job(),
    })
    results = threejs.run_jobs(b"", list(jobs.values()), threejs.shipped_material(release), release, served)
    return dict(zip(jobs, results)), stems


def test_threejs_loader_refuses_each_hostile_sidecar(threejs_page):
    out, stems = threejs_page
    hostile_sidecars.check_refusals(out, "GLTF", "NORMAL_FRAME", lambda name: f"{stems[name]}.boxmarch.json")


def test_threejs_loader_finds_the_sidecar_of_a_url_with_query_or_fragment(threejs_page):
    out, stems = threejs_page
    assert out["query"] is None and out["fragment"] is None, out  # c00 (valid) read: the .glb failed
    refused = out["query and fragment, refused"]
    assert refused.startswith(f"boxmarch: {stems['version null']}.boxmarch.json?v=2: format_version must be 1"), refused


def test_threejs_material_refuses_options_out_of_the_previews_range(threejs_page):
    out = threejs_page[0]
    options = out["options"]
    for text, words in MATERIAL_OPTIONS.items():
        if words is None:
            assert options[text] == pytest.approx(DRAWN[text], rel=1e-6), (text, options[text])
        else:
            assert isinstance(options[text], str) and options[text].startswith("boxmarch: ") and words in options[text], \
                (text, options[text])
    assert "option quality must be" in out["options refused before any fetch"]


# --- Godot 3 ----------------------------------------------------------------------------------

def godot_project(folder, files=None):
    godot3.write_project(folder, files or {}, plugins=("boxmarch",) if files is not None else ())
    shutil.copytree(import_helpers.GODOT3_ADDON, folder / "addons" / "boxmarch")
    return folder


def test_godot3_plugin_refuses_each_hostile_sidecar(tmp_path):
    need(godot3.available())
    project = godot_project(tmp_path)
    stems = written_cases(tmp_path, "GODOT3", "NORMAL_COLOR")
    out = godot3.plugin_refusals(project, [f"res://{stem}.glb" for stem in stems.values()])
    messages = {name: out[f"res://{stem}.glb"] or None for name, stem in stems.items()}
    hostile_sidecars.check_refusals(messages, "GODOT3", "NORMAL_COLOR", lambda name: f"res://{stems[name]}.boxmarch.json")


@pytest.mark.parametrize("hostile", ["100,000 nested brackets", "version null"])
def test_godot3_editor_reports_a_hostile_sidecar_and_sets_up_the_model_after_it(hostile, tmp_path):
    """The editor with the plug-in enabled opens a project holding a hostile sidecar (beside
    a.glb) and a valid GODOT3 one (beside b.glb, checked after it): the first is reported by
    name, the second gets mesh compression off, and the editor is still running 3 s later.
    Before: 100,000 nested brackets crashed the editor; a null format_version stopped the
    plug-in's check at a script error, so b.glb kept Godot's compressed import."""
    need(godot3.available())
    cases = hostile_sidecars.cases("GODOT3", "NORMAL_COLOR")
    files = {"a.boxmarch.json": cases[hostile][0], "a.glb": b"", "b.boxmarch.json": cases["valid"][0], "b.glb": b""}
    project = godot_project(tmp_path, files)
    words = cases[hostile][1]

    def both_reported(text):
        return ("boxmarch: re-importing res://b.glb with mesh compression off" in text
                and any("boxmarch: res://a.boxmarch.json: " in line and words in line for line in text.splitlines()))

    log, running = godot3.editor_log(project, until=both_reported, linger_s=3.0)
    assert running, log[-4000:]
    assert both_reported(log), log[-4000:]
    assert "SCRIPT ERROR" not in log, log[-4000:]
    assert "meshes/compress=false" in (tmp_path / "b.glb.import").read_text()


# --- Unity ------------------------------------------------------------------------------------

def test_unity_postprocessor_refuses_each_hostile_sidecar(tmp_path):
    import_helpers.need_mono()
    built = import_helpers.compile_unity(import_helpers.UNITY_POSTPROCESSOR.read_text(), tmp_path,
                                         [import_helpers.UNITY_STUB.parent / "SidecarRefusals.cs"], target="exe")
    assert built.returncode == 0, built.stdout + built.stderr
    stems = written_cases(tmp_path, "UNITY", "UV_FRAME")
    paths = [str(tmp_path / f"{stem}.boxmarch.json") for stem in stems.values()]
    run = subprocess.run(["mono", str(tmp_path / "boxmarch.exe"), *paths], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-3000:]
    lines = run.stdout.splitlines()
    assert len(lines) == len(stems), run.stdout[-3000:]
    messages = {name: None if line == "-" else base64.b64decode(line).decode() for name, line in zip(stems, lines)}
    hostile_sidecars.check_refusals(messages, "UNITY", "UV_FRAME", lambda name: paths[list(stems).index(name)])


# --- Unreal -----------------------------------------------------------------------------------

class UntouchedUnreal(types.ModuleType):
    """A stub ``unreal`` module that fails any use: a refused sidecar must stop the script first."""

    def __getattr__(self, name):
        raise AssertionError(f"unreal.{name} used although the sidecar was refused")


def test_unreal_script_refuses_each_hostile_sidecar_before_using_unreal(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "unreal", UntouchedUnreal("unreal"))
    namespace = {"__name__": "boxmarch_import"}
    exec(compile(import_helpers.UNREAL_SCRIPT.read_text(), str(import_helpers.UNREAL_SCRIPT), "exec"), namespace)
    stems = written_cases(tmp_path, "UNREAL", "UV_FRAME")
    messages = {}
    for name, stem in stems.items():
        model = str(tmp_path / f"{stem}.fbx")
        try:
            namespace["read_sidecar"](model)
            messages[name] = None
        except ValueError as error:
            messages[name] = str(error)
            with pytest.raises(ValueError):  # the import itself stops at the same check
                namespace["import_boxmarch_fbx"](model, "/Game/Boxmarch")
    hostile_sidecars.check_refusals(messages, "UNREAL", "UV_FRAME",
                                    lambda name: str(tmp_path / f"{stems[name]}.boxmarch.json"))


class _Streaming(http.server.BaseHTTPRequestHandler):
    """Serves any path as a sidecar declaring STREAMED_LENGTH bytes (over the 16 MiB limit) and
    streaming them slowly, CHUNK every PAUSE_S, until the client goes or STREAMED_LENGTH is sent
    (about 14 s); counts the bytes sent in ``sent`` (a one-item list, set per server)."""

    sent = [0]

    def do_GET(self):
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(STREAMED_LENGTH))
        self.send_header("Access-Control-Allow-Origin", "*")  # the page is served from another port
        self.end_headers()
        chunk = b" " * CHUNK
        try:
            while self.sent[0] < STREAMED_LENGTH:
                self.wfile.write(chunk)
                self.wfile.flush()
                self.sent[0] += len(chunk)
                time.sleep(PAUSE_S)
        except OSError:  # the client closed the connection
            pass

    def log_message(self, *args):
        pass


CHUNK, PAUSE_S = 1 << 16, 0.05
STREAMED_LENGTH = hostile_sidecars.MAX_BYTES + CHUNK


@pytest.mark.parametrize("release", sorted(threejs.RELEASES))
def test_threejs_loader_refuses_a_declared_length_over_the_limit_before_reading_the_body(release):
    """A server that declares a sidecar of over 16 MiB and streams it slowly: loadBoxmarch refuses
    it from its Content-Length, the body unread: the server has sent a small share of it when the
    page is done (reading it all would take about 14 s; the body-size check alone gives the same
    message only after it)."""
    need(threejs.available(release))
    handler = type("Streaming", (_Streaming,), {"sent": [0]})
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = f"http://127.0.0.1:{server.server_address[1]}/big.glb"
    try:
        message = threejs.run_page(b"", loader_job(url), threejs.shipped_material(release), release)
    finally:
        server.shutdown()
        server.server_close()
    sidecar = url.replace(".glb", ".boxmarch.json")
    assert message == f"boxmarch: {sidecar}: larger than {hostile_sidecars.MAX_BYTES} bytes, not a boxmarch sidecar"
    assert handler.sent[0] <= STREAMED_LENGTH // 4, handler.sent[0]
