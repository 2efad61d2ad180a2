"""The differential battery of the cuts that claim to change no pixel (tests/helpers/cut_battery.py,
docs/BENCHMARKS.md "Cuts that change no pixel"): the Blender preview's back-face culling, occluder
pre-pass and resolved passes, three.js's culling, pre-pass and visibility passes, each against the
plain march on seeded random scenes; every pixel a cut changes must be one where plain and cut
agree when both march with the large step budget, or (three.js) where plain drawn with the
opposite depth-tie rule draws what the cut draws.

The slow tier runs CI_SEEDS and every seed of REGRESSIONS in each renderer; the everyday tier
checks the comparison itself on made-up pictures and that CI_SEEDS draw every trait the
generator has. ``python3 -m bench.cut_battery`` runs thousands. Another worktree's add-on and
shaders: ``PYTHONPATH=OTHER_CHECKOUT/addon python3 -m pytest -m slow tests/test_cut_battery.py``.
"""
import numpy as np
import pytest

from tests.engines import threejs
from tests.helpers import cut_battery
from tests.helpers.tools import need

# The scenes the slow tier draws in each renderer: every seed is built once (bpy), drawn by the
# preview or exported for three.js; the three.js releases draw distinct scenes (the two draw
# alike: issue 36 item 10).
CI_SEEDS = {"preview": range(0, 250), "r111": range(0, 45), "r180": range(60, 105)}
_SEED_6 = ("pre-pass, visibility and default 1 px another colour (main at 9ec7267); an ordinary LINK scene, long thin links, "
           "orthographic, scale 879: a march closing in on a link 2,000 units long at a slant stalled (epsilon 1e-4 "
           "under t's float32 step) and missed at every budget, so plain and cut showed different boxes behind")
_EDGE_ON = ("culling (and default) 1 px wrong colour (bench.cut_battery seeds 100-299 at c000917): BOX, coincident "
            "boxes, vertices far from the origin; at a box's silhouette plain's winning fragment is one of a face the "
            "rasteriser calls back-facing (seen on seed 237) whose own span calls it an entry (more of its box ahead "
            "than behind), 5e-5 window depth in front of the front face; culling dropped it, the front face showed; passes since "
            "presets hit in closed form")
_NAN = ("(closed-form hits, main at c8600c7; not the cuts': plain drew the same pixel NaN at the same depth): the "
        "box's face fragment started a rounding inside the shape (vertices far from the origin), where "
        "bm_hit_round_box took a farther piece's root with normal 0; bm_preset_hit now hits such a start at once "
        "(bm_face_hit)")
_PAST_FAR = ("(bench.cut_battery seeds 300-699 at 3bba224, closed-form hits): plain draws hits past the far plane at "
             "window depth 1.0 (clamped); the visibility pass kept 1.0, and the shade pass bounded its march at the "
             "crossing of depth 1.0 + bm_shade_margin, short of the hit, so nothing was shaded there")
_SLIVER = ("pre-pass and visibility passes 1 px emptied at (62, 55) (seeds 500-1099 at fbf929f on r180, 700-999 at "
           "7d8c73a on r111): the pre-pass wrote 0.9938747 there, nearer than plain's closed-form hit on box 51 "
           "(0.9939306), while in float64 the occluder lies 0.46 px behind that hit along the pixel's ray (the 8 "
           "pixels around read back its depth plus 1e-6); the writer was a back face (occluders drew both sides "
           "without culling, and always in the visibility passes), off every face of the occluder: a face seen "
           "nearly edge-on, its vertices snapped, its depth plane tilted, on a pixel the front face's snapped edge "
           "leaves. The occluders now draw front faces only, wound outward whatever the mesh's winding "
           "(boxmarchOccluderGeometry); CYLINDER, scale 465, quality 0.25, long thin, an ordinary scene, perspective")
_NEAR_EXIT = ("visibility passes 1 px emptied at (42, 47) (seeds 500-1099 at fbf929f on r180, 700-999 at 7d8c73a on "
              "r111): plain draws box 197 there at depth 0, a front face's hit, not from the eye, on a face cut by the "
              "near plane whose fragment came out below 0 and whose box's exit lay in front of the near plane too "
              "(the depth buffer clamps the hit to 0). The visibility pass kept that 0; the shade pass dropped the "
              "box as ending before the kept depth (its face's and exit's depths, unclamped, below 0 - margin), so "
              "nothing was shaded and the composite wrote depth 0 with an empty colour, hiding the surface behind "
              "too. Those depths are now clamped to [0, 1] as the kept one is (three.js and the preview); BOX, scale "
              "12.3, quality 0.25, long thin, coincident, inside-out, nested, open, mirrored, non-uniform scale, near "
              "plane cuts boxes, perspective")
_EDGE_ON_OCCLUDER = ("visibility passes 1 px emptied at (45, 3) (seeds 1100-1399 at a93ff06 on r180, 1000-1299 on "
                     "r111): the passes' occluders wrote 0.3437 there (read back), in front of plain's closed-form "
                     "hit on box 8 (0.3446), where in float64 the ray meets box 8's own occluder at 0.3464, on a face "
                     "at 87 degrees to the view (normal . view 0.054) whose depth changes 0.087 a pixel: the depth "
                     "plane through corners snapped to SwiftShader's 1/16-px grid is the face's a point up to 1/32 px "
                     "away, 0.0027 off. The march ended at the occluder, short of the hit. Each occluder's limit now "
                     "adds a quarter of its depth's slope (bm_occluder_limit, fwidth); CYLINDER, scale 2.6, quality 1, "
                     "far from the world origin, nested, orthographic")
_CORNER_TIE = ("culling, visibility passes and default 1 px another colour at (20, 42) (r180 2300-2599 and r111 "
               "2200-2499 at 2dfa9b6): plain drew box 85's back face's fragment there, the culled picture its "
               "front face's, at one depth (0.35637226, a tie LESS_EQUAL gives to the later); the pixel's ray "
               "passes the box's corner, where each fragment's start (float32, rounded) lay within 4e-5 of the "
               "half-extent of three faces and took a different one's normal: the front face's fragment the far "
               "face's, turned away from the eye (now the face the ray enters by: bm_face_hit), the back face's "
               "the side face's. Plain with the first of a tie winning draws the culled picture's colour there: "
               "explained (compare's plain_other_tie); BOX, scale 3.73, quality 0.5, long thin, orthographic")
_CLIPPED_SLIVER = ("culling, visibility passes and default 1 px another colour at (39, 29) (r180 3100-3499 at "
                   "55861a2; r111 3000-3499 the same): plain's winner was box 135's fragment of its -z face, "
                   "nearly edge-on (the ray 1.2 degrees off it) and cut by the near plane, which SwiftShader "
                   "rasterised 0.007 in front of that plane (gl_FragCoord.z -0.0070) with its winding reversed; "
                   "its ray enters there, so plain drew its hit at depth 0, and culling dropped the fragment (box "
                   "155 showed). A march from its face whose hit lies in front of the near plane now draws "
                   "nothing (bm_hit_depth -1: clipped, as the rasteriser clips faces); BOX, scale 1.18, quality 1, "
                   "long thin, coincident, flat, nested, open, sheared, eye inside a box, orthographic")
_SILHOUETTE_EDGE = ("culling, visibility passes and default 1 px another colour at (56, 33) (r180 3100-3499 at "
                    "55861a2; r111 3000-3499 the same): the pixel's centre lies on box 124's silhouette edge "
                    "(its ray meets the box only there: span (0, 0)); the fill rule gave the pixel to the box's "
                    "back face, not its front face (back faces 19 px, front faces 18), and plain drew that "
                    "fragment's hit at the edge while culling dropped it (box 140 showed). A back face whose ray "
                    "meets its box only on its surface is now the far side (bm_from_eye), drawn only from an "
                    "eye inside the box; BOX, scale 224, quality 0.5, long thin, axis-aligned, inside-out, non-uniform scale, "
                    "eye inside a box, orthographic")
# Seeds where a cut changed pixels that no step budget explains: (seed, renderer, what it found
# the day it was kept, main at 20bdfbf, 96 x 72). Each runs every time, in its renderer.
REGRESSIONS = [
    (3, "preview", "pre-pass 233 px (211 emptied); ROUNDED_BOX, vertices far from the origin, inside-out, flat"),
    (6, "preview", "pre-pass 141 px (102 emptied, 35 the box behind); an ordinary LINK scene, orthographic"),
    (16, "preview", "pre-pass 162 px, 151 the box behind; BOX, nested, vertices far, far from the world origin"),
    (19, "preview", "resolved passes 302 px emptied (pre-pass 1); CAPSULE, coincident, vertices far"),
    (55, "preview", "culling 903 px (826 emptied); PER_BOX, quality 0.25, mirrored, near plane cuts boxes"),
    (80, "preview", "resolved passes 252 px emptied; PER_BOX, open, inside-out, mirrored, near plane cuts boxes; "
                    "later every cut 1 px NaN colour at (27, 62), a ROUNDED_BOX id 4,600 units out " + _NAN),
    (2, "preview", "every cut 1 px NaN colour at (64, 24); ROUNDED_BOX 1,300 units out, quality 0.25, orthographic "
                   + _NAN),
    (58, "r111", "visibility 1,566 px emptied; TORUS, nested, mirrored"),
    (68, "r111", "pre-pass 4 px emptied; an ordinary CYLINDER scene"),
    (75, "r111", "pre-pass 59 px emptied; CYLINDER, inside-out, vertices far, non-uniform scale"),
    (87, "r111", "pre-pass 64 px (29 emptied, 35 another colour); an ordinary CYLINDER scene, orthographic"),
    (90, "r111", "visibility 2,251 px emptied; CAPSULE, open, coincident, mirrored"),
    (16, "r180", "pre-pass 910 px (641 emptied); BOX, nested, vertices far, far from the world origin"),
    (39, "r180", "pre-pass 15 px, visibility 1,388 px emptied; PER_BOX, mirrored"),
    (54, "r180", "pre-pass 1 px emptied; an ordinary BOX scene at scale 271"),
    (61, "r180", "visibility 2,378 px another colour; LINK, eye inside a box, mirrored, sheared"),
    (74, "r180", "visibility: all 6,912 px emptied; ROUNDED_BOX, eye inside a box, mirrored"),
    (51, "r180", "visibility 36 px emptied (cutfix, main at cf51879; hits beyond the far plane); ROUNDED_BOX, "
                 "eye inside a box, coincident, long thin"),
    (98, "r180", "pre-pass 133 px (86 emptied); ROUNDED_BOX, orthographic, sheared, open"),
    (6, "r111", _SEED_6),
    (6, "r180", _SEED_6),
    (81, "preview", "resolved passes 1 px emptied (main at 9ec7267: a hit a hair in front of the near plane, "
                    "window depth -9e-6, never kept); PER_BOX, eye inside a box, orthographic, nested, open, "
                    "inside-out, coincident"),
    (464, "preview", "resolved passes 4,242 px emptied (c000917: hits plain draws at window depth exactly 1.0, the "
                     "eye box's march writing its far side's depth at the far plane, were the no-hit value); "
                     "CYLINDER, nested, eye inside a box, perspective"),
    (184, "preview", _EDGE_ON + "; also mirrored, sheared, flat, nested, far from the world origin, perspective"),
    (195, "preview", _EDGE_ON + "; also inside-out, nested, mirrored, quality 0.25, perspective"),
    (237, "preview", _EDGE_ON + "; also non-uniform scale, orthographic"),
    (337, "preview", "culling 1 px wrong colour, the same signature (seeds 300-499 at c000917); BOX, long thin, "
                     "mirrored, sheared, vertices far, non-uniform scale, perspective"),
    (441, "preview", "culling 1 px wrong colour, the same signature; BOX, quality 0.5, long thin, non-uniform scale, "
                     "orthographic"),
    (488, "preview", "culling 1 px wrong colour, the same signature; BOX, long thin, non-uniform scale, orthographic"),
    (381, "preview", "resolved passes 5 px emptied " + _PAST_FAR + "; SPHERE, quality 0.25, scale 0.00144, long thin, "
                     "nested, coincident, inside-out, open, mirrored, vertices far, non-uniform scale, perspective"),
    (485, "preview", "resolved passes 83 px emptied " + _PAST_FAR + "; LINK, quality 0.25, scale 0.00116, long thin, "
                     "nested, vertices far, mirrored, coincident, open, inside-out, perspective"),
    (940, "preview", "culling (and default) 1 px emptied at (25, 53) (seeds 700-1199 at 050b210): plain's winning "
                     "fragment there is back-facing, not from the eye, yet its box-local ray (float32 positions 511 "
                     "units out, boxes down to 1.8e-5, under float32's step there) has more of its box ahead than "
                     "behind and hits; culling dropped it (such boxes are no longer culled: "
                     "mesh_data.CULL_MIN_STEPS); LINK, quality 0.5, scale 0.00289, nested, coincident, inside-out, "
                     "non-uniform scale, perspective"),
    (948, "preview", "every cut (and plain) 4 px NaN colour (seeds 700-1199 at 050b210): a fragment's interpolated "
                     "object position rounds to the eye (vertices 2,000 units out, eye inside a box, near plane 7e-6), "
                     "so its ray direction was 0 / 0; such a fragment now draws nothing, in every engine; BOX, long "
                     "thin, sheared, perspective"),
    (771, "preview", "culling, resolved and default 2 px wrong colour (seeds 700-1199 at 050b210): a front face's hit "
                     "and the eye box's march, which wrote its far side's depth, tied; the eye's box now writes its "
                     "hit's own depth; PER_BOX, scale 38.6, eye inside a box, nested, coincident, perspective"),
    (236, "r180", "visibility passes 1 px emptied at (34, 55) (seeds 200-299 at 927b606; r111 alike): the box's own "
                  "occluder lay 9.5e-7 of window depth in front of its face, so the passes' depth test dropped the "
                  "face; the pre-pass sized the pixel it pulls occluders in by an eighth of along the object-to-clip "
                  "matrix's y row alone, 5.6 times too small in object units across the squashed axis of this "
                  "sheared, non-uniformly scaled object (now the view-space pixel times |normalMatrix a| per axis); "
                  "BOX, quality 0.5, scale 13.6, far from the world origin, long thin, flat, open, vertices far, "
                  "sheared, nested, non-uniform scale, perspective"),
    (70, "r180", "visibility 227 px emptied (cutfix, main at cf51879; fixed then), later 2 px another colour at "
                 "(9, 90) and (10, 91) (r111 alike): a front face cut by the near plane handed its fragments "
                 "gl_FragCoord.z -8e-4 (SwiftShader); the visibility pass kept that depth unclamped, where plain's "
                 "depth buffer clamps it to 0 and LESS_EQUAL gives the tie with the eye box's hit at 0 to the eye "
                 "box, drawn last; the passes now clamp every depth to [0, 1]; CYLINDER, eye inside a box, nested, "
                 "flat, inside-out, vertices far"),
    (542, "r111", "culling and default 63 px another colour (seeds 400-699 at fbf929f), visibility passes the same "
                  "since f7684b8: a depth tie at 0 between box 43's face, cut by the near plane and clamped to 0 by "
                  "the depth buffer (and the passes), and box 37's march from the eye inside its shape, hitting at "
                  "0; plain r111 drew both in one draw, box 43 last, winning by LESS_EQUAL, while culling and the "
                  "passes drew the eye's box apart and last; now every release draws it apart (useBoxmarchMaterial), "
                  "one tie order with every cut; CAPSULE, scale 362, quality 0.25, long thin, inside-out, vertices "
                  "far, non-uniform scale, eye inside a box, perspective"),
    (795, "r180", _SLIVER),
    (795, "r111", _SLIVER),
    (851, "r180", _NEAR_EXIT),
    (851, "r111", _NEAR_EXIT),
    (1285, "r180", _EDGE_ON_OCCLUDER),
    (1285, "r111", _EDGE_ON_OCCLUDER),
    (2387, "r180", _CORNER_TIE),
    (2387, "r111", _CORNER_TIE),
    (2333, "preview", "resolved passes (and default) 11 px, 5 emptied and 6 another colour (preview 2000-2999 at "
                      "04e44ce): the eye's box covers the view; its object's vertices lie 8,000 units from the "
                      "object's origin around boxes a few millimetres across, so a fragment's ray from the eye, "
                      "rounded, heads away from the view (clip w falling) and its hits take depth 0; plain draws "
                      "the last of that tie, while the shade pass bounded the march where the ray's clip depth "
                      "crossed the kept 0 with w below 0 (bm_depth_crossing, now no bound before w rises above 0, "
                      "none where it never does), cutting off that hit; LINK, scale 0.0023, quality 1, near plane "
                      "6.2e-5, open, inside-out, long thin, axis-aligned, nested, mirrored, perspective"),
    (3188, "r180", _CLIPPED_SLIVER),
    (3188, "r111", _CLIPPED_SLIVER),
    (3369, "r180", _SILHOUETTE_EDGE),
    (3369, "r111", _SILHOUETTE_EDGE),
]

# Seeds of the depth-hostile generator (bench.cut_battery --generator depth-hostile: the near plane
# far nearer, vertices 1e3-1e4 out, grazing views) where a cut changed pixels no step budget
# explains: (seed, renderer, what it found), each drawn in its renderer in the slow tier.
_ROUNDED_SILHOUETTE = ("culling, visibility passes and default 1 px another colour at (36, 43) (r180 300-499 and "
                       "r111, at dc8602b, whose rule dropped every fragment whose ray has no chord in its box): "
                       "box 29's front-face fragment there, its start rounded (vertices 1e3-1e4 units out, boxes "
                       "a millimetre across), came out with no chord and was dropped, while its back face's, "
                       "rounded otherwise, drew it in plain; culling showed box 45. Only a back face with no "
                       "chord is dropped now (bm_from_eye's far side); PER_BOX, scale 0.00109, quality 0.25, "
                       "non-uniform scale, long thin, axis-aligned, nested, coincident, perspective")
DEPTH_HOSTILE_REGRESSIONS = [
    (138, "preview", "resolved passes 18 px emptied (main at e5a16d1): 17 px where a back face of a box the vertex "
          "stage calls clear of the eye, sent from the eye by the fragment's own test (positions 1e3 units "
          "out, the eye 5e-9 away), kept its hit at depth 0 and won, where the one-pass draw writes its face's "
          "depth; 1 px where the shade pass dropped the winner as a box ending before the kept depth, a "
          "distance inverted from that depth along a rounded ray coming out beyond its exit; PER_BOX, eye "
          "inside a box, mirrored, nested, flat, long thin, near plane 7.4e-10, vertices 1e3-1e4 out"),
    (365, "r180", _ROUNDED_SILHOUETTE),
    (365, "r111", _ROUNDED_SILHOUETTE),
]


@pytest.fixture(scope="module")
def battery(tmp_path_factory):
    """found(renderer): [Found, ...] of the renderer's CI seeds and regression seeds, drawn on first use."""
    wanted = {r: sorted(set(CI_SEEDS[r]) | {s for s, renderer, *_ in REGRESSIONS if renderer == r})
              for r in cut_battery.RENDERERS}
    seeds = sorted(set().union(*wanted.values()))
    folder = tmp_path_factory.mktemp("cut_battery")
    exported = set().union(*(wanted[r] for r in cut_battery.RENDERERS if r != "preview"))
    drawn = cut_battery.draw_in_blender(seeds, folder, preview=wanted["preview"], export=exported)
    failed = {seed: arrays["error"] for seed, arrays in drawn.items() if "error" in arrays}
    assert not failed, f"scenes that did not build or draw: {failed}"
    cache = {}

    def found(renderer):
        if renderer not in cache:
            if renderer == "preview":
                cache[renderer] = [f for s in wanted[renderer] for f in cut_battery.preview_findings(s, drawn[s])]
            else:
                need(threejs.available(renderer))
                cache[renderer] = cut_battery.draw_in_threejs(wanted[renderer], folder, renderer)
        return wanted[renderer], cache[renderer]

    return found


def unexplained(found):
    return [f.line() for f in found if f.unexplained]


@pytest.mark.slow
@pytest.mark.parametrize("renderer", cut_battery.RENDERERS)
def test_every_pixel_a_cut_changes_is_one_the_plain_march_leaves_unresolved(battery, renderer):
    seeds, results = battery(renderer)
    exported = {f.seed for f in results}
    assert len(exported) >= 0.9 * len(seeds), f"only {len(exported)} of {len(seeds)} scenes drawn"
    lines = unexplained(results)
    assert not lines, "\n".join(lines)


@pytest.mark.slow
@pytest.mark.parametrize("seed, renderer, kept", REGRESSIONS)
def test_regression_seed(battery, seed, renderer, kept):
    results = [f for f in battery(renderer)[1] if f.seed == seed]
    assert results, f"seed {seed} was not drawn in {renderer}"
    assert not unexplained(results), f"kept as: {kept}\nnow: " + "\n".join(unexplained(results))


@pytest.mark.slow
def test_depth_hostile_regression_seeds(tmp_path):
    seeds = sorted({seed for seed, _renderer, _kept in DEPTH_HOSTILE_REGRESSIONS})
    exported = sorted({seed for seed, renderer, _kept in DEPTH_HOSTILE_REGRESSIONS if renderer != "preview"})
    previewed = sorted({seed for seed, renderer, _kept in DEPTH_HOSTILE_REGRESSIONS if renderer == "preview"})
    drawn = cut_battery.draw_in_blender(seeds, tmp_path, preview=previewed, export=exported,
                                        generator=cut_battery.depth_hostile_scene)
    for seed, renderer, kept in DEPTH_HOSTILE_REGRESSIONS:
        assert "error" not in drawn[seed], f"seed {seed} did not draw: {drawn[seed]}"
        if renderer == "preview":
            assert drawn[seed], f"seed {seed} did not draw"
            found = cut_battery.preview_findings(seed, drawn[seed])
        else:
            need(threejs.available(renderer))
            found = cut_battery.draw_in_threejs([seed], tmp_path, renderer, generator=cut_battery.depth_hostile_scene)
            assert found, f"seed {seed} was not exported"
        lines = unexplained(found)
        assert not lines, f"kept as: {kept}\nnow: " + "\n".join(lines)


# --- negative controls: a cut known to be wrong must fail the battery -----------------------------

# Seeds at full quality whose shape is not the box: the box's own occluder (the whole box) covers
# what such a shape leaves open around it.
def _rounded_seeds(count):
    scenes = (cut_battery.scene(s) for s in range(1000))
    seeds = (c["seed"] for c in scenes if c["quality"] == 1.0 and c["shape"] in ("SPHERE", "CAPSULE", "TORUS")
             and "eye inside a box" not in c["traits"])
    return [next(seeds) for _ in range(count)]


@pytest.mark.slow
def test_a_cut_that_occludes_with_the_whole_box_fails_the_battery(tmp_path):
    """Negative control: the pre-pass drawing each box's BOX occluder (the whole box) for a sphere,
    capsule or torus hides what lies behind the shape's open corners, at every step budget."""
    seeds = _rounded_seeds(3)
    broken_preview = {"occlusion.ENABLED": True, "occlusion.shape_id": {"returns": 0.0}}
    drawn = cut_battery.draw_in_blender(seeds, tmp_path, cuts={"whole box": broken_preview})
    preview = [f for s in seeds for f in cut_battery.preview_findings(s, drawn[s], {"whole box": broken_preview})]
    assert sum(f.unexplained for f in preview) > 100 and all(f.kinds.get("emptied", 0) + f.kinds.get(
        "shows what lies behind", 0) > 0 for f in preview if f.unexplained)
    need(threejs.available("r180"))
    three = cut_battery.draw_in_threejs(seeds, tmp_path, "r180",
                                        cuts={"whole box": {"occluders": "BOX", "cullBackFaces": False}})
    assert sum(f.unexplained for f in three) > 100


# --- everyday tier: the comparison and the generator ------------------------------------------------

def _picture(covered, colour, depth):
    rgba = np.zeros((cut_battery.H, cut_battery.W, 4))
    rgba[covered] = [*colour, 1.0]
    d = np.ones((cut_battery.H, cut_battery.W))
    d[covered] = depth
    return rgba, d


PROJECTION = np.array([[1.0, 0, 0, 0], [0, 1.33, 0, 0], [0, 0, -1.02, -0.202], [0, 0, -1, 0]])  # near 0.1, far 10


def test_compare_explains_only_pixels_where_the_large_budget_agrees():
    covered = np.zeros((cut_battery.H, cut_battery.W), bool)
    covered[10:20, 10:20] = True
    plain = _picture(covered, (0.5, 0.5, 0.5), 0.9)
    emptied = _picture(covered & ~(np.arange(cut_battery.W) == 12)[None, :], (0.5, 0.5, 0.5), 0.9)
    # the large budget: the plain march now finds nothing on that column either: explained
    found = cut_battery.compare(1, "preview", "x", plain, emptied, emptied, emptied, PROJECTION)
    assert (found.changed, found.explained, found.kinds) == (10, 10, {})
    # the large budget draws the column in plain, not with the cut: unexplained, emptied
    found = cut_battery.compare(1, "preview", "x", plain, emptied, plain, emptied, PROJECTION)
    assert (found.changed, found.unexplained, found.kinds) == (10, 10, {"emptied": 10})
    # a farther hit (the box behind) and another colour at the same depth
    behind = _picture(covered, (0.5, 0.5, 0.5), 0.99)
    found = cut_battery.compare(1, "preview", "x", plain, behind, plain, behind, PROJECTION)
    assert found.kinds == {"shows what lies behind": 100}
    tinted = _picture(covered, (0.5, 0.6, 0.5), 0.9)
    found = cut_battery.compare(1, "preview", "x", plain, tinted, plain, tinted, PROJECTION)
    assert found.kinds == {"wrong colour": 100}
    # within the tolerances: explained
    close = _picture(covered, (0.5 + 3 / 255, 0.5, 0.5), 0.9 + 1e-7)
    found = cut_battery.compare(1, "preview", "x", plain, close, plain, close, PROJECTION)
    assert (found.changed, found.unexplained) == (100, 0)


def test_compare_explains_a_pixel_plain_leaves_to_a_depth_tie():
    """A pixel the cut draws another colour, unexplained at the large budget, is explained where
    plain drawn with the opposite depth-tie rule draws the cut's colour there, and only there."""
    covered = np.zeros((cut_battery.H, cut_battery.W), bool)
    covered[10:20, 10:20] = True
    plain = _picture(covered, (0.5, 0.5, 0.5), 0.9)
    cut = (plain[0].copy(), plain[1])
    cut[0][12, 12, :3] = 0.3
    cut[0][15, 15, :3] = 0.3
    other_tie = (plain[0].copy(), plain[1])
    other_tie[0][12, 12, :3] = 0.3
    found = cut_battery.compare(1, "r180", "x", plain, cut, plain, cut, PROJECTION)
    assert (found.changed, found.unexplained) == (2, 2)
    found = cut_battery.compare(1, "r180", "x", plain, cut, plain, cut, PROJECTION, plain_other_tie=other_tie)
    assert (found.changed, found.unexplained, found.kinds) == (2, 1, {"wrong colour": 1})
    found = cut_battery.compare(1, "r180", "x", plain, cut, plain, cut, PROJECTION, plain_other_tie=plain)
    assert (found.changed, found.unexplained) == (2, 2)
    # a pixel the cut empties stays unexplained where the other tie empties it too (a hit at the
    # far plane ties with the cleared depth)
    emptied = (cut[0].copy(), cut[1])
    emptied[0][12, 12] = 0.0
    other_tie[0][12, 12] = 0.0
    found = cut_battery.compare(1, "r180", "x", plain, emptied, plain, emptied, PROJECTION, plain_other_tie=other_tie)
    assert (found.changed, found.unexplained, found.kinds) == (2, 2, {"emptied": 1, "wrong colour": 1})


def test_compare_counts_a_nan_colour_in_both_pictures_and_only_it():
    """A NaN colour at the same pixel and depth in plain and cut (seeds 2 and 80: a closed-form hit's
    zero normal, every picture alike) is counted as itself, never as a cut's wrong colour; the same
    pictures without the NaN are unchanged, and a real wrong colour beside it keeps its kind."""
    covered = np.zeros((cut_battery.H, cut_battery.W), bool)
    covered[10:20, 10:20] = True
    plain = _picture(covered, (0.5, 0.5, 0.5), 0.9)
    assert cut_battery.compare(1, "preview", "x", plain, plain, plain, plain, PROJECTION).changed == 0
    with_nan = _picture(covered, (0.5, 0.5, 0.5), 0.9)
    with_nan[0][12, 12, :3] = np.nan
    found = cut_battery.compare(1, "preview", "x", with_nan, with_nan, with_nan, with_nan, PROJECTION)
    assert (found.changed, found.unexplained, found.kinds) == (1, 1, {"NaN colour": 1})
    tinted = (with_nan[0].copy(), with_nan[1])
    tinted[0][15, 15, 1] = 0.6
    found = cut_battery.compare(1, "preview", "x", with_nan, tinted, with_nan, tinted, PROJECTION)
    assert (found.changed, found.unexplained, found.kinds) == (2, 2, {"NaN colour": 1, "wrong colour": 1})


def test_ci_seeds_draw_every_trait_of_the_generator():
    drawn = [cut_battery.scene(s) for s in set().union(*CI_SEEDS.values())]
    traits = {t for c in drawn for t in c["traits"][3:]}
    assert {c["shape"] for c in drawn} == set(cut_battery.SHAPES)
    assert {c["quality"] for c in drawn} == set(cut_battery.QUALITIES)
    assert {"ordinary", "long thin", "axis-aligned", "nested", "coincident", "flat", "open", "inside-out",
            "vertices far from the origin", "non-uniform scale", "mirrored", "sheared", "far from the world origin",
            "eye inside a box", "near plane cuts boxes", "orthographic", "perspective"} <= traits
    scales = [float(c["traits"][0].split(" ")[1]) for c in drawn]
    assert min(scales) < 1e-2 and max(scales) > 1e2


def test_the_depth_generators_draw_what_they_say():
    """bench.cut_battery --generator: mid-depth-ortho puts the view's centre at window depth 0.5 of
    an orthographic camera, the vertices around their object's origin; depth-hostile draws each of
    its traits on seeds 0-29 (docs/BENCHMARKS.md, the occluder depth margin)."""
    for seed in range(10):
        spec = cut_battery.mid_depth_ortho_scene(seed)
        camera = spec["camera"]
        distance = np.linalg.norm(np.subtract(camera["position"], camera["target"]))
        assert "ortho" in camera and "fov" not in camera
        assert abs((distance - camera["near"]) / (camera["far"] - camera["near"]) - 0.5) < 1e-9
        assert distance > 1e4 * camera["ortho"] * 0.99 and all(ob["offset"] == [0.0] * 3 for ob in spec["objects"])
    traits = {t for s in range(30) for t in cut_battery.depth_hostile_scene(s)["traits"]}
    assert {"near plane far nearer", "far plane far farther", "vertices 1e3-1e4 out", "grazing"} <= traits
