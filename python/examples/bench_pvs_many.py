"""pvs_many speed-up (threads=2 vs 1) and the Python overhead per cell.

    python python/examples/bench_pvs_many.py [SCENE] [--size 25] [--method dual-ray] [--cells 300] [--repeat 3]

The overhead is that of one `Scene.pvs` call per cell (argument conversion, the GIL
release, the result array) over `pvs_many(threads=1)`, which crosses the boundary once;
both run the same prepared method. Prints medians over `--repeat` runs and the load.
"""

import argparse
import os
import statistics
import time

import sightline


def timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="?", default="data/lyon1_bdtopo.geojson")
    ap.add_argument("--size", type=float, default=25.0)
    ap.add_argument("--method", default="dual-ray")
    ap.add_argument("--cells", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()

    scene = sightline.Scene.from_file(a.scene)
    cells = scene.cells(size=a.size)
    step = max(1, len(cells) // a.cells)
    cells = cells[::step][: a.cells]
    t_prep = timed(lambda: scene.pvs(cells[0], a.method))  # prepares and caches the method
    print(f"scene {a.scene}: {len(scene)} objects; {len(cells)} cells of {a.size} m; method {a.method}")
    print(f"prepare + first cell: {t_prep:.2f} s; load before: {os.getloadavg()[0]:.2f}")

    one, two, loop = [], [], []
    for _ in range(a.repeat):
        one.append(timed(lambda: scene.pvs_many(cells, a.method, threads=1)))
        two.append(timed(lambda: scene.pvs_many(cells, a.method, threads=2)))
        loop.append(timed(lambda: [scene.pvs(c, a.method) for c in cells]))
    m1, m2, ml = (statistics.median(v) for v in (one, two, loop))
    n = len(cells)
    print(f"pvs_many threads=1: {1e3 * m1 / n:.3f} ms/cell (median of {a.repeat})")
    print(f"pvs_many threads=2: {1e3 * m2 / n:.3f} ms/cell -> speed-up {m1 / m2:.2f}x")
    print(f"pvs loop          : {1e3 * ml / n:.3f} ms/cell -> Python overhead {1e6 * (ml - m1) / n:.1f} us/cell"
          f" = {100 * (ml - m1) / m1:.2f} % of the method's time")
    print(f"load after: {os.getloadavg()[0]:.2f} (2 cores)")


if __name__ == "__main__":
    main()
