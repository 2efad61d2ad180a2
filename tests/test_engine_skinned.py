"""Skinned export (issue 13): a 3-bone rig carrying 36 boxes of distinct sizes and rest rotations,
each rigidly weighted to its bone (tests/engine_scene.py), baked at rest and exported with the
GLTF preset (NORMAL_FRAME: the frame rides in NORMAL + TANGENT, which skinning turns). The .glb
goes unmodified into three.js's GLTFLoader as a SkinnedMesh, in r111 (WebGL 1) and r180 (WebGL 2);
the page turns each joint 40 degrees and the shipped material (``skinning: true``, which r111 and
r180 read; r180's is the RawShaderMaterial declaring its depth, drawing bit for bit the
ShaderMaterial's picture) raymarches a box at 0.6 of each box's half-extents. The pixels must cover
the posed boxes' silhouettes within 1 px, the posed boxes coming from the test's own forward
kinematics of the rest boxes (engine_scene.posed_rig_boxes); so must the same file drawn by the
one-call loader (loadBoxmarch). Negative control: the same render with the rest-pose frame (what
a frame in UV maps delivers, CLASSIC or UV_FRAME: no skinning turns it) must fail the check. Then
the same file read back without three.js, skinned with the glTF specification's formula in NumPy,
decodes each vertex's posed box centre within 1e-5 of its half-extent."""
import pathlib

import numpy as np
import pytest

from tests.conftest import empty_scene
from tests.engine_scene import (
    RIG_TURN_ANGLE,
    RIG_TURN_AXES,
    TO_Y_UP,
    axis_turn,
    box_of_vertex,
    decode_normal_frame,
    frame_and_size_errors,
    posed_rig_boxes,
    rig_boxes,
    silhouettes,
    skinned_scene,
)
from tests.engines import coverage_mismatch, godot3, threejs
from tests.gltf_reader import node_globals, read_glb, read_skin
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Chromium and Godot 3 renders of skinned exports

W, H = 400, 300
# Both cameras look at the middle of the posed chain (glTF frame), about 9 units away.
SIDE = {"position": [8.9, 4.35, -2.2], "target": [0.9, 1.85, 1.8], "fov": 42, "near": 1.0, "far": 40}
TOP = {"position": [-1.1, 10.85, 3.3], "target": [0.9, 1.85, 1.8], "fov": 42, "near": 1.0, "far": 40}
INNER = 0.6
BOX_MAP = "return sd_box(p, 0.6 * box_half);"
# The negative control: the frame as the vertex carries it at rest (attributes normal, tangent),
# not the skinned one: what a layout with the frame in UV maps gives the shader.
REST_FRAME = ("bmObjPos = transformed;", "objectNormal = normal; axisX = tangent.xyz; bmObjPos = transformed;")


@pytest.fixture(scope="module")
def exported(bpy_module, tmp_path_factory):
    from boxmarch.export import scene

    ob, rig = skinned_scene(empty_scene(bpy_module))
    # Posed in Blender: the file must hold the rest geometry and bind pose all the same.
    rig.pose.bones["bone1"].rotation_quaternion = (0.8, 0.6, 0.0, 0.0)
    pose = tuple(rig.pose.bones["bone1"].rotation_quaternion)
    path = tmp_path_factory.mktemp("skinned") / "skinned.glb"
    report = scene.export_objects(bpy_module.context, [ob], "GLTF", str(path))
    assert rig.data.pose_position == "POSE" and tuple(rig.pose.bones["bone1"].rotation_quaternion) == pose
    return path, report


def bone_turns():
    """The pose for the page: each bone's world axis in glTF's frame."""
    return {f"bone{k}": TO_Y_UP @ axis for k, axis in enumerate(RIG_TURN_AXES)}


def setup_js(frame_tamper=None, angle=RIG_TURN_ANGLE):
    tamper = ""
    if frame_tamper:
        old, new = frame_tamper
        tamper = (f"if (m.vertexShader.indexOf({old!r}) < 0) throw new Error('no {old} in the vertex shader');"
                  f"m.vertexShader = m.vertexShader.replace({old!r}, {new!r});")
    return (threejs.pose_bones_js(bone_turns(), angle)
            + "var skinned = 0; gltf.scene.traverse(function (o) { if (!o.isSkinnedMesh) return; skinned++;"
            + " o.frustumCulled = false;"  # its bounding sphere is the rest pose's
            + f" var m = createBoxmarchMaterial(THREE, {{map: {BOX_MAP!r}, color: new THREE.Color(1, 1, 1),"
            + " maxSteps: 256, skinning: true});" + tamper + " useBoxmarchMaterial(THREE, o, m); });"
            + " if (skinned !== 1) throw new Error(skinned + ' skinned meshes');")


def loader_setup(declare_depth=True):
    """The file as loadBoxmarch loads it from skinned.glb (and skinned.boxmarch.json), in place of
    the page's own parse, then posed: no skinning flag given, the loader sets the material per mesh
    (``declare_depth`` False: the ShaderMaterial on r163+ too)."""
    return ("scene.remove(gltf.scene);"
            f" gltf = await loadBoxmarch(THREE, GLTFLoader, 'skinned.glb', {{map: {BOX_MAP!r},"
            f" color: new THREE.Color(1, 1, 1), maxSteps: 256, declareDepth: {str(declare_depth).lower()}}});"
            " scene.add(gltf.scene);"
            " if (gltf.meshes.length !== 1 || !gltf.meshes[0].isSkinnedMesh) throw new Error('not one SkinnedMesh');"
            " gltf.meshes[0].frustumCulled = false;\n" + threejs.pose_bones_js(bone_turns(), RIG_TURN_ANGLE))


# A SkinnedMesh given a material made without skinning: the error's message, or 'no error'.
UNSKINNED_MATERIAL_JOB = """function (gltf) {
  var mesh = null;
  gltf.scene.traverse(function (o) { if (o.isSkinnedMesh) mesh = o; });
  var before = mesh.material;
  try { useBoxmarchMaterial(THREE, mesh, createBoxmarchMaterial(THREE, {})); } catch (e) {
    return mesh.material === before ? String(e.message) : 'changed the mesh: ' + e.message;
  }
  return 'no error';
}"""


def posed_silhouettes(shot):
    centres, sizes, _rotations, _bones = rig_boxes()
    posed_centres, posed_rotations = posed_rig_boxes()
    return silhouettes(shot, posed_centres, INNER * sizes, posed_rotations, TO_Y_UP)


def covered(shot):
    return shot.pixels[..., 3] > 0


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def shots(request, exported):
    """One page per release: {"side", "top", "rest-frame" (SIDE), "loader" (SIDE)} -> Shot."""
    release = request.param
    need(threejs.available(release))
    glb = exported[0].read_bytes()
    jobs = {"side": setup_js(), "top": setup_js(), "rest-frame": setup_js(REST_FRAME), "loader": loader_setup(),
            "loader-undeclared": loader_setup(declare_depth=False)}
    cameras = {"side": SIDE, "top": TOP, "rest-frame": SIDE, "loader": SIDE, "loader-undeclared": SIDE}
    files = {"skinned.glb": glb, "skinned.boxmarch.json": exported[0].with_suffix(".boxmarch.json").read_bytes()}
    renders = [threejs.render_job(js, W, H, cameras[k]) for k, js in jobs.items()]
    results = threejs.run_jobs(glb, renders + [UNSKINNED_MATERIAL_JOB], threejs.shipped_material(release), release, files)
    return dict(zip([*jobs, "unskinned-material"], results), release=release)


def test_skinned_export_holds_the_skin_at_rest_and_says_so(exported):
    path, report = exported
    assert report["layout"] == "NORMAL_FRAME"
    assert report["skinned"] == {"Skinned": {"armature": "Skinned-rig", "bones": ["bone0", "bone1", "bone2"]}}
    assert report["meshes"][0]["skin"]["non_rigid_boxes"] == 0
    assert any("the export uses the rest geometry" in w for w in report["warnings"])
    (mesh,) = read_glb(path)
    (primitive,) = mesh["primitives"]
    centres, sizes, rotations, bone_of_box = rig_boxes()
    box = box_of_vertex(primitive["POSITION"], centres, sizes, rotations, TO_Y_UP)  # the rest geometry
    skin = read_skin(path)
    joint_names = [skin["node_names"][j] for j in skin["joints"]]
    joints, weights = primitive["JOINTS_0"].astype(int), primitive["WEIGHTS_0"]
    # every vertex wholly on its box's bone
    strongest = np.array(joint_names)[joints[np.arange(len(joints)), weights.argmax(axis=1)]]
    assert list(strongest) == [f"bone{k}" for k in bone_of_box[box]]
    assert np.allclose(weights.max(axis=1), 1.0) and np.allclose(weights.sum(axis=1), 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("view", ["side", "top", "loader"])
def test_threejs_raymarches_each_box_where_the_posed_bone_carries_it(shots, view):
    shot = shots[view]
    expected = posed_silhouettes(shot)
    for polygon in expected:  # every box in the picture, none clipped by its edge
        assert polygon.min() > 0 and polygon[:, 0].max() < W and polygon[:, 1].max() < H
    mismatch = coverage_mismatch(covered(shot), expected)
    assert mismatch is None, mismatch
    assert covered(shot).sum() > 1500


def test_threejs_raw_material_draws_the_shader_materials_posed_picture(shots):
    """r180's default RawShaderMaterial (layout(depth_greater), USE_SKINNING defined itself) and
    the ShaderMaterial (declareDepth false) draw the posed rig bit for bit alike."""
    assert covered(shots["loader"]).sum() > 1500
    assert np.array_equal(shots["loader-undeclared"].pixels, shots["loader"].pixels)


def test_threejs_refuses_a_material_made_without_skinning_on_a_skinned_mesh(shots):
    """r111 and r180 read the skinning flag: a mismatch is refused, the mesh left as it was."""
    assert shots["unskinned-material"] == (f"boxmarch: a SkinnedMesh needs createBoxmarchMaterial(THREE, "
                                           f"{{skinning: true}}) on three.js r{threejs.RELEASES[shots['release']].revision}")


@pytest.mark.slow
def test_threejs_rest_frame_fails_the_posed_check(shots):
    shot = shots["rest-frame"]
    assert covered(shot).sum() > 1500  # it drew, in the wrong places
    assert coverage_mismatch(covered(shot), posed_silhouettes(shot)) is not None


def gltf_pose_skinning(path):
    """(positions, normals, tangents) of the file's skinned mesh under the pose, computed with
    the glTF 2.0 specification's skinning (section 3.7.3): joint matrix = the joint node's global
    transform x its inverse bind matrix, blended by WEIGHTS_0 over JOINTS_0; normals and
    tangents by the same matrices' 3 x 3 part (rigid joints here). The pose turns each bone's
    local rotation as pose_bones_js does in the page."""
    skin = read_skin(path)
    turns = {name: axis / np.linalg.norm(axis) for name, axis in bone_turns().items()}
    local = skin["local"].copy()
    for node, name in enumerate(skin["node_names"]):
        if name in turns:
            rest_rotation = skin["global"][node][:3, :3]
            rest_rotation = rest_rotation / np.linalg.norm(rest_rotation, axis=0)  # without the scale
            turn = np.eye(4)
            turn[:3, :3] = axis_turn(rest_rotation.T @ turns[name], RIG_TURN_ANGLE)  # axis in the bone's frame
            local[node] = local[node] @ turn
    posed_global = node_globals(local, skin["parent"])
    joint_matrices = np.array([posed_global[j] @ ibm for j, ibm in zip(skin["joints"], skin["inverse_bind"])])
    (mesh,) = read_glb(path)
    (p,) = mesh["primitives"]
    blend = np.einsum("nk,nkij->nij", p["WEIGHTS_0"], joint_matrices[p["JOINTS_0"].astype(int)])
    positions = np.einsum("nij,nj->ni", blend[:, :3, :3], p["POSITION"]) + blend[:, :3, 3]
    normals = np.einsum("nij,nj->ni", blend[:, :3, :3], p["NORMAL"])
    tangents = np.concatenate([np.einsum("nij,nj->ni", blend[:, :3, :3], p["TANGENT"][:, :3]), p["TANGENT"][:, 3:]], 1)
    return p, positions, normals, tangents


def test_gltf_round_trip_decodes_the_posed_boxes(exported):
    path, _report = exported
    p, positions, normals, tangents = gltf_pose_skinning(path)
    centres, sizes, rotations, _bones = rig_boxes()
    box = box_of_vertex(p["POSITION"], centres, sizes, rotations, TO_Y_UP)
    offset = np.concatenate([p["TEXCOORD_1"], p["TEXCOORD_2"][:, :1]], axis=1)
    half = np.concatenate([p["TEXCOORD_3"], p["TEXCOORD_4"][:, :1]], axis=1)
    origins, axes, half = decode_normal_frame(positions, normals, tangents, offset, half)
    posed_centres, posed_rotations = posed_rig_boxes()
    errors = frame_and_size_errors(origins, axes, half, box, posed_centres, sizes, posed_rotations, TO_Y_UP)
    assert errors[0] < 1e-5 and errors[1] < 1e-6 and errors[2] < 1e-5, errors
    # Negative control: the rest frame (no skinning of NORMAL / TANGENT) misses the posed centres.
    rest_origins, _axes, _half = decode_normal_frame(positions, p["NORMAL"], p["TANGENT"], offset, half)
    rest_errors = frame_and_size_errors(rest_origins, axes, half, box, posed_centres, sizes, posed_rotations, TO_Y_UP)
    assert rest_errors[0] > 0.1, rest_errors


def test_report_counts_boxes_whose_vertices_blend_bones_differently(blender, tmp_path):
    """Box 0's vertices 0-3 keep 0.7 on bone0 and take 0.3 of bone1: that box is no longer carried
    rigidly (docs/ACCURACY.md measures what it costs), and the report says so."""
    from boxmarch.export import scene

    ob, _rig = skinned_scene(blender)
    ob.vertex_groups["bone0"].add([0, 1, 2, 3], 0.7, "REPLACE")
    ob.vertex_groups["bone1"].add([0, 1, 2, 3], 0.3, "REPLACE")
    report = scene.export_objects(blender.context, [ob], "GLTF", str(tmp_path / "blended.glb"))
    skin = report["meshes"][0]["skin"]
    assert skin["non_rigid_boxes"] == 1 and abs(skin["worst_weight_spread"] - 0.3) < 1e-6
    assert any("1 of 36 boxes have vertices with different bone weights (up to 0.3 apart)" in w
               for w in report["warnings"])


def godot3_import_skinned(context, ob, folder):
    """The rig's mesh object ``ob`` (skinned_scene) exported with the GODOT3 preset into the
    existing ``folder`` and imported unmodified by Godot 3.2 (compression off, as the report
    asks): the project's path."""
    from boxmarch.export import scene

    path = pathlib.Path(folder) / "skinned.glb"
    report = scene.export_objects(context, [ob], "GODOT3", str(path))
    assert report["layout"] == "NORMAL_COLOR" and report["skinned"][ob.name]["bones"] == ["bone0", "bone1", "bone2"]
    project = pathlib.Path(folder) / "project"
    godot3.import_gltf(path.read_bytes(), str(project), compress=False,
                       extra_files={"model.boxes.tres": (pathlib.Path(folder) / "skinned.boxes.tres").read_bytes()})
    return str(project)


def godot3_posed_shot(project, frame_code=None):
    """Godot 3 draws the imported rig posed (each joint turned 40 degrees by Skeleton.set_bone_pose)
    with the shipped shader raymarching a box at 0.6 of each half-extent (its frame lines replaced
    by ``frame_code`` if given), from SIDE. Returns (shot, covered mask)."""
    # Godot 3.2's glTF importer renames the joints bone0.. to bone_0.. (a digit after a letter
    # gets an underscore), and the Skeleton's bones carry those names.
    turns = {name.replace("bone", "bone_"): axis for name, axis in bone_turns().items()}
    code = godot3.shipped_shader("return sd_box(p, 0.6 * h);", frame_code)
    shot = godot3.render(project, code, width=W, height=H, camera=SIDE,
                         uniforms={"box_table": "res://model.boxes.tres", "max_steps": 256},
                         bone_turns=turns, turn_angle=RIG_TURN_ANGLE)
    return shot, shot.pixels[..., :3].max(axis=2) > 20


@pytest.mark.slow
def test_godot3_raymarches_each_box_where_the_posed_bone_carries_it(blender, tmp_path):
    """The same rig through the GODOT3 preset (NORMAL_COLOR: frame in NORMAL + TANGENT, offsets
    in the colour, half-extents in the box table) in Godot 3.2, whose skinning folds the blended
    bone matrix into the vertex stage's WORLD_MATRIX: the shipped shader carries its frame
    through it. The pixels must cover the posed boxes' silhouettes within 1 px; the shader with
    its frame taken as the vertex carries it at rest (no skinning) must fail."""
    need(godot3.available())
    ob, _rig = skinned_scene(blender)
    project = godot3_import_skinned(blender.context, ob, tmp_path)
    shot, covered_px = godot3_posed_shot(project)
    mismatch = coverage_mismatch(covered_px, posed_silhouettes(shot))
    assert mismatch is None, mismatch
    assert covered_px.sum() > 1500
    rest_shot, rest_covered = godot3_posed_shot(project, godot3.REST_FRAME)
    assert rest_covered.sum() > 1500  # it drew, in the wrong places
    assert coverage_mismatch(rest_covered, posed_silhouettes(rest_shot)) is not None
