"""The differential battery of the cuts that claim to change no pixel (docs/BENCHMARKS.md, "Cuts
that change no pixel"): seeded random scenes a user might make and a hostile one would, drawn by
the Blender preview (bpy module, llvmpipe) and by three.js r111 and r180 (headless Chromium,
SwiftShader), each with a cut and without (plain); every pixel a cut changes must be one the plain
march leaves unresolved: drawn again by both with a large step budget, the two agree there, or
(three.js) plain drawn with the opposite depth-tie rule draws the cut's colour there (a pixel all
three draw).

A cut is one entry of PREVIEW_CUTS or THREEJS_CUTS (its switches against the plain ones): adding
a cut is adding its line there. tests/test_cut_battery.py runs it in the test tiers and
bench/cut_battery.py runs thousands of scenes and prints the table.

The scenes (:func:`scene`): 1 to 3 objects of 4 to 80 boxes each at random rotations (or none),
sizes spread over two decades inside a scene and the whole scene scaled by 1e-3 to 1e3, aspect
ratios up to 100:1:1, nested boxes (one inside another, same frame) and coincident ones (a box
twice), flat boxes (one size 1e-4 of the others), open boxes (a face deleted) and boxes turned
inside out (faces wound inward); objects turned, scaled (unevenly too), mirrored (a negative
scale) or sheared (a child turned under a parent scaled unevenly), their vertices up to 1e4 units
from the object origin (the object moved back by as much) and the whole scene up to 1e4 units
from the world origin; a perspective or orthographic camera looking through the scene from
outside, from inside a box, or with its near plane cutting the boxes in front; every preset
(core.SDF_PRESETS) and per-box shapes (each box a random preset id), quality 1, 0.5 or 0.25.
"""
import json
import math
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np

from boxmarch import core, scenes
from tests.engine_scene import TO_Y_UP

W, H = 96, 72
HIGH_STEPS = 512  # the most either renderer takes (properties.py max_steps, three.js maxSteps)
SCRIPT = Path(__file__).resolve().parents[1] / "blender_scripts" / "cut_battery_preview.py"
PER_BOX = "PER_BOX"
SHAPES = (*core.SDF_PRESETS, PER_BOX)
QUALITIES = (1.0, 0.5, 0.25)

# The preview's switches (module attributes set by the Blender script): plain draws every face of
# every box and marches every fragment; each cut turns on its own. The thresholds (MIN_LAYERS,
# MIN_OVERDRAW) are set to 0 in every configuration, so each cut runs on every scene whatever its depth.
PREVIEW_PLAIN = {"draw.CULL_BACK_FACES": False, "occlusion.ENABLED": False, "resolve.ENABLED": False}
PREVIEW_CUTS = {
    "culling": {"draw.CULL_BACK_FACES": True},
    "pre-pass": {"occlusion.ENABLED": True},
    "resolved": {"occlusion.ENABLED": True, "resolve.ENABLED": True},
    "default": {"draw.CULL_BACK_FACES": True, "occlusion.ENABLED": True, "resolve.ENABLED": True},
}
# three.js: loadBoxmarch's options as given (each left out takes the loader's default: culling and
# the pre-pass on); plain turns both off.
THREEJS_PLAIN = {"occluders": False, "cullBackFaces": False}
THREEJS_CUTS = {
    "culling": {"occluders": False},
    "pre-pass": {"cullBackFaces": False},
    "visibility": {"visibilityPass": True},
    "default": {},
}
RENDERERS = ("preview", "r111", "r180")
PAGE_TIMEOUT_S = 600  # a three.js page of many scenes on a busy machine

# Tolerances at the large step budget, where plain and cut must agree on a pixel the cut changed:
# the same coverage; colour within COLOUR_TOLERANCE on every channel (both marches converge on the
# same surface point to the hit epsilon; the shade is a function of the normal there, which moves
# by much less than 1/255 over that distance except across an edge); window depth that puts the
# two hits within half a pixel's footprint of each other along the ray (the same surface to
# sub-pixel precision: a hit on another box lies farther than that).
COLOUR_TOLERANCE = 4.0 / 255.0


def _rotation(rng, turned=True):
    return scenes.random_rotations(1, rng)[0] if turned else np.eye(3)


def _object(rng, scale, shape, hostile):
    """One object's spec: boxes in its mesh, its transform, what is hostile about it (nothing but
    its rotations and sizes unless ``hostile``)."""
    traits = []
    count = int(rng.integers(4, 81))
    spread = scale * rng.uniform(0.5, 2.0)
    centres = rng.uniform(-spread, spread, (count, 3))
    sizes = scale * rng.uniform(0.1, 0.6, (count, 1)) * 10.0 ** rng.uniform(-1, 1, (count, 1)) * np.ones((1, 3))
    if rng.random() < 0.4:
        traits.append("long thin")
        aspect = 10.0 ** rng.uniform(0, 2, count)  # up to 100:1:1
        axis = rng.integers(0, 3, count)
        sizes[np.arange(count), axis] *= np.sqrt(aspect)
        sizes /= np.sqrt(np.sqrt(aspect))[:, None]
    else:
        sizes *= rng.uniform(0.5, 1.5, (count, 3))  # boxes, not cubes
    turned = rng.random() < 0.8
    if not turned:
        traits.append("axis-aligned")
    rotations = scenes.random_rotations(count, rng) if turned else np.tile(np.eye(3), (count, 1, 1))
    if hostile and rng.random() < 0.25:
        traits.append("nested")
        for k in rng.choice(count, max(1, count // 5), replace=False):
            centres = np.vstack([centres, centres[k]])
            sizes = np.vstack([sizes, sizes[k] * rng.uniform(0.3, 0.8)])
            rotations = np.concatenate([rotations, rotations[k:k + 1]])
    if hostile and rng.random() < 0.2:
        traits.append("coincident")
        k = rng.choice(len(centres), max(1, len(centres) // 8), replace=False)
        centres, sizes, rotations = np.vstack([centres, centres[k]]), np.vstack([sizes, sizes[k]]), \
            np.concatenate([rotations, rotations[k]])
    count = len(centres)
    if hostile and rng.random() < 0.15:
        traits.append("flat")
        k = rng.choice(count, max(1, count // 6), replace=False)
        sizes[k, rng.integers(0, 3)] = 1e-4 * sizes[k].max(axis=1)
    open_boxes = rng.choice(count, max(1, count // 6), replace=False).tolist() if hostile and rng.random() < 0.2 else []
    if open_boxes:
        traits.append("open")
    inside_out = rng.choice(count, max(1, count // 6), replace=False).tolist() if hostile and rng.random() < 0.15 else []
    if inside_out:
        traits.append("inside-out")
    offset = np.zeros(3)
    if hostile and rng.random() < 0.25:
        traits.append("vertices far from the origin")
        direction = rng.normal(size=3)
        offset = direction / np.linalg.norm(direction) * 10.0 ** rng.uniform(1, 4)
    rotation = _rotation(rng, rng.random() < 0.7)
    object_scale = np.full(3, rng.uniform(0.5, 2.0))
    if hostile and rng.random() < 0.25:
        traits.append("non-uniform scale")
        object_scale = rng.uniform(0.3, 3.0, 3)
    if hostile and rng.random() < 0.2:
        traits.append("mirrored")
        object_scale[rng.integers(0, 3)] *= -1.0
    parent_scale = np.ones(3)
    if hostile and rng.random() < 0.15:
        traits.append("sheared")
        parent_scale = rng.uniform(0.4, 2.5, 3)
        rotation = _rotation(rng)  # turned under the uneven parent: sheared in the world
    shapes = rng.integers(0, len(core.SDF_PRESETS), count).tolist() if shape == PER_BOX else None
    return {"centres": centres.tolist(), "sizes": sizes.tolist(), "rotations": rotations.tolist(),
            "offset": offset.tolist(), "rotation": rotation.tolist(), "scale": object_scale.tolist(),
            "parent_scale": parent_scale.tolist(), "open": [int(k) for k in open_boxes],
            "inside_out": [int(k) for k in inside_out], "shapes": shapes, "traits": traits}


def object_matrix(spec, place):
    """The object's matrix_world (Blender's frame), float64: the parent's scale times the object's
    translation, rotation and scale, its location chosen so that the boxes (its mesh holds them
    moved by ``offset``) lie around ``place``."""
    linear = np.diag(spec["parent_scale"]) @ np.asarray(spec["rotation"]) @ np.diag(spec["scale"])
    matrix = np.eye(4)
    matrix[:3, :3] = linear
    matrix[:3, 3] = np.asarray(place) - linear @ np.asarray(spec["offset"])
    return matrix


def object_location(spec, place):
    """The object's own location (its parent only scales): what Blender's ob.location is set to."""
    return (np.diag(1.0 / np.asarray(spec["parent_scale"])) @ object_matrix(spec, place)[:3, 3]).tolist()


def _world_boxes(spec, place):
    """(centres, reach) of the object's boxes in the world."""
    matrix = object_matrix(spec, place)
    local = np.asarray(spec["centres"]) + np.asarray(spec["offset"])
    centres = local @ matrix[:3, :3].T + matrix[:3, 3]
    reach = np.linalg.norm(np.asarray(spec["sizes"]), axis=1) / 2 * np.abs(np.linalg.svd(matrix[:3, :3])[1]).max()
    return centres, reach


def scene(seed):
    """The battery's scene of ``seed``: JSON-ready dict (objects, their placements, the camera in
    Blender's frame and in three.js's, the shape and the quality, the traits drawn)."""
    rng = np.random.default_rng([36, seed])
    scale = 10.0 ** rng.uniform(-3, 3)
    shape = SHAPES[int(rng.integers(0, len(SHAPES)))]
    quality = float(rng.choice(QUALITIES, p=(0.6, 0.2, 0.2)))  # the pre-pass runs at full quality only
    hostile = rng.random() < 0.75
    world = np.zeros(3)
    traits = [f"scale {scale:.3g}", shape, f"quality {quality}"] + ([] if hostile else ["ordinary"])
    if hostile and rng.random() < 0.2:
        direction = rng.normal(size=3)
        world = direction / np.linalg.norm(direction) * 10.0 ** rng.uniform(2, 4)
        traits.append("far from the world origin")
    objects, places, centres, reach = [], [], [], []
    for _ in range(int(rng.integers(1, 4))):
        spec = _object(rng, scale, shape, hostile)
        place = world + rng.uniform(-1, 1, 3) * scale
        c, r = _world_boxes(spec, place)
        objects.append(spec)
        places.append(place.tolist())
        centres.append(c)
        reach.append(r)
        traits += [t for t in spec["traits"] if t not in traits]
    centres, reach = np.concatenate(centres), np.concatenate(reach)
    middle = centres.mean(axis=0)
    extent = float(np.max(np.linalg.norm(centres - middle, axis=1) + reach))
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    ortho = rng.random() < 0.25
    fov = float(rng.uniform(30, 70))
    distance = extent / math.sin(math.radians(fov) / 2) * rng.uniform(0.5, 1.0)
    eye = middle + direction * distance
    near = distance * 0.01
    view = rng.random() if hostile else 1.0
    if view < 0.15:
        traits.append("eye inside a box")
        k = int(rng.integers(0, len(centres)))
        eye = centres[k] + (rng.uniform(-0.2, 0.2, 3) * reach[k] / 2)
        if np.linalg.norm(middle - eye) < 1e-3 * extent:
            middle = eye - direction * extent
        near = float(reach[k]) * 0.01
    elif view < 0.3:
        traits.append("near plane cuts boxes")
        near = distance * rng.uniform(0.5, 1.0)
    far = float(np.linalg.norm(eye - middle)) + 2.0 * extent
    traits.append("orthographic" if ortho else "perspective")
    camera = {"position": eye.tolist(), "target": middle.tolist(), "near": near, "far": far}
    if ortho:
        camera["ortho"] = extent * rng.uniform(0.5, 1.0)
    else:
        camera["fov"] = fov
    up = [0.0, 0.0, 1.0]  # Blender's camera tracks -Z to the target with world Z up
    three_camera = {k: v for k, v in camera.items() if k not in ("position", "target")}
    three_camera.update(position=(TO_Y_UP @ eye).tolist(), target=(TO_Y_UP @ middle).tolist(), up=(TO_Y_UP @ up).tolist())
    return {"seed": int(seed), "shape": shape, "quality": quality, "objects": objects, "places": places,
            "camera": camera, "three_camera": three_camera, "traits": traits}


def _camera_moved(spec, position):
    """``spec`` with its camera at ``position`` (Blender's frame), three.js's camera to match."""
    camera = spec["camera"]
    camera["position"] = np.asarray(position, np.float64).tolist()
    three = {k: v for k, v in camera.items() if k not in ("position", "target")}
    three.update(position=(TO_Y_UP @ np.asarray(camera["position"])).tolist(),
                 target=(TO_Y_UP @ np.asarray(camera["target"])).tolist(), up=(TO_Y_UP @ [0.0, 0.0, 1.0]).tolist())
    spec["three_camera"] = three
    return spec


def depth_hostile_scene(seed):
    """The battery's scene of ``seed`` made hostile to the depth rounding of the occluders
    (raymarch.glsl bm_occluder_limit, bm_depth_rounding; docs/BENCHMARKS.md): the near plane 10 to
    10,000 times nearer (depths near 1), an orthographic camera's far plane up to 1,000 times
    farther, vertices 1e3 to 1e4 units from their object's origin, axis-aligned boxes seen within
    1e-4 to 1e-1 rad of a face plane; each with its own chance, from its own random stream."""
    spec = scene(seed)
    rng = np.random.default_rng([3636, seed])
    traits, camera = spec["traits"], spec["camera"]
    if rng.random() < 0.7:
        camera["near"] *= 10.0 ** -rng.uniform(1, 4)
        traits.append("near plane far nearer")
    if "ortho" in camera and rng.random() < 0.7:
        camera["far"] *= 10.0 ** rng.uniform(0, 3)
        traits.append("far plane far farther")
    for ob in spec["objects"]:
        if rng.random() < 0.7:
            direction = rng.normal(size=3)
            ob["offset"] = (direction / np.linalg.norm(direction) * 10.0 ** rng.uniform(3, 4)).tolist()
            if "vertices 1e3-1e4 out" not in traits:
                traits.append("vertices 1e3-1e4 out")
    position = np.asarray(camera["position"])
    if rng.random() < 0.5:
        traits.append("grazing")
        for ob in spec["objects"]:
            ob["rotations"] = np.tile(np.eye(3), (len(ob["rotations"]), 1, 1)).tolist()
            ob["rotation"] = np.eye(3).tolist()
            ob["parent_scale"] = [1.0, 1.0, 1.0]
        target = np.asarray(camera["target"])
        axis = np.zeros(3)
        axis[rng.integers(0, 3)] = rng.choice([-1.0, 1.0])
        tilt = rng.normal(size=3)
        tilt -= axis * (tilt @ axis)
        direction = axis + tilt / np.linalg.norm(tilt) * 10.0 ** rng.uniform(-4, -1)
        if abs(direction[2]) > 0.999 * np.linalg.norm(direction):  # Blender's camera tracks with world Z up
            direction[0] += 1e-2
        position = target + direction / np.linalg.norm(direction) * np.linalg.norm(position - target)
    return _camera_moved(spec, position)


def mid_depth_ortho_scene(seed):
    """The battery's scene of ``seed`` seen by an orthographic camera 1e4 to 1e6 times its view's
    half-height away, its far plane twice that less the near plane, so the boxes lie at window
    depth about 0.5, their vertices around their object's origin: there an occluder's clip z is
    about 0, raymarch.glsl bm_depth_rounding pushes it back by almost nothing, and a box's face
    lies less than a float step of depth in front of its own occluder (docs/BENCHMARKS.md)."""
    spec = scene(seed)
    rng = np.random.default_rng([3737, seed])
    camera = spec["camera"]
    eye, target = np.asarray(camera["position"]), np.asarray(camera["target"])
    half_height = camera.get("ortho") or 0.5 * float(np.linalg.norm(eye - target))
    distance = half_height * 10.0 ** rng.uniform(4, 6)
    camera.pop("fov", None)
    camera["ortho"] = float(half_height)
    camera["near"] = float(distance * 10.0 ** -rng.uniform(0.5, 3))
    camera["far"] = float(2.0 * distance - camera["near"])
    for ob in spec["objects"]:
        ob["offset"] = [0.0, 0.0, 0.0]
    spec["traits"] = [t for t in spec["traits"] if t not in ("perspective", "eye inside a box", "near plane cuts boxes",
                                                             "vertices far from the origin")] + ["mid-depth orthographic"]
    return _camera_moved(spec, target + (eye - target) / np.linalg.norm(eye - target) * distance)


# Scene generators by name (bench.cut_battery --generator): seed -> the JSON-ready scene.
GENERATORS = {"battery": scene, "depth-hostile": depth_hostile_scene, "mid-depth-ortho": mid_depth_ortho_scene}


def mesh_arrays(spec):
    """(positions, edges, face_starts, face_sizes, corner_verts) of an object's mesh: its boxes
    moved by its offset (float32, as Blender stores them), the open boxes' first face deleted,
    the inside-out boxes' faces wound the other way."""
    positions, edges, face_starts, face_sizes, corner_verts = scenes.box_arrays(
        np.asarray(spec["centres"]) + np.asarray(spec["offset"]), spec["sizes"], spec["rotations"])
    faces = corner_verts.reshape(-1, 6, 4).copy()
    for k in spec["inside_out"]:
        faces[k] = faces[k, :, ::-1]
    keep = np.ones((len(faces), 6), bool)
    keep[spec["open"], 0] = False
    faces = faces[keep]
    return (positions, edges, np.arange(0, 4 * len(faces), 4, dtype=np.int32), np.full(len(faces), 4, np.int32),
            faces.reshape(-1).astype(np.int32))


# --- the comparison -------------------------------------------------------------------------------

class Found(NamedTuple):
    """What one cut did to one scene in one renderer."""

    seed: int
    renderer: str
    cut: str
    compared: int      # pixels compared
    changed: int       # pixels the cut changed at the everyday step budget
    explained: int     # of those, the ones where plain and cut agree at the large budget
    kinds: dict        # kind -> count of the unexplained ones

    @property
    def unexplained(self):
        return self.changed - self.explained

    def line(self):
        kinds = ", ".join(f"{k} {v}" for k, v in sorted(self.kinds.items()))
        return (f"seed {self.seed} {self.renderer} {self.cut}: changed {self.changed}, explained {self.explained}, "
                f"unexplained {self.unexplained}" + (f" ({kinds})" if kinds else ""))


def _colour_agrees(a, b):
    return np.all(np.abs(a[..., :3] - b[..., :3]) <= COLOUR_TOLERANCE + 1e-6, axis=-1)


def view_distance(depth, projection):
    """Distance in front of the eye of window depths (0 near plane, 1 far plane) under a GL
    ``projection``: perspective when its w row reads -z, orthographic otherwise."""
    ndc = 2.0 * np.asarray(depth, np.float64) - 1.0
    p = np.asarray(projection, np.float64)
    if p[3, 2] != 0.0:
        return p[2, 3] / (ndc + p[2, 2])
    return (p[2, 3] - ndc) / p[2, 2]


def pixel_footprint(distance, projection, height):
    """The width of one pixel at ``distance`` in front of the eye."""
    p = np.asarray(projection, np.float64)
    return (2.0 * distance if p[3, 2] != 0.0 else 2.0) / (p[1, 1] * height)


def compare(seed, renderer, cut, plain, changed_by_cut, plain_high=None, cut_high=None, projection=None,
            plain_other_tie=None):
    """Found of one cut: ``plain`` and ``changed_by_cut`` are (rgba float in [0, 1], depth or None)
    at the everyday budget; ``plain_high`` and ``cut_high`` at HIGH_STEPS (needed only where a
    pixel changed). Depth (window depth, 1 where nothing drew; None where the renderer gives none)
    needs ``projection``. ``plain_other_tie``: plain at the everyday budget with the opposite
    depth-tie rule (three.js: the first of two equally deep fragments wins, not the last); a
    changed pixel where it draws what the cut draws is one plain leaves to the order of two
    fragments at one depth (three.js seed 2387: one box's front and back face at its corner, each
    fragment's start rounded onto another face), explained too where all three draw there."""
    rgba, depth = plain
    cut_rgba, cut_depth = changed_by_cut
    # A NaN colour is never a right picture: counted changed and unexplained in either picture (kind
    # "NaN colour"), also where both hold it at the same pixel, which NaN != NaN would otherwise call
    # "wrong colour" (issue 36: preview seeds 2 and 80, a closed-form hit's zero normal).
    nan = np.isnan(rgba).any(axis=-1) | np.isnan(cut_rgba).any(axis=-1)
    changed = np.any(rgba != cut_rgba, axis=-1) | nan
    if depth is not None:
        changed |= depth != cut_depth
    total = int(changed.sum())
    if not total:
        return Found(seed, renderer, cut, changed.size, 0, 0, {})
    (high, high_depth), (cut_high_rgba, cut_high_depth) = plain_high, cut_high
    covered, cut_covered = high[..., 3] > 0, cut_high_rgba[..., 3] > 0
    agree = (covered == cut_covered) & (~covered | _colour_agrees(high, cut_high_rgba))
    if high_depth is not None:
        distance, cut_distance = view_distance(high_depth, projection), view_distance(cut_high_depth, projection)
        agree &= ~covered | (np.abs(distance - cut_distance) <= pixel_footprint(distance, projection, high.shape[0]) / 2)
    low_covered, low_cut_covered = rgba[..., 3] > 0, cut_rgba[..., 3] > 0
    if plain_other_tie is not None:
        # only where plain, the cut and the other tie all draw: a hit at the far plane ties with the
        # cleared depth, and an emptied pixel there stays the cut's (issue 36, seeds 381 and 485)
        tie_rgba = plain_other_tie[0]
        agree |= low_covered & low_cut_covered & (tie_rgba[..., 3] > 0) & _colour_agrees(tie_rgba, cut_rgba)
    bad = changed & (~agree | nan)
    kinds = {"NaN colour": int(nan.sum())} if nan.any() else {}
    kind_masks = {"emptied": low_covered & ~low_cut_covered, "drawn where plain draws nothing": ~low_covered & low_cut_covered}
    both = low_covered & low_cut_covered
    if depth is not None:
        d, cd = view_distance(depth, projection), view_distance(cut_depth, projection)
        tolerance = pixel_footprint(d, projection, rgba.shape[0]) / 2
        kind_masks["shows what lies behind"] = both & (cd > d + tolerance)
        kind_masks["draws in front"] = both & (cd < d - tolerance)
        kind_masks["wrong colour"] = both & (np.abs(cd - d) <= tolerance)
    else:
        kind_masks["another colour"] = both
    for name, mask in kind_masks.items():
        n = int((bad & mask & ~nan).sum())
        if n:
            kinds[name] = n
    return Found(seed, renderer, cut, changed.size, total, total - int(bad.sum()), kinds)


# --- the renderers ---------------------------------------------------------------------------------

def blender_env_command(script_args, tmp):
    """Runs the preview script in the bpy module (a fresh Python) on the scenes; returns its output."""
    from tests.helpers.blender_program import blender_env, python_env

    proc = subprocess.run([sys.executable, str(SCRIPT), "--", *map(str, script_args)],
                          env=python_env(blender_env(tmp)), capture_output=True, text=True, timeout=3600)
    if proc.returncode != 0:
        raise RuntimeError(f"the preview battery script failed (exit {proc.returncode}):\n"
                           + proc.stdout[-3000:] + proc.stderr[-3000:])
    return proc.stdout


def _with_meshes(spec):
    names = ("positions", "edges", "face_starts", "face_sizes", "corner_verts")
    for ob in spec["objects"]:
        ob["mesh"] = {name: array.tolist() for name, array in zip(names, mesh_arrays(ob))}
    return spec


def draw_in_blender(seeds, folder, preview=True, export=True, cuts=None, generator=scene):
    """Builds and bakes each seed's scene (``generator``'s: a value of GENERATORS) in one bpy
    process, draws it plain and with each of ``cuts`` (PREVIEW_CUTS when None) where ``preview``
    says, and exports it with the GLTF preset as ``folder``/scene_SEED.glb where ``export`` says
    (each: True, every seed; False, none; else the seeds it names); returns {seed: {"error": str}
    or the preview's arrays, empty where not drawn}. The
    boxmarch package drawn is the one this Python imports (PYTHONPATH=OTHER/addon: another
    worktree's, its shaders with it)."""
    import boxmarch

    package_parent = Path(boxmarch.__file__).resolve().parent.parent
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    specs = folder / "scenes.json"

    def chosen(which):
        return list(seeds) if which is True else sorted(which or ())

    specs.write_text(json.dumps({"scenes": [_with_meshes(generator(s)) for s in seeds], "width": W, "height": H,
                                 "high_steps": HIGH_STEPS, "preview": chosen(preview), "export": chosen(export),
                                 "plain": PREVIEW_PLAIN,
                                 "cuts": PREVIEW_CUTS if cuts is None else cuts}))
    blender_env_command([package_parent, specs, folder], folder)
    out = {}
    for seed in seeds:
        path = folder / f"scene_{seed}.npz"
        error = folder / f"scene_{seed}.error"
        out[seed] = {"error": error.read_text()} if error.exists() else dict(np.load(path)) if path.exists() else {}
    return out


def preview_findings(seed, arrays, cuts=None):
    """Found per preview cut (PREVIEW_CUTS when ``cuts`` is None) from the script's arrays
    (plain_rgba, plain_depth, CUT_rgba, ..., and the _high ones where a cut changed a pixel)."""
    found = []
    plain = (arrays["plain_rgba"], arrays["plain_depth"])
    high = (arrays.get("plain_high_rgba"), arrays.get("plain_high_depth"))
    for cut in PREVIEW_CUTS if cuts is None else cuts:
        got = (arrays[f"{cut}_rgba"], arrays[f"{cut}_depth"])
        cut_high = (arrays.get(f"{cut}_high_rgba"), arrays.get(f"{cut}_high_depth"))
        found.append(compare(seed, "preview", cut, plain, got, high, cut_high, arrays["projection"]))
    return found


def _map(shape):
    if shape == PER_BOX:
        return "return bm_sdf_by_id(box_params.x, p, box_half);"
    return f"return sdf_preset_{shape.lower()}(p, box_half);"


# The key of plain drawn with the opposite depth-tie rule (compare's plain_other_tie).
OTHER_TIE = "plain, the first of a tie"


def threejs_job(seed, spec, options, steps=None, first_of_a_tie=False):
    """The render job of one scene under loadBoxmarch ``options`` (with the scene's map and quality);
    ``first_of_a_tie``: the materials' depth test (the eye box's too) LESS, not three.js's
    LESS_EQUAL: of two fragments at one depth the first drawn wins."""
    from tests.engines import threejs

    options = dict(options, map=_map(spec["shape"]), quality=spec["quality"])
    if steps:
        options["maxSteps"] = steps
    setup = (f"scene.remove(gltf.scene); var loaded = await loadBoxmarch(THREE, GLTFLoader, 'scene_{seed}.glb', "
             f"{json.dumps(options)}); scene.add(loaded.scene);")
    if first_of_a_tie:
        setup += (" loaded.scene.traverse(function (o) { [o, o.userData.boxmarchEyeBox].forEach(function (m) {"
                  " if (m && m.material) m.material.depthFunc = THREE.LessDepth; }); });")
    return threejs.render_job(setup, W, H, spec["three_camera"])


def _rgba(shot):
    return shot.pixels.astype(np.float64) / 255.0, None


def _pages(keys, batch, generator=scene):
    """(seed, ...) keys in pages of at most ``batch`` seeds each, the seeds ordered by shape so a
    page holds few shapes: a page draws with one renderer, so it compiles each material once however
    many scenes use it (SwiftShader: about a second of CPU each), and each page costs a Chromium
    start (2.4 s)."""
    seeds = sorted(dict.fromkeys(key[0] for key in keys), key=lambda s: generator(s)["shape"])
    pages = []
    for k in range(0, len(seeds), batch):
        chosen = set(seeds[k:k + batch])
        pages.append([key for key in keys if key[0] in chosen])
    return pages


def draw_in_threejs(seeds, folder, release, batch=40, cuts=None, generator=scene):
    """Found per three.js cut (THREEJS_CUTS when ``cuts`` is None) of each seed exported into
    ``folder``: every scene drawn plain and with each cut at the material's default maxSteps, in
    pages of ``batch`` scenes; then, in as few pages, plain and each cut that changed
    a pixel again at HIGH_STEPS, and plain with the opposite depth-tie rule (OTHER_TIE).
    ``generator``: the one the seeds were exported from."""
    from tests.engines import threejs

    cuts = THREEJS_CUTS if cuts is None else cuts
    folder = Path(folder)
    configs = {"plain": THREEJS_PLAIN, **cuts}
    material = threejs.shipped_material(release)
    drawn = {}

    def draw(keys):
        for page in _pages(keys, batch, generator):
            page_seeds = list(dict.fromkeys(key[0] for key in page))
            files = {}
            for s in page_seeds:
                for name in (f"scene_{s}.glb", f"scene_{s}.boxmarch.json"):
                    files[name] = (folder / name).read_bytes()
            jobs = [threejs_job(s, generator(s), configs.get(n, THREEJS_PLAIN), steps, n == OTHER_TIE)
                    for s, n, steps in page]
            shots = threejs.run_jobs(files[f"scene_{page_seeds[0]}.glb"], jobs, material, release, files,
                                     PAGE_TIMEOUT_S)
            drawn.update((key, _rgba(shot)) for key, shot in zip(page, shots))

    seeds = [s for s in seeds if (folder / f"scene_{s}.glb").exists()]
    draw([(s, name, None) for s in seeds for name in configs])
    changed = {(s, cut) for s in seeds for cut in cuts
               if not np.array_equal(drawn[(s, "plain", None)][0], drawn[(s, cut, None)][0])}
    again = [(s, name, HIGH_STEPS) for s in seeds for name in configs
             if (s, name) in changed or (name == "plain" and any((s, cut) in changed for cut in cuts))]
    again += [(s, OTHER_TIE, None) for s in dict.fromkeys(s for s, _cut in changed)]
    if again:
        draw(again)
    return [compare(s, release, cut, drawn[(s, "plain", None)], drawn[(s, cut, None)],
                    drawn.get((s, "plain", HIGH_STEPS)), drawn.get((s, cut, HIGH_STEPS)),
                    plain_other_tie=drawn.get((s, OTHER_TIE, None)))
            for s in seeds for cut in cuts]
