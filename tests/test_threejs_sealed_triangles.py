"""boxmarchSealedTriangles (shaders/threejs/: which boxes of a mesh may draw occluders in the
pre-pass) in typed arrays, against the implementation it replaced (string-keyed Maps: about 6 s of
CPU for 100,000 boxes; issue 36), kept here verbatim as the reference: on seeded random meshes of
boxes split per face corner as the glTF export writes them, with open boxes, a lost triangle, a
doubled face, faces wound inward, a modelled shape smaller than its box, shuffled triangles, box
numbers in any order, indexed and not, both give the same triangles. One change: a mesh with a
triangle spanning two boxes (not what the export writes) now seals no box, as
boxmarchClosedOutward refuses it. And boxmarchOccluderGeometry, which the pre-pass draws front
faces only from: the same triangles, each wound outward. One node process (no
three.js: the geometry is a stand-in with the attribute methods the functions call).
bench/bench_threejs_closed.py times both checks at 100,000 and 470,000 boxes."""
import json
import shutil
import subprocess

import numpy as np
import pytest

from boxmarch import scenes
from boxmarch.formats import shader_sources
from tests.helpers.tools import need

# The implementation replaced (template.js before the typed arrays), renamed.
OLD_SEALED_JS = r"""function oldSealedTriangles(geometry) {
  var position = geometry.getAttribute('position'), number = geometry.getAttribute('bmOffsetZIndex');
  var offset = geometry.getAttribute('bmOffsetXY'), halfXY = geometry.getAttribute('bmHalfXY');
  var halfZ = geometry.getAttribute('bmHalfZ');
  var index = geometry.index ? geometry.index.array : null, corners = index ? index.length : position.count;
  var byBox = new Map(), sealed = [];
  for (var t = 0; t + 2 < corners; t += 3) {
    var box = number.getY(index ? index[t] : t);
    if (!byBox.has(box)) byBox.set(box, []);
    byBox.get(box).push(t);
  }
  function corner(t) { return index ? index[t] : t; }
  function onFace(t) {  // whether triangle t lies on one face of its box
    var v = corner(t), h = [halfXY.getX(v), halfXY.getY(v), halfZ.getX(v)];
    var slack = h.map(function (e) { return e - BOXMARCH_SEALED_TOLERANCE * Math.max(h[0], h[1], h[2]); });
    for (var axis = 0; axis < 3; axis++) {
      var above = 0, below = 0;
      for (var k = 0; k < 3; k++) {
        var c = corner(t + k), f = axis === 0 ? offset.getX(c) : axis === 1 ? offset.getY(c) : number.getX(c);
        if (-f >= slack[axis]) above++;
        if (-f <= -slack[axis]) below++;
      }
      if (above === 3 || below === 3) return true;
    }
    return false;
  }
  byBox.forEach(function (triangles) {
    var welded = new Map(), id = [];
    triangles.forEach(function (t) {
      for (var k = 0; k < 3; k++) {
        var v = corner(t + k), key = position.getX(v) + ',' + position.getY(v) + ',' + position.getZ(v);
        if (!welded.has(key)) welded.set(key, welded.size);
        id.push(welded.get(key));
      }
    });
    var n = welded.size, uses = new Map(), closed = true;
    for (var i = 0; i < id.length; i++) {
      var a = id[i], b = id[i % 3 === 2 ? i - 2 : i + 1], edge = Math.min(a, b) * n + Math.max(a, b);
      uses.set(edge, (uses.get(edge) || 0) + 1);
    }
    uses.forEach(function (count) { if (count !== 2) closed = false; });
    if (closed && triangles.every(onFace)) Array.prototype.push.apply(sealed, triangles);
  });
  return sealed;
}
"""

# The node side's stand-in geometry (no three.js): a mesh sent as JSON (mesh()) with the attribute
# methods the shipped functions call.
NODE_GEOMETRY_JS = r"""
function attribute(values, itemSize) {
  const array = Float32Array.from(values);
  return { array: array, itemSize: itemSize, count: array.length / itemSize,
           getX: (i) => array[i * itemSize], getY: (i) => array[i * itemSize + 1], getZ: (i) => array[i * itemSize + 2],
           getW: (i) => array[i * itemSize + 3] };
}
function geometryOf(m) {
  const attributes = {};
  for (const name in m.attributes) attributes[name] = attribute(m.attributes[name][0], m.attributes[name][1]);
  return { attributes: attributes, getAttribute: (name) => attributes[name],
           index: m.index ? { array: Uint32Array.from(m.index), count: m.index.length } : null };
}
"""

NODE_JS = r"""
const vm = require('vm');
const fs = require('fs');
vm.runInThisContext(fs.readFileSync(process.argv[1], 'utf8'));
vm.runInThisContext(process.argv[2]);
""" + NODE_GEOMETRY_JS + r"""// what boxmarchOccluderGeometry builds a geometry with
const THREE = {
  BufferAttribute: function (array, itemSize) { this.array = array; this.count = array.length; this.itemSize = itemSize; },
  BufferGeometry: function () {
    this.attributes = {};
    this.setAttribute = (name, a) => { this.attributes[name] = a; return this; };
    this.setIndex = (index) => { this.index = index; return this; };
    this.getAttribute = (name) => this.attributes[name];
  }
};
const meshes = JSON.parse(fs.readFileSync(0, 'utf8'));
console.log(JSON.stringify(meshes.map((m) => {
  const geometry = geometryOf(m);
  const occluders = boxmarchOccluderGeometry(THREE, geometry);
  return { now: Array.from(boxmarchSealedTriangles(geometry)), before: oldSealedTriangles(geometry).slice().sort((a, b) => a - b),
           occluders: occluders === null ? null : occluders === geometry ? 'geometry'
             : Array.from(occluders.index.array) };
})));
"""

SIGNS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
QUADS = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 4, 7, 3]]  # outward


def mesh(seed, indexed=True):
    """A JSON-ready mesh of 40 boxes, a quarter of them spoiled one way or another, how many
    boxes are left sealed by construction, and its corners (with each box: centre, rotation, half
    extents, spoil). Each box's frame (normal, tangent with w: y is w times
    normal x tangent, bm_axis_y) is its rotation, half of them with w = -1 (y turned over, the
    box-local offsets with it)."""
    rng = np.random.default_rng([36, seed])
    count = 40
    numbers = rng.permutation(1000)[:count] * 0.5 + 3  # any order, not 0..n-1
    position, offset_xy, offset_z_index, half_xy, half_z, triangles = [], [], [], [], [], []
    normal, tangent, centres = [], [], []
    sealed, boxes = 0, []
    for b in range(count):
        h = rng.uniform(0.1, 2.0, 3)
        rotation = scenes.random_rotations(1, rng)[0]
        centre = rng.uniform(-5, 5, 3) if rng.random() < 0.9 else np.zeros(3)
        spoil = rng.choice(["none", "open", "lost triangle", "doubled face", "inward", "smaller"], p=[0.5, 0.1, 0.1, 0.1, 0.1, 0.1])
        w = rng.choice([1.0, -1.0])
        faces = []
        for quad in QUADS:
            first = len(position)
            for corner in quad:
                local = SIGNS[corner] * h
                f = -local * (0.9 if spoil == "smaller" else 1.0) * [1.0, w, 1.0]  # along (x, w y, z)
                position.append((centre + rotation @ local).tolist())
                offset_xy.append([f[0], f[1]])
                offset_z_index.append([f[2], numbers[b]])
                half_xy.append([h[0], h[1]])
                half_z.append([h[2]])
                normal.append(rotation[:, 2].tolist())
                tangent.append(rotation[:, 0].tolist() + [w])
                centres.append(centre.tolist())
            quad_triangles = [[first, first + 1, first + 2], [first, first + 2, first + 3]]
            if spoil == "inward":
                quad_triangles = [t[::-1] for t in quad_triangles]
            faces += quad_triangles
        if spoil == "open":
            del faces[0:2]
        elif spoil == "lost triangle":
            del faces[int(rng.integers(0, 12))]
        elif spoil == "doubled face":
            faces += faces[2:4]
        sealed += spoil in ("none", "inward")
        boxes.append({"centre": centre, "rotation": rotation, "half": h, "spoil": spoil})
        triangles += faces
    triangles = [triangles[k] for k in rng.permutation(len(triangles))] if seed % 2 else triangles
    index = np.array(triangles, int).reshape(-1)
    attributes = {"position": (position, 3), "bmOffsetXY": (offset_xy, 2), "bmOffsetZIndex": (offset_z_index, 2),
                  "bmHalfXY": (half_xy, 2), "bmHalfZ": (half_z, 1), "normal": (normal, 3), "tangent": (tangent, 4)}
    if not indexed:
        attributes = {name: ([values[v] for v in index], size) for name, (values, size) in attributes.items()}
    corners = {"position": np.array(position, float)[index], "centre": np.array(centres, float)[index], "boxes": boxes}
    attributes = {name: (np.ravel(values).tolist(), size) for name, (values, size) in attributes.items()}
    return {"attributes": attributes, "index": index.tolist() if indexed else None}, sealed, corners


def run(meshes):
    node = shutil.which("node") or shutil.which("nodejs")
    need(None if node else "node is not installed (apt-get install nodejs)")
    material = shader_sources.shader_dir() / "threejs" / "boxmarch.js"
    proc = subprocess.run([node, "-e", NODE_JS, str(material), OLD_SEALED_JS], input=json.dumps(meshes),
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.mark.parametrize("indexed", [True, False])
def test_sealed_triangles_are_the_ones_the_map_based_check_gave(indexed):
    built = [mesh(seed, indexed) for seed in range(6)]
    results = run([m for m, *_ in built])
    for seed, ((_, sealed, _corners), result) in enumerate(zip(built, results)):
        assert result["now"] == result["before"], f"seed {seed}"
        assert len(result["now"]) == 12 * sealed and 0 < sealed < 40, (seed, sealed)  # some sealed, some not


def test_a_triangle_spanning_two_boxes_seals_no_box():
    spanning, *_ = mesh(0)
    spanning["index"][0] = spanning["index"][-1]  # a corner of the last box's last triangle
    result = run([spanning])[0]
    assert result["now"] == [] and len(result["before"]) > 100


@pytest.mark.parametrize("indexed", [True, False])
def test_occluder_triangles_are_the_sealed_ones_wound_outward(indexed):
    """boxmarchOccluderGeometry: the pre-pass draws front faces only, so each sealed box's triangles
    come wound outward (the inward boxes' turned back; the frames with w = -1 read right), whatever
    the mesh's winding; judged by each triangle's object-space normal against its box's centre."""
    built = [mesh(seed, indexed) for seed in range(6)]
    results = run([m for m, *_ in built])
    inward_before = 0
    for seed, ((built_mesh, sealed, corners), result) in enumerate(zip(built, results)):
        drawn = np.array(result["occluders"]).reshape(-1, 3)
        first = np.array(result["now"])  # the sealed triangles' first corners, as wound in the mesh
        assert len(drawn) == len(first) == 12 * sealed, f"seed {seed}"
        vertices = np.array(built_mesh["attributes"]["position"][0]).reshape(-1, 3)
        # the centre of each vertex's box: indexed, by vertex; else the corners are the vertices
        centre_of = {}
        for corner, vertex in enumerate(built_mesh["index"] if indexed else range(len(vertices))):
            centre_of[vertex] = corners["centre"][corner]

        def outward(triangles):
            p = vertices[triangles]
            normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
            out = p.mean(axis=1) - np.array([centre_of[t[0]] for t in triangles])
            return np.einsum("ij,ij->i", normal, out) > 0

        assert outward(drawn).all(), f"seed {seed}: {int((~outward(drawn)).sum())} inward"
        as_wound = np.array(built_mesh["index"]).reshape(-1)[first[:, None] + np.arange(3)] if indexed \
            else first[:, None] + np.arange(3)
        inward_before += int((~outward(as_wound)).sum())
        assert sorted(map(sorted, drawn.tolist())) == sorted(map(sorted, as_wound.tolist())), f"seed {seed}"
    assert inward_before >= 24  # the mesh does hold inward boxes: the check can fail
