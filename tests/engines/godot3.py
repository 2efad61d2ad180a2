"""Godot 3 (Debian's godot3 / godot3-server 3.2) importing a .glb and drawing it.

``import_gltf`` writes a minimal project and runs the editor's headless import; ``dump_arrays``
runs a SceneTree script that writes every surface array as float64 to a binary file (no text
printing, so float32 values come back bit-exactly); ``render`` draws one frame with ``godot3``
under ``xvfb-run`` (Mesa llvmpipe) and writes the viewport's RGBA8 bytes. Every Godot run gets a temporary
HOME/XDG tree and a time limit; failures raise ``RuntimeError`` with Godot's output.
"""
import json
import os
import shutil
import signal
import struct
import subprocess
import tempfile
import time

import numpy as np

from . import Shot

GODOT = "godot3"
GODOT_SERVER = "godot3-server"
TIMEOUT_S = 60
# Godot's Mesh.ARRAY_* order and the values per vertex of each.
ARRAYS = {"vertex": 3, "normal": 3, "tangent": 4, "color": 4, "uv": 2, "uv2": 2, "bones": 4,
          "weights": 4, "index": 1}

_PROJECT = 'config_version=4\n\n[application]\n\nconfig/name="boxmarch-engine-test"\n'

# Shared by both scripts: the nodes of a class under a node, node -> root transforms, and
# transforms written as 12 doubles.
_COMMON = """extends SceneTree

func nodes_of_class(node, name, out):
    if node.is_class(name):
        out.append(node)
    for child in node.get_children():
        nodes_of_class(child, name, out)
    return out

func global_xform(node, top):
    var t = node.transform
    while node != top:
        node = node.get_parent()
        t = node.transform * t
    return t

func store_xform(f, t):
    for v in [t.basis.x, t.basis.y, t.basis.z, t.origin]:
        f.store_double(v.x)
        f.store_double(v.y)
        f.store_double(v.z)
"""

_DUMP = _COMMON + """
func store_array(f, a):
    if a == null:
        f.store_32(0)
        return
    var flat = []
    for e in a:
        match typeof(e):
            TYPE_VECTOR2:
                flat += [e.x, e.y]
            TYPE_VECTOR3:
                flat += [e.x, e.y, e.z]
            TYPE_COLOR:
                flat += [e.r, e.g, e.b, e.a]
            _:
                flat.append(e)
    f.store_32(1)
    f.store_32(flat.size())
    for x in flat:
        f.store_double(x)

func _init():
    var f = File.new()
    f.open(OS.get_environment("BOXMARCH_PARAMS"), File.READ)
    var params = parse_json(f.get_as_text())
    f.close()
    var scene = load(params.model).instance()
    f.open(OS.get_environment("BOXMARCH_OUT"), File.WRITE)
    for mi in nodes_of_class(scene, "MeshInstance", []):
        for s in range(mi.mesh.get_surface_count()):
            var arrays = mi.mesh.surface_get_arrays(s)
            f.store_pascal_string(mi.name)
            store_xform(f, global_xform(mi, scene))
            for k in range(Mesh.ARRAY_MAX):
                store_array(f, arrays[k])
    f.close()
    quit()
"""

_SHOT = _COMMON + """
var params
var camera
var frames = 0
var posed = -1
# Turns each named bone by angle about its own head, about a world axis as it points with the
# skeleton at rest (moved into the bone's frame with the rest global rotations, read first).
func pose_bones(scene, turns, angle):
    var count = 0
    for sk in nodes_of_class(scene, "Skeleton", []):
        var rest = {}  # bone index -> its rest rotation in world space
        var axes = {}  # bone index -> its turn's world axis
        for name in turns:
            var i = sk.find_bone(name)
            if i >= 0:
                rest[i] = (sk.global_transform * sk.get_bone_global_pose(i)).basis.orthonormalized()
                axes[i] = Vector3(turns[name][0], turns[name][1], turns[name][2])
        for i in rest:
            var axis = rest[i].inverse().xform(axes[i]).normalized()
            sk.set_bone_pose(i, Transform(Basis(axis, angle), Vector3()))
            count += 1
    return count

func uniform_value(v):
    if typeof(v) == TYPE_STRING:
        return load(v)
    if typeof(v) == TYPE_ARRAY:
        match v.size():
            2: return Vector2(v[0], v[1])
            3: return Vector3(v[0], v[1], v[2])
            4: return Plane(v[0], v[1], v[2], v[3])
    return v

func _init():
    var f = File.new()
    f.open(OS.get_environment("BOXMARCH_PARAMS"), File.READ)
    params = parse_json(f.get_as_text())
    f.close()
    VisualServer.set_default_clear_color(Color(0, 0, 0, 1))
    var shader = Shader.new()
    shader.code = params.shader
    var material = ShaderMaterial.new()
    material.shader = shader
    for name in params.uniforms:
        material.set_shader_param(name, uniform_value(params.uniforms[name]))
    var scene = load("res://model.glb").instance()
    root.add_child(scene)
    for mi in nodes_of_class(scene, "MeshInstance", []):
        for s in range(mi.mesh.get_surface_count()):
            mi.set_surface_material(s, material)
        if params.has("child_script"):
            var child = MeshInstance.new()
            child.set_script(load(params.child_script))
            for name in params.child_properties:
                child.set(name, uniform_value(params.child_properties[name]))
            mi.add_child(child)
    if params.has("bone_turns"):
        posed = pose_bones(scene, params.bone_turns, params.turn_angle)
    var c = params.camera
    camera = Camera.new()
    root.add_child(camera)
    var up = c.get("up", [0, 1, 0])
    camera.look_at_from_position(uniform_value(c.position), uniform_value(c.target), uniform_value(up))
    if c.has("ortho"):
        camera.set_orthogonal(2.0 * c.ortho, c.get("near", 0.1), c.get("far", 1000.0))
    else:
        camera.set_perspective(c.fov, c.get("near", 0.1), c.get("far", 1000.0))
    camera.make_current()

func _idle(_delta):
    frames += 1
    if frames > 60:  # _init failed: a script error does not stop Godot
        quit()
    if frames < 4:
        return
    if params.has("bone_turns") and posed != params.bone_turns.size():
        quit()  # a bone to turn is missing: no result
        return
    var image = root.get_texture().get_data()
    image.flip_y()
    image.convert(Image.FORMAT_RGBA8)
    var f = File.new()
    f.open(OS.get_environment("BOXMARCH_OUT"), File.WRITE)
    f.store_32(image.get_width())
    f.store_32(image.get_height())
    f.store_buffer(image.get_data())
    var t = camera.get_camera_transform()
    store_xform(f, t)
    for p in params.probes:
        var world = t.xform(Vector3(p[0], p[1], p[2]))
        var px = camera.unproject_position(world)
        for x in [world.x, world.y, world.z, px.x, px.y]:
            f.store_double(x)
    f.close()
    quit()
"""

# Camera-space points (x, y, -depth) where the camera's world -> pixel matrix is sampled.
_PROBES = [[x * d * 0.1, y * d * 0.1, -d] for d in (1.0, 3.0, 7.0) for x in (-1, 1) for y in (-1, 0.5)]


# The shipped shader's map() body and frame lines, which tests replace.
SHIPPED_MAP = "return sd_round_box(p, h, 0.1 * min3(h));"
# bm_map_hit()'s body as shipped (the default rounded box's hit), and the body that marches map()
SHIPPED_CLOSED_FORM = "return bm_round_box_hit(ro, rd, h, 0.1 * min3(h));"
MARCH_MAP = "return vec4(0.0, 0.0, 0.0, -2.0);"
SHIPPED_FRAME = ("  bm_v_axis_z = mat3(WORLD_MATRIX) * NORMAL;\n  bm_v_axis_x = mat3(WORLD_MATRIX) * TANGENT;\n"
                 "  bm_v_axis_y = mat3(WORLD_MATRIX) * BINORMAL;")
# Negative controls for a mesh whose object sits at the world origin (the varyings are world
# space): the identity frame, and the frame as the vertex carries it at rest (what a frame in
# UV maps gives the shader: no skinning turns it).
IDENTITY_FRAME = "  bm_v_axis_z = vec3(0.0, 0.0, 1.0);\n  bm_v_axis_x = vec3(1.0, 0.0, 0.0);\n  bm_v_axis_y = vec3(0.0, 1.0, 0.0);"
REST_FRAME = "  bm_v_axis_z = NORMAL;\n  bm_v_axis_x = TANGENT;\n  bm_v_axis_y = BINORMAL;"


def shipped_shader(map_code=None, frame_code=None, closed_code=None):
    """shaders/godot3/boxmarch.shader, with its map() body replaced by ``map_code``, its frame
    lines by ``frame_code`` and its bm_map_hit() body by ``closed_code`` where given (each must be
    found); a map_code without a closed_code marches (bm_map_hit() returns w = -2)."""
    from boxmarch.formats import shader_sources

    code = (shader_sources.shader_dir() / "godot3" / "boxmarch.shader").read_text()
    if map_code is not None and closed_code is None:
        closed_code = MARCH_MAP
    for old, new in ((SHIPPED_MAP, map_code), (SHIPPED_FRAME, frame_code), (SHIPPED_CLOSED_FORM, closed_code)):
        if new is not None:
            if old not in code:
                raise AssertionError(f"the shipped Godot shader has no {old!r}")
            code = code.replace(old, new)
    return code


def available():
    """None when godot3, godot3-server and xvfb-run are installed, else the reason."""
    for tool, package in ((GODOT, "godot3"), (GODOT_SERVER, "godot3-server"), ("xvfb-run", "xvfb")):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (apt-get install {package})"
    return None


def _home_env(home):
    """The environment of a Godot run whose HOME and XDG folders are under ``home``."""
    return dict(os.environ, HOME=home, XDG_CONFIG_HOME=os.path.join(home, "config"),
                XDG_DATA_HOME=os.path.join(home, "data"), XDG_CACHE_HOME=os.path.join(home, "cache"))


def _godot(cmd, project_dir, extra_env=()):
    """Runs a Godot command with a throw-away HOME; returns its combined output."""
    with tempfile.TemporaryDirectory(prefix="boxmarch-godot-home-") as home:
        env = _home_env(home)
        env.update(extra_env)
        # own session: on timeout the whole group (xvfb-run, Xvfb, godot) is killed
        proc = subprocess.Popen(cmd + ["--audio-driver", "Dummy", "--path", str(project_dir)],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, start_new_session=True)
        try:
            return proc.communicate(timeout=TIMEOUT_S)[0]
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            raise RuntimeError(f"{cmd[0]} timed out after {TIMEOUT_S} s:\n{proc.communicate()[0]}") from None


def _run_script(cmd, project_dir, script, params=None):
    """Runs a SceneTree ``script`` that reads ``params`` (JSON) from $BOXMARCH_PARAMS and writes
    $BOXMARCH_OUT; returns the bytes written. Raises with Godot's output when the script or a
    shader failed to compile or run (Godot itself carries on after both)."""
    with tempfile.TemporaryDirectory(prefix="boxmarch-godot-") as tmp:
        paths = {name: os.path.join(tmp, name) for name in ("script.gd", "params.json", "out.bin")}
        with open(paths["script.gd"], "w") as f:
            f.write(script)
        with open(paths["params.json"], "w") as f:
            json.dump(params, f)
        log = _godot(cmd + ["-s", paths["script.gd"]], project_dir,
                     {"BOXMARCH_PARAMS": paths["params.json"], "BOXMARCH_OUT": paths["out.bin"]})
        failed = [e for e in ("SCRIPT ERROR", "SHADER ERROR", "Parse Error") if e in log]
        if failed or not os.path.isfile(paths["out.bin"]):
            raise RuntimeError(f"Godot failed ({', '.join(failed) or 'no result'}):\n{log[-6000:]}")
        with open(paths["out.bin"], "rb") as f:
            return f.read()


def write_project(project_dir, files, plugins=()):
    """Writes a Godot 3 project into ``project_dir``: project.godot (with the editor plug-ins
    named by their folder under res://addons/ enabled, as Godot 3.2 names them) and ``files``
    (relative path -> bytes)."""
    text = _PROJECT
    if plugins:
        text += "\n[editor_plugins]\n\nenabled=PoolStringArray( " + ", ".join(f'"{p}"' for p in plugins) + " )\n"
    files = {"project.godot": text.encode(), **files}
    for name, data in files.items():
        path = os.path.join(project_dir, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)


def _imported(project_dir, model):
    """The md5 file of ``model`` (res:// relative path) in .import/, or None."""
    folder = os.path.join(project_dir, ".import")
    name = os.path.basename(model)
    hits = [n for n in os.listdir(folder) if n.startswith(name + "-") and n.endswith(".md5")] if os.path.isdir(folder) else []
    return os.path.join(folder, hits[0]) if hits else None


def _newest_change(project_dir):
    """The latest modification time of any file under ``project_dir``."""
    return max((os.path.getmtime(os.path.join(root, n)) for root, _dirs, names in os.walk(project_dir) for n in names),
               default=0.0)


def import_project(project_dir, models, quiet_s=1.0):
    """Runs Godot's editor headless on ``project_dir`` until every one of ``models`` (paths
    relative to the project) has its ``.import/NAME-*.md5`` and no file of the project changed
    for ``quiet_s`` seconds, then stops it (``--quit`` can leave before the first scan when the
    machine is loaded, and an editor plug-in may re-import after the first import). Returns
    Godot's output; raises RuntimeError with it when a model is not imported within TIMEOUT_S."""
    with tempfile.TemporaryDirectory(prefix="boxmarch-godot-home-") as home:
        env = _home_env(home)
        log_path = os.path.join(home, "log.txt")
        with open(log_path, "w") as log:
            proc = subprocess.Popen([GODOT_SERVER, "-e", "--audio-driver", "Dummy", "--path", str(project_dir)],
                                    env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        start, done = time.monotonic(), False
        try:
            while time.monotonic() - start < TIMEOUT_S and proc.poll() is None:
                time.sleep(0.25)
                if all(_imported(project_dir, m) for m in models) and time.time() - _newest_change(project_dir) > quiet_s:
                    done = True
                    break
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            with open(log_path) as f:
                output = f.read()
    if not done:
        missing = [m for m in models if not _imported(project_dir, m)]
        raise RuntimeError(f"Godot did not import {missing or models} within {TIMEOUT_S} s:\n{output[-6000:]}")
    return output


def editor_log(project_dir, until, linger_s):
    """Runs Godot's editor headless on ``project_dir`` until ``until(output so far)`` holds (or
    TIMEOUT_S), then ``linger_s`` seconds more, and stops it. Returns (its output, whether it was
    still running at the end): an editor that crashed has stopped by itself."""
    with tempfile.TemporaryDirectory(prefix="boxmarch-godot-home-") as home:
        log_path = os.path.join(home, "log.txt")
        with open(log_path, "w") as log:
            proc = subprocess.Popen([GODOT_SERVER, "-e", "--audio-driver", "Dummy", "--path", str(project_dir)],
                                    env=_home_env(home), stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            start = time.monotonic()
            while time.monotonic() - start < TIMEOUT_S and proc.poll() is None:
                time.sleep(0.25)
                with open(log_path, errors="replace") as f:
                    if until(f.read()):
                        break
            time.sleep(linger_s)
            running = proc.poll() is None
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        with open(log_path, errors="replace") as f:
            return f.read(), running


def import_gltf(glb_bytes, project_dir, *, compress, extra_files=None):
    """Writes a Godot 3 project holding ``model.glb`` (and ``extra_files``: relative path ->
    bytes) into ``project_dir`` and imports it headless (import_project) with ``meshes/compress``
    set to ``compress``. The settings go into ``model.glb.import`` and the cached import
    (``.import/``) is deleted first: Godot honours an .import file present at import time, but
    editing it alone does not trigger a re-import. Returns Godot's output."""
    shutil.rmtree(os.path.join(project_dir, ".import"), ignore_errors=True)
    files = {"model.glb": glb_bytes,
             "model.glb.import": ('[remap]\n\nimporter="scene"\ntype="PackedScene"\n\n[params]\n\n'
                                  f"meshes/compress={'true' if compress else 'false'}\n").encode()}
    write_project(project_dir, {**files, **(extra_files or {})})
    return import_project(project_dir, ["model.glb"])


def _read_xform(data, at):
    """4x4 matrix from the 12 doubles store_xform wrote (basis columns, then origin)."""
    cols = np.array(struct.unpack_from("<12d", data, at)).reshape(4, 3)
    m = np.eye(4)
    m[:3, :] = cols.T
    return m, at + 96


def dump_arrays(project_dir, model="res://model.glb"):
    """What Godot's importer stored: one dict per surface of every MeshInstance of the imported
    ``model`` (tree order): ``{"name": node name, "surface": index, "transform": 4x4
    node -> scene-root matrix, "vertex", "normal", "tangent", "color", "uv", "uv2", "bones",
    "weights", "index": float64 arrays or None}``. Per-vertex arrays are (count, width): vertex
    and normal 3, uv and uv2 2, tangent, color, bones and weights 4; index is (n,). Values are the
    float32 Godot holds, widened exactly."""
    data = _run_script([GODOT_SERVER, "--quit"], project_dir, _DUMP, {"model": model})
    surfaces, at, surface_of = [], 0, {}
    while at < len(data):
        (n,) = struct.unpack_from("<I", data, at)
        name = data[at + 4 : at + 4 + n].decode()
        transform, at = _read_xform(data, at + 4 + n)
        surface_of[name] = surface_of.get(name, -1) + 1
        entry = {"name": name, "surface": surface_of[name], "transform": transform}
        for key, width in ARRAYS.items():
            (present,) = struct.unpack_from("<I", data, at)
            at += 4
            if not present:
                entry[key] = None
                continue
            (size,) = struct.unpack_from("<I", data, at)
            values = np.array(struct.unpack_from(f"<{size}d", data, at + 4))
            at += 4 + 8 * size
            entry[key] = values if key == "index" else values.reshape(-1, width)
        surfaces.append(entry)
    return surfaces


def _fit_to_pixels(world, pixels):
    """The 3x4 matrix P with pixel ~ P @ [world, 1] (homogeneous), by least squares (DLT)."""
    rows = []
    for (x, y, z), (u, v) in zip(world, pixels):
        p = [x, y, z, 1.0]
        rows.append(p + [0.0] * 4 + [-u * c for c in p])
        rows.append([0.0] * 4 + p + [-v * c for c in p])
    m = np.linalg.svd(np.array(rows))[2][-1].reshape(3, 4)
    return m / np.linalg.norm(m[2, :3]) if np.linalg.norm(m[2, :3]) > 1e-9 else m / m[2, 3]


def render(project_dir, shader_code, *, width, height, camera, uniforms=None, bone_turns=None, turn_angle=0.0,
           child_script=None, child_properties=None):
    """Draws the imported ``res://model.glb`` once with ``godot3`` (GLES3 on llvmpipe under
    xvfb-run) and returns a :class:`Shot`.

    Every MeshInstance surface gets one ShaderMaterial with ``shader_code`` (a ``shader_type
    spatial;`` shader; use ``render_mode unshaded;`` to write exact colours, ALBEDO is still
    converted to sRGB). ``uniforms``: name -> float, [x, y] / [x, y, z] / [x, y, z, w] lists, or a
    ``res://`` path of a resource (an imported texture). ``camera`` is the dict threejs.render
    takes: perspective with vertical ``fov`` degrees, or ``ortho`` half-height; ``near``/``far``
    optional. ``bone_turns`` (bone name -> world axis (3,) as it points with the skeleton at
    rest) turns each named bone of the imported Skeleton by ``turn_angle`` radians about its own
    head, on top of its rest pose (``Skeleton.set_bone_pose``); a name no bone has fails the
    render. ``child_script`` (a ``res://`` path of a script extending MeshInstance): a MeshInstance
    with that script, its properties set from ``child_properties`` (name -> value, as ``uniforms``),
    is added under every MeshInstance after its material is set. The background is opaque black (0, 0, 0, 255). ``Shot.view`` inverts
    ``Camera.get_camera_transform()``; ``Shot.to_pixels`` is fitted to
    ``Camera.unproject_position`` of probe points (the fit must reproduce them within 1e-3 px).
    """
    params = {"shader": shader_code, "uniforms": uniforms or {}, "camera": camera,
              "probes": _PROBES}
    if bone_turns:
        params.update(bone_turns={k: [float(x) for x in v] for k, v in bone_turns.items()},
                      turn_angle=float(turn_angle))
    if child_script:
        params.update(child_script=child_script, child_properties=child_properties or {})
    cmd = ["xvfb-run", "-a", "-s", f"-screen 0 {max(width, 640)}x{max(height, 480)}x24",
           GODOT, "--resolution", f"{width}x{height}"]
    data = _run_script(cmd, project_dir, _SHOT, params)
    w, h = struct.unpack_from("<II", data)
    pixels = np.frombuffer(data, dtype=np.uint8, count=w * h * 4, offset=8).reshape(h, w, 4).copy()
    cam_to_world, at = _read_xform(data, 8 + w * h * 4)
    probes = np.array(struct.unpack_from(f"<{5 * len(_PROBES)}d", data, at)).reshape(-1, 5)
    to_pixels = _fit_to_pixels(probes[:, :3], probes[:, 3:])
    fitted = np.c_[probes[:, :3], np.ones(len(probes))] @ to_pixels.T
    residual = np.abs(fitted[:, :2] / fitted[:, 2:3] - probes[:, 3:]).max()
    if residual > 1e-3:
        raise RuntimeError(f"Godot's camera is not a 3x4 projection (fit residual {residual} px)")
    if pixels.shape[:2] != (height, width):
        raise RuntimeError(f"Godot drew {pixels.shape[1]}x{pixels.shape[0]}, not {width}x{height}")
    return Shot(pixels, np.linalg.inv(cam_to_world), to_pixels)



_REFUSALS = """extends SceneTree

func _init():
    var f = File.new()
    f.open(OS.get_environment("BOXMARCH_PARAMS"), File.READ)
    var params = parse_json(f.get_as_text())
    f.close()
    # plugin.gd's refusal(model) as the plug-in makes it (an EditorPlugin is not made outside the editor)
    var plugin = load("res://addons/boxmarch/plugin.gd").get_script_constant_map()
    var sidecar = load("res://addons/boxmarch/sidecar.gd")
    var out = {}
    for model in params["models"]:
        out[model] = sidecar.refusal(model.get_basename() + plugin["SIDECAR_SUFFIX"], plugin["FORMAT_VERSION"],
                                     plugin["PRESET"], plugin["LAYOUTS_READ"])
    f.open(OS.get_environment("BOXMARCH_OUT"), File.WRITE)
    f.store_string(to_json(out))
    f.close()
    quit()
"""


def plugin_refusals(project_dir, models):
    """{model: the boxmarch plug-in's refusal of its sidecar ("" when it reads it)} for each
    ``models`` path (res://NAME.glb), made as ``plugin.gd`` makes it (its constants, its
    ``sidecar.gd``) by godot3-server in ``project_dir``, which must hold the plug-in under
    res://addons/boxmarch."""
    return json.loads(_run_script([GODOT_SERVER], project_dir, _REFUSALS, {"models": list(models)}))


_CHILD_MESHES = _COMMON + """
func _init():
    var f = File.new()
    f.open(OS.get_environment("BOXMARCH_PARAMS"), File.READ)
    var params = parse_json(f.get_as_text())
    f.close()
    var parents = {"model": load("res://model.glb").instance(), "not_a_mesh_instance": Spatial.new(),
                   "mesh_without_colours": MeshInstance.new()}
    parents["mesh_without_colours"].mesh = CubeMesh.new()
    var out = {}
    for name in parents:
        root.add_child(parents[name])
        var parent = parents[name]
        if name == "model":
            parent = nodes_of_class(parent, "MeshInstance", [])[0]
        var child = MeshInstance.new()
        child.set_script(load(params.script))
        parent.add_child(child)
        out[name] = -1 if child.mesh == null else child.mesh.get_surface_count()
    f.open(OS.get_environment("BOXMARCH_OUT"), File.WRITE)
    f.store_string(to_json(out))
    f.close()
    quit()
"""


def child_meshes(project_dir, script):
    """{parent: the surface count of the mesh a MeshInstance with ``script`` (res:// path) built
    once added under it (-1: none)} for three parents made by godot3-server in ``project_dir``:
    "model" (the first MeshInstance of res://model.glb), "not_a_mesh_instance" (a Spatial) and
    "mesh_without_colours" (a MeshInstance of a CubeMesh)."""
    return json.loads(_run_script([GODOT_SERVER], project_dir, _CHILD_MESHES, {"script": script}))
