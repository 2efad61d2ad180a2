"""loadBoxmarch's passes without depth writes (``visibilityPass: true``, useBoxmarchVisibility: the
depth test culls hidden fragments; the mesh's own draw is one full-screen triangle) in three.js
r111 (WebGL 1) and r180 (WebGL 2) on SwiftShader, on the pile of test_engine_threejs_occluders: the
picture and the depth buffer are those of the full march (``occluders: false``, every fragment
marching and writing its depth) to the bit, with an opaque plane through the pile (drawn by three.js
itself) composited by depth, seen from outside the pile, from inside one link's box and through
an orthographic camera, and as
drawn where the context lacks the extensions (the pre-pass path, from the composite). Negative
controls: the shade pass without its test that a hit's depth is the least one (every box that
passes the depth test shades), and the visibility pass without MIN blending (the last hit drawn
is taken for the nearest)."""
import base64
import json

import numpy as np
import pytest

from tests.engines import threejs
from tests.helpers.tools import need
from tests.test_engine_threejs_occluders import CAMERA, LINK_MAP, H, W, pile  # noqa: F401 (pile: the fixture)

pytestmark = pytest.mark.slow  # Chromium renders

# A plane through the pile's centre, facing the camera, that three.js draws with its own material.
PLANE = ("var plane = new THREE.Mesh(new THREE.PlaneGeometry(4, 4), new THREE.MeshBasicMaterial({color: 0x3366ff,"
         " side: THREE.DoubleSide})); plane.lookAt(new THREE.Vector3().fromArray(camera.position.toArray()));"
         " scene.add(plane);")
# The same view through an orthographic camera (the eye at infinity: no box holds it).
ORTHOGRAPHIC = dict(CAMERA, ortho=1.2, near=0.5, far=10)
# Tampering with the shipped passes for the negative controls (JS, ``passes`` the mesh's userData entry).
TAMPER = {
    "no equality test": ("passes.scenes.shade.children.forEach(function (m) {"
                         " var text = m.material.fragmentShader.replace('if (depth != resolved) discard;', '');"
                         " if (text === m.material.fragmentShader) throw new Error('no equality test to remove');"
                         " m.material.fragmentShader = text; m.material.needsUpdate = true; });"),
    "no MIN blending": ("passes.scenes.visibility.children.forEach(function (m) {"
                        " m.material.blending = THREE.NoBlending; m.material.needsUpdate = true; });"),
}
# Reads the depth buffer: the scene again into a target with a depth texture (32-bit float on
# WebGL 2, 24-bit on WebGL 1), copied by a full-screen pass into a float target.
DEPTH_AFTER = """var gl = renderer.getContext();
    ['WEBGL_depth_texture', 'OES_texture_float', 'WEBGL_color_buffer_float', 'EXT_color_buffer_float']
      .forEach(function (e) { gl.getExtension(e); });
    var nearest = {minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter};
    var target = new THREE.WebGLRenderTarget(W, H, nearest);
    target.depthTexture = new THREE.DepthTexture(W, H);
    target.depthTexture.type = renderer.capabilities.isWebGL2 ? THREE.FloatType : THREE.UnsignedIntType;
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    var copy = new THREE.WebGLRenderTarget(W, H, Object.assign({type: THREE.FloatType}, nearest));
    var triangle = new THREE.BufferGeometry();
    triangle.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
    var quad = new THREE.Mesh(triangle, new THREE.ShaderMaterial({
      uniforms: {depth: {value: target.depthTexture}, size: {value: new THREE.Vector2(W, H)}},
      vertexShader: 'void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }',
      fragmentShader: 'uniform sampler2D depth; uniform vec2 size;'
        + ' void main() { gl_FragColor = vec4(texture2D(depth, gl_FragCoord.xy / size).r); }'}));
    quad.frustumCulled = false;
    renderer.setRenderTarget(copy);
    renderer.render(new THREE.Scene().add(quad), camera);
    var depth = new Float32Array(W * H * 4);
    renderer.readRenderTargetPixels(copy, 0, 0, W, H, depth);
    renderer.setRenderTarget(null);
    var passes = window.bmPasses;
    return {depth: __b64(new Uint8Array(depth.buffer)), visibility: !!(passes && passes.supported)};"""


def setup_js(passes, tamper=""):
    """The pile as loadBoxmarch loads it with ``visibilityPass: true``, or the full march (``occluders: false``)."""
    options = {"map": LINK_MAP, "maxSteps": 64, "epsilon": 1e-3}
    options.update({"visibilityPass": True} if passes else {"occluders": False})
    return ("scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'pile.glb', "
            f"{json.dumps(options)}); scene.add(loaded.scene); {PLANE}"
            " var passes = window.bmPasses = loaded.meshes[0].userData.boxmarchVisibility;"
            f" if (!passes !== {json.dumps(not passes)}) throw new Error('not the passes asked for'); {tamper}")


def inside_a_link(centres):
    """A camera at the centre of the pile's link nearest its middle, looking at the pile's centre."""
    from tests.engine_scene import TO_Y_UP

    at = TO_Y_UP @ centres[np.argmin(np.linalg.norm(centres, axis=1))]
    return dict(CAMERA, position=at.tolist(), target=(at + [0.3, -0.2, -1.0]).tolist(), near=0.01)


def parse(job):
    def shot_and_depth(out):
        depth = np.frombuffer(base64.b64decode(out["depth"]), np.float32).reshape(H, W, 4)[::-1, :, 0]
        return job.parse(out), depth.copy(), out["visibility"]
    return threejs.Job(job.js, shot_and_depth)


@pytest.fixture(scope="module", params=sorted(threejs.RELEASES))
def drawn(request, pile):  # noqa: F811 (the fixture imported above)
    release = request.param
    need(threejs.available(release))
    glb, sidecar, centres, _rotations = pile
    runs = {"full": (False, "", CAMERA), "passes": (True, "", CAMERA), **{k: (True, v, CAMERA) for k, v in TAMPER.items()},
            "inside, full": (False, "", inside_a_link(centres)), "inside, passes": (True, "", inside_a_link(centres)),
            "orthographic, full": (False, "", ORTHOGRAPHIC), "orthographic, passes": (True, "", ORTHOGRAPHIC),
            "without the extensions": (True, "passes.supported = false;", CAMERA)}
    jobs = [parse(threejs.render_job(setup_js(passes, tamper), W, H, camera, DEPTH_AFTER))
            for passes, tamper, camera in runs.values()]
    # one page draws every run (36 s of r180 seen on a loaded machine): more than TIMEOUT_S's minute
    results = threejs.run_jobs(glb, jobs, threejs.shipped_material(release), release,
                               {"pile.glb": glb, "pile.boxmarch.json": sidecar}, timeout_s=240)
    return dict(zip(runs, results))


def changed(a, b):
    """Pixels whose colour differs by more than 1/255, and pixels whose depth differs at all."""
    (shot_a, depth_a, _), (shot_b, depth_b, _) = a, b
    colour = np.abs(shot_a.pixels.astype(int) - shot_b.pixels.astype(int)).max(-1) > 1
    return colour.sum(), (depth_a != depth_b).sum()


@pytest.mark.parametrize("view", ["", "inside, ", "orthographic, "])
def test_visibility_passes_draw_the_full_march_to_the_bit(drawn, view):
    full, passes = drawn[view + "full"], drawn[view + "passes"]
    assert passes[2] and not full[2]  # the passes ran (the context has the extensions)
    covered = full[0].pixels[..., 3] > 0
    links = (full[0].pixels[..., 2] < 200) & covered  # the plane is blue
    assert covered.mean() > 0.9 and links.mean() > 0.2 and (full[1] < 1).mean() > 0.9
    assert changed(full, passes) == (0, 0)


def test_a_context_without_the_extensions_draws_the_pre_pass_path(drawn):
    """What the composite draws where boxmarchVisibilitySupported said no: the marching material
    behind the pre-pass, from the composite's onBeforeRender; the same picture."""
    fallback = drawn["without the extensions"]
    assert not fallback[2] and changed(drawn["full"], fallback) == (0, 0)


@pytest.mark.parametrize("tamper", sorted(TAMPER))
def test_negative_controls_change_the_picture(drawn, tamper):
    colour, depth = changed(drawn["full"], drawn[tamper])
    assert colour > 100
