"""pvs_many speed-up (threads=2 vs 1) and the Python overhead per cell.

    python python/examples/bench_pvs_many.py [SCENE] [--size 25] [--method dual-ray] [--cells 300] [--repeat 3]

* speed-up: wall time of `pvs_many(threads=1)` over `threads=2` (medians over
  `--repeat` runs). On a loaded machine the wall clock says little, so the CPU time of
  the two pool threads is printed too: both busy means the cells did run in parallel
  (on a loaded machine the split also shows how the OS scheduled them).
* Python overhead: CPU time per call of a `Scene.pvs` loop over `pvs_many(threads=1)`
  (one boundary crossing for all cells), measured with the method `all` — whose answer
  is every object, the largest result array — and compared with the CPU time per cell
  of the method itself.
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


def cpu(f):
    t = time.process_time()
    f()
    return time.process_time() - t


def thread_cpu():
    """CPU seconds of each thread of this process (Linux /proc)."""
    out = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            fields = open(f"/proc/self/task/{tid}/stat").read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[tid] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    return out


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

    n = len(cells)
    one, two, cpu1 = [], [], []
    for _ in range(a.repeat):
        t = time.perf_counter()
        cpu1.append(cpu(lambda: scene.pvs_many(cells, a.method, threads=1)))
        one.append(time.perf_counter() - t)
        before = thread_cpu()
        two.append(timed(lambda: scene.pvs_many(cells, a.method, threads=2)))
        after = thread_cpu()
    split = sorted((after[k] - before.get(k, 0.0) for k in after), reverse=True)[:2]
    m1, m2, c1 = (statistics.median(v) for v in (one, two, cpu1))
    print(f"pvs_many threads=1: {1e3 * m1 / n:.2f} ms/cell wall, {1e3 * c1 / n:.2f} ms/cell CPU (medians of {a.repeat})")
    print(f"pvs_many threads=2: {1e3 * m2 / n:.2f} ms/cell wall -> wall speed-up {m1 / m2:.2f}x")
    print(f"  CPU of the two busiest threads in the last run: {split[0]:.2f} s + {split[1]:.2f} s"
          f" (total {sum(split):.2f} s)")
    scene.pvs(cells[0], "all")
    loops, manys = [], []
    for _ in range(a.repeat):
        loops.append(cpu(lambda: [scene.pvs(c, "all") for c in cells]))
        manys.append(cpu(lambda: scene.pvs_many(cells, "all", threads=1)))
    overhead = (statistics.median(loops) - statistics.median(manys)) / n
    print(f"Python overhead of one pvs() call: {1e6 * overhead:.1f} us CPU"
          f" = {100 * overhead / (c1 / n):.3f} % of the {a.method} CPU time per cell")
    print(f"load after: {os.getloadavg()[0]:.2f} (2 cores)")


if __name__ == "__main__":
    main()
