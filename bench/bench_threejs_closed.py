"""The time of boxmarchClosedOutward (shaders/threejs/: whether every box of a mesh is closed and
wound outward, which loadBoxmarch asks of every static mesh before it culls back faces) on
geometries of N cubes shaped as the glTF export writes them (tests/engines/threejs.py CUBES_JS),
in headless Chromium for each three.js release: best of REPEATS calls on the serving process's
clock less one reading's round trip (performance.now() stands still under Chromium's virtual
time), and the answer (true: closed and outward). The check it replaced kept every directed edge
in one Set: 13 s for 100,000 boxes, and a RangeError after 80-99 s at about 466,000 (issue 36).

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
  var rows = [];
  for (var count of __COUNTS__) {
    var geometry = boxmarchTestCubes(THREE, count), best = Infinity, closed = null;
    for (var r = 0; r < __REPEATS__; r++) {
      var start = now();
      closed = boxmarchClosedOutward(geometry);
      best = Math.min(best, now() - start - overhead);
    }
    rows.push({count: count, ms: best, closed: closed});
  }
  return rows;
}"""


def main():
    from tests.engines import threejs

    counts = [int(n) for n in sys.argv[1:]] or list(COUNTS)
    threejs.TIMEOUT_S = 900
    js = (TIMING_JOB.replace("__CUBES__", threejs.CUBES_JS).replace("__CLOCK_JS__", threejs.CLOCK_JS)
          .replace("__COUNTS__", json.dumps(counts, allow_nan=False)).replace("__REPEATS__", str(REPEATS)))
    rows = []
    for release in [r for r in sorted(threejs.RELEASES) if threejs.available(r) is None]:
        for row in threejs.run_page(b"", js, threejs.shipped_material(release), release):
            rows.append([f"r{threejs.RELEASES[release].revision}", f"{row['count']:,}", f"{row['ms']:,.0f}",
                         f"{row['ms'] * 1e3 / row['count']:.1f}", str(row["closed"]).lower()])
    print(f"boxmarchClosedOutward in headless Chromium, best of {REPEATS}")
    print(table(["three.js", "cubes", "ms", "us per box", "closed outward"], rows))


if __name__ == "__main__":
    main()
