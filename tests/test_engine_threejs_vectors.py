"""The decode-vectors view in three.js (boxmarchDecodeVectors, shaders/threejs/): the design's
"Decode vertex vectors" debug view, drawn by r111 (WebGL 1) and r180 (WebGL 2) in headless
Chromium from the GLTF preset's export of the mixed scene, over the mesh's faces drawn black and,
as the README's snippet draws it, over the shapes loadBoxmarch marches. The corrected (orange)
lines must run from every box corner to the box's generating centre, within 1.5 px, and nowhere
else; the raw (light blue) lines from every vertex along its TEXCOORD_1.xy, TEXCOORD_2.x as stored
(read by the release's GLTFLoader, not by the code under test). Negative controls: the frame read with a wrong
channel (the tangent's w negated, so the y axis flips; the normal and the tangent swapped) must
visibly fail to converge, and so must the raw lines."""
import numpy as np
import pytest

from tests.conftest import empty_scene
from tests.engine_scene import TO_Y_UP, baked_scene, box_corners
from tests.engines import segment_errors, threejs
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium renders

W, H = 480, 360
CAMERA = {"position": [2.0, 9.0, 14.0], "target": [0.5, -0.5, 0.0], "fov": 50, "near": 0.5, "far": 100}
# Geometry tampering before the view is built (JS, ``g`` the mesh's geometry, ``t`` its tangents).
CONTROLS = {
    "tangent-w-negated": "for (var i = 3; i < t.length; i += 4) t[i] = -t[i];",
    "normal-and-tangent-swapped": ("var n = g.getAttribute('normal').array;"
                                   "for (var i = 0; i < n.length / 3; i++) for (var k = 0; k < 3; k++) {"
                                   " var s = n[3 * i + k]; n[3 * i + k] = t[4 * i + k]; t[4 * i + k] = s; }"),
}


def view_js(options, tamper=""):
    """Draws every mesh's faces black (they would hide the lines inside the boxes, were the lines
    depth-tested) and its decode-vectors view with ``options`` (JS object text) over them."""
    return ("var meshes = []; gltf.scene.traverse(function (o) { if (o.isMesh) meshes.push(o); });"
            " meshes.forEach(function (o) { var g = o.geometry, t = g.getAttribute('tangent').array;" + tamper +
            " o.material = new THREE.MeshBasicMaterial({color: 0x000000});"
            " boxmarchDecodeVectors(THREE, o, " + options + "); });")


# The README's snippet as written (loadBoxmarch's defaults: the rounded boxes marched, the pre-pass,
# the back-face culling; the view's defaults: both kinds of line).
README_JS = ("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'mixed.glb');"
             " scene.add(loaded.scene);"
             " loaded.meshes.forEach(function (mesh) { boxmarchDecodeVectors(THREE, mesh); });")


@pytest.fixture(scope="module")
def exported(bpy_module, tmp_path_factory):
    blender = empty_scene(bpy_module)
    _ob, centres, sizes, rotations = baked_scene(blender)
    path = tmp_path_factory.mktemp("vectors") / "mixed.glb"
    assert blender.ops.boxmarch.export(filepath=str(path), preset="GLTF") == {"FINISHED"}
    files = {"mixed.glb": path.read_bytes(), "mixed.boxmarch.json": path.with_suffix(".boxmarch.json").read_bytes()}
    return files, centres, sizes, rotations


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def page(request, exported):
    release = request.param
    need(threejs.available(release))
    files, centres, sizes, rotations = exported
    glb = files["mixed.glb"]
    jobs = {"meshes": threejs.load_job(),
            "corrected": threejs.render_job(view_js("{raw: false}"), W, H, CAMERA)}
    for name, tamper in CONTROLS.items():
        jobs[name] = threejs.render_job(view_js("{raw: false}", tamper), W, H, CAMERA)
    jobs["refusal"] = ("function (gltf) { try { boxmarchDecodeVectors(THREE, gltf.scene, {}); return 'no error'; }"
                       " catch (e) { return e.message; } }")
    jobs["no-channels"] = ("function (gltf) { var g = new THREE.BufferGeometry();"
                           " g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));"
                           " var mesh = new THREE.Mesh(g); try { boxmarchDecodeVectors(THREE, mesh); }"
                           " catch (e) { return [e.message, mesh.children.length]; } return 'no error'; }")
    jobs["readme"] = threejs.render_job(README_JS, W, H, CAMERA)
    results = threejs.run_jobs(glb, list(jobs.values()), threejs.shipped_material(release), release, files)
    return dict(zip(jobs, results), release=release), centres, sizes, rotations


def corrected_segments(shot, centres, sizes, rotations):
    """Every generating box corner to its box's generating centre, in the engine's pixels."""
    segments = []
    for c, s, r in zip(centres, sizes, rotations):
        ends = shot.project(np.r_[box_corners(c, s, r), [c]] @ TO_Y_UP.T)
        segments += [[corner, ends[-1]] for corner in ends[:-1]]
    return np.array(segments)


def raw_segments(shot, mesh, release):
    """Every vertex to the vertex plus its raw offset (TEXCOORD_1.xy, TEXCOORD_2.x) as the loader read it."""
    a, names = mesh["attributes"], threejs.RELEASES[release].texcoords
    world = (np.c_[a["position"], np.ones(len(a["position"]))] @ mesh["matrixWorld"].T)[:, :3]
    f = np.c_[a[names[1]], a[names[2]][:, :1]]
    return np.stack([shot.project(world), shot.project(world + f @ mesh["matrixWorld"][:3, :3].T)], axis=1)


def drawn(shot):
    """The lines' pixels: the background is clear and the faces black."""
    return shot.pixels[..., :3].max(axis=2) > 40


def test_corrected_vectors_meet_at_each_box_centre(page):
    out, centres, sizes, rotations = page
    (mesh,) = out["meshes"]
    assert np.allclose(mesh["matrixWorld"], np.eye(4))  # the generating frame is the mesh's
    shot = out["corrected"]
    segments = corrected_segments(shot, centres, sizes, rotations)
    assert drawn(shot).sum() > 500
    assert segment_errors(drawn(shot), segments) == (0, 0)
    colours = shot.pixels[drawn(shot)][:, :3].astype(int)
    assert (colours[:, 0] > colours[:, 1]).all() and (colours[:, 1] > colours[:, 2]).all()  # orange


def readme_lines(shot):
    """(orange, light blue) pixels of the README's picture: its marched shapes are grey."""
    rgb = shot.pixels[..., :3].astype(int)
    return rgb[..., 0] - rgb[..., 2] > 100, rgb[..., 2] - rgb[..., 0] > 60


def test_the_readme_snippet_draws_both_kinds_over_the_loaders_marched_boxes(page):
    out, centres, sizes, rotations = page
    shot = out["readme"]
    orange, blue = readme_lines(shot)
    assert ((shot.pixels[..., :3].max(axis=2) > 40) & ~orange & ~blue).sum() > 2000  # the marched shapes
    assert segment_errors(orange, corrected_segments(shot, centres, sizes, rotations)) == (0, 0)
    raw = raw_segments(shot, out["meshes"][0], out["release"])
    # the orange lines are drawn after the blue ones: where they cross, the blue line lies under them
    assert (segment_errors(blue, raw)[0], segment_errors(blue | orange, raw)[1]) == (0, 0)


def test_raw_vectors_do_not_meet(page):
    out, centres, sizes, rotations = page
    _orange, blue = readme_lines(out["readme"])
    stray, missed = segment_errors(blue, corrected_segments(out["readme"], centres, sizes, rotations))
    print(f"raw vectors: {stray} px drawn off the box-centre lines, {missed} points of them missed")
    assert stray > 300 and missed > 300, (stray, missed)


@pytest.mark.parametrize("control", sorted(CONTROLS))
def test_a_wrong_frame_channel_visibly_fails_to_converge(page, control):
    out, centres, sizes, rotations = page
    shot = out[control]
    stray, missed = segment_errors(drawn(shot), corrected_segments(shot, centres, sizes, rotations))
    print(f"{control}: {stray} px drawn off the box-centre lines, {missed} points of them missed")
    assert stray > 300 and missed > 300, (stray, missed)


def test_the_view_refuses_what_it_cannot_read_and_adds_nothing(page):
    out = page[0]
    assert out["refusal"].startswith("boxmarch: boxmarchDecodeVectors needs a THREE.Mesh")
    assert out["no-channels"] == ["boxmarch: the geometry has no NORMAL (export with the GLTF preset)", 0]
