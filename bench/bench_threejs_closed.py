"""The time of loadBoxmarch's checks of every static mesh (shaders/threejs/): boxmarchClosedOutward
(whether every box is closed and wound outward, before it culls back faces) and
boxmarchSealedTriangles (which boxes may draw occluders in the pre-pass), and of the Map-based
sealed check the latter replaced (tests/test_threejs_sealed_triangles.py OLD_SEALED_JS), on
geometries of N cubes shaped as the glTF export writes them (tests/engines/threejs.py CUBES_JS),
in headless Chromium for each three.js release (the sealed checks in r111, whose script makes
them globals): best of REPEATS calls (one of the replaced check)
on the serving process's clock less one reading's round trip (performance.now() stands still
under Chromium's virtual time), and the answer (closed: true when closed and outward; sealed: the
triangles kept). The closed check it replaced kept every directed edge in one Set: 13 s for
100,000 boxes, and a RangeError after 80-99 s at about 466,000 (issue 36).

    PYTHONPATH=addon python3 -m bench.bench_threejs_closed [N ...]
"""
import json
import sys

from bench.common import table

COUNTS = (10_000, 100_000, 470_000, 1_000_000)
REPEATS = 3

TIMING_JOB = """async function () {
  __CUBES__
  __CLOCK_JS__
  __OLD_SEALED__
  var checks = {boxmarchClosedOutward: [boxmarchClosedOutward, __REPEATS__]};
  if (typeof boxmarchSealedTriangles === 'function') {  // a global of r111's script; r180's module does not export it
    checks.boxmarchSealedTriangles = [function (g) { return boxmarchSealedTriangles(g).length; }, __REPEATS__];
    checks['Map-based sealed check (replaced)'] = [function (g) { return oldSealedTriangles(g).length; }, 1];
  }
  var rows = [];
  for (var count of __COUNTS__) {
    var geometry = boxmarchTestCubes(THREE, count, true);
    for (var name in checks) {
      var best = Infinity, answer = null;
      for (var r = 0; r < checks[name][1]; r++) {
        var start = now();
        answer = checks[name][0](geometry);
        best = Math.min(best, now() - start - overhead);
      }
      rows.push({check: name, count: count, ms: best, answer: answer});
    }
  }
  return rows;
}"""


def main():
    from tests.engines import threejs
    from tests.test_threejs_sealed_triangles import OLD_SEALED_JS

    counts = [int(n) for n in sys.argv[1:]] or list(COUNTS)
    threejs.TIMEOUT_S = 900
    js = (TIMING_JOB.replace("__CUBES__", threejs.CUBES_JS).replace("__CLOCK_JS__", threejs.CLOCK_JS)
          .replace("__COUNTS__", json.dumps(counts, allow_nan=False)).replace("__REPEATS__", str(REPEATS))
          .replace("__OLD_SEALED__", OLD_SEALED_JS))
    rows = []
    for release in [r for r in sorted(threejs.RELEASES) if threejs.available(r) is None]:
        for row in threejs.run_page(b"", js, threejs.shipped_material(release), release):
            rows.append([f"r{threejs.RELEASES[release].revision}", row["check"], f"{row['count']:,}", f"{row['ms']:,.0f}",
                         f"{row['ms'] * 1e3 / row['count']:.1f}", json.dumps(row["answer"], allow_nan=False)])
    print(f"loadBoxmarch's mesh checks in headless Chromium, best of {REPEATS} (the replaced check: one call)")
    print(table(["three.js", "check", "cubes", "ms", "us per box", "answer"], rows))


if __name__ == "__main__":
    main()
