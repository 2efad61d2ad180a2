"""boxmarchEyeMayBeInABox (shaders/threejs/: whether useBoxmarchEyeBox and the visibility passes
draw the box holding the eye this frame; where it says no, that draw and its program are skipped):
on the seeded meshes of test_threejs_sealed_triangles (frames with w = -1 among them, indexed and
not), every eye inside a box, or within the vertex stage's margin of one (BM_EYE_BOX_ONLY: 1e-3 of
its largest half-extent), must be answered yes, judged in float64 by each box's own rotation and
half-extents; eyes 5 % beyond every box's bounding sphere must be answered no (the skip happens);
an orthographic camera's eye (w 0) no; a box whose decoded sphere is NaN yes. One node process."""
import json
import shutil
import subprocess

import numpy as np

from boxmarch.formats import shader_sources
from tests.helpers.tools import need
from tests.test_threejs_sealed_triangles import NODE_GEOMETRY_JS, mesh

NODE_JS = r"""
const vm = require('vm');
const fs = require('fs');
vm.runInThisContext(fs.readFileSync(process.argv[1], 'utf8'));
""" + NODE_GEOMETRY_JS + r"""
const cases = JSON.parse(fs.readFileSync(0, 'utf8'));
console.log(JSON.stringify(cases.map((m) => {
  const geometry = geometryOf(m);
  if (m.nanBox) {  // the first corner's box: its half-extent x NaN at every vertex (JSON has no NaN)
    const number = geometry.getAttribute('bmOffsetZIndex'), id = number.getY(m.index ? m.index[0] : 0);
    for (let v = 0; v < number.count; v++) if (number.getY(v) === id) geometry.getAttribute('bmHalfXY').array[2 * v] = NaN;
  }
  const spheres = boxmarchBoxSpheres(geometry);
  return m.eyes.map((e) => boxmarchEyeMayBeInABox(spheres, { x: e[0], y: e[1], z: e[2], w: e[3] }));
})));
"""


def run(cases):
    node = shutil.which("node") or shutil.which("nodejs")
    need(None if node else "node is not installed (apt-get install nodejs)")
    material = shader_sources.shader_dir() / "threejs" / "boxmarch.js"
    proc = subprocess.run([node, "-e", NODE_JS, str(material)], input=json.dumps(cases), capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout)


def eyes_near_boxes(boxes, rng):
    """(eyes, must): eyes inside or at the margin of the whole boxes (must be True) and 5 % beyond
    every box's bounding sphere (must be False), each (x, y, z, 1)."""
    whole = [b for b in boxes if b["spoil"] != "smaller"]  # a smaller shape's corners disagree on its origin
    eyes, must = [], []
    for b in whole:
        h = b["half"]
        for local in (rng.uniform(-1.0, 1.0, (6, 3)) * h).tolist() + [(h + 1e-3 * h.max()) * [1, -1, 1]]:
            eyes.append(b["centre"] + b["rotation"] @ np.array(local))
            must.append(True)
    far = rng.uniform(-9.0, 9.0, (400, 3))
    reach = np.array([[*b["centre"], 1.05 * np.linalg.norm(b["half"])] for b in boxes])
    clear = (np.linalg.norm(far[:, None, :] - reach[None, :, :3], axis=2) > reach[None, :, 3]).all(axis=1)
    eyes += list(far[clear])
    must += [False] * int(clear.sum())
    return [list(e) + [1.0] for e in eyes], must


def test_every_eye_in_a_box_draws_it_and_eyes_clear_of_the_boxes_skip_it():
    cases, musts = [], []
    for seed in range(6):
        built, _sealed, corners = mesh(seed, indexed=seed % 2 == 0)
        eyes, must = eyes_near_boxes(corners["boxes"], np.random.default_rng([37, seed]))
        cases.append(dict(built, eyes=eyes))
        musts.append(must)
    for seed, (answers, must) in enumerate(zip(run(cases), musts)):
        answers, must = np.array(answers), np.array(must)
        assert answers[must].all(), f"seed {seed}: {int((~answers[must]).sum())} eyes in a box answered no"
        assert not answers[~must].any(), f"seed {seed}: {int(answers[~must].sum())} eyes clear of every box answered yes"
        assert must.sum() > 100 and (~must).sum() > 20, (seed, int(must.sum()), int((~must).sum()))


def test_an_orthographic_eye_skips_and_a_nan_box_draws():
    built, _sealed, corners = mesh(0)
    inside = corners["boxes"][0]["centre"].tolist()
    far = (corners["centre"][0] + 100.0).tolist()  # far from every box: only a NaN sphere may answer yes
    answers = run([dict(built, eyes=[inside + [0.0], inside + [1.0], far + [1.0]]),
                   dict(built, eyes=[far + [1.0]], nanBox=True)])
    assert answers == [[False, True, False], [True]], answers
