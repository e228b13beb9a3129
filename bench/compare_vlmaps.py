#!/usr/bin/env python3
"""Side-by-side comparison of VLMaps' planner and ivlmap's grid planner, in one run.

VLMaps (vlmaps/vlmaps: vlmaps/navigator/navigator.py, vlmaps/utils/navigation_utils.py)
plans on a visibility graph: the obstacle cells of its obstacle map (1 = free, 0 =
occupied) are traced with cv2.findContours(RETR_EXTERNAL, CHAIN_APPROX_SIMPLE), each
contour becomes a pyvisgraph polygon, and VisGraph.build links their vertices. When a
query's start lies inside a polygon on a free cell (the closed outer wall encloses the
whole free space), the Navigator rebuilds: it traces with RETR_TREE, finds the two
contours holding the start, cuts the wall between their closest points with a 5 px
line, traces again and rebuilds the graph. Each query then runs VisGraph.shortest_path.
The functions below re-implement that method step by step (no code copied), with the
same OpenCV and pyvisgraph calls, so the timings and paths are those of VLMaps' method.

Our side runs `cargo run --release -p map_core --example plan_bench`, which prints JSON.

Usage: bench/compare_vlmaps.py [--grid G] [--queries Q] [--workers N] [--reference OUT]
"""

import argparse
import importlib.metadata
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_DIR = REPO.parent / "shared" / "bench"


def ensure_venv():
    """Re-exec inside the bench venv (created by bench/setup.sh) unless already there."""
    try:
        import cv2  # noqa: F401
        import numpy  # noqa: F401
        import pyvisgraph  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get("IVLMAP_BENCH_REEXEC"):
        sys.exit("bench venv lacks numpy/opencv/pyvisgraph even after bench/setup.sh")
    py = subprocess.run(["bash", str(REPO / "bench" / "setup.sh")], check=True,
                        capture_output=True, text=True).stdout.strip().splitlines()[-1]
    env = dict(os.environ, IVLMAP_BENCH_REEXEC="1")
    os.execve(py, [py, *sys.argv], env)


ensure_venv()
import cv2  # noqa: E402
import numpy as np  # noqa: E402
import pyvisgraph as vg  # noqa: E402


# ---------------------------------------------------------------- VLMaps' method
def islands(obs_map, label, tree=False):
    """Contours of the cells equal to `label`, as (row, col) integer arrays."""
    mask = (obs_map == label).astype(np.uint8)
    mode = cv2.RETR_TREE if tree else cv2.RETR_EXTERNAL
    contours, _ = cv2.findContours(mask, mode, cv2.CHAIN_APPROX_SIMPLE)
    return [c.reshape(-1, 2)[:, ::-1] for c in contours]  # OpenCV gives (x=col, y=row)


def contours_holding(obs_map, contours, point):
    r, c = int(point[0]), int(point[1])
    ids = []
    for i, con in enumerate(contours):
        filled = np.zeros_like(obs_map, dtype=np.uint8)
        cv2.drawContours(filled, [con[:, ::-1].copy()], 0, 255, -1)
        if filled[r, c] == 255:
            ids.append(i)
    return ids


def visgraph_from_obs_map(obs_map, workers, cut_at=None):
    contours = islands(obs_map, 0, tree=cut_at is not None)
    if cut_at is not None:
        ids = contours_holding(obs_map, contours, cut_at)
        if len(ids) != 2:
            raise RuntimeError(f"start is in {len(ids)} contours, VLMaps expects 2")
        pa, pb = closest_points(obs_map, contours[ids[0]], contours[ids[1]])
        cut = cv2.line((obs_map * 255).astype(np.uint8), (int(pa[1]), int(pa[0])),
                       (int(pb[1]), int(pb[0])), 255, 5)
        obs_map = (cut == 255)
        contours = islands(obs_map, 0)
    polys = [[vg.Point(int(r), int(c)) for r, c in con] for con in contours]
    g = vg.VisGraph()
    g.build(polys, workers=workers, status=False)
    return g, polys


def closest_points(obs_map, con_a, con_b):
    """Closest pair of outline pixels of two contours (VLMaps draws both and uses cdist)."""
    a = np.zeros_like(obs_map, dtype=np.uint8)
    b = np.zeros_like(obs_map, dtype=np.uint8)
    cv2.drawContours(a, [con_a[:, ::-1].copy()], 0, 255, 1)
    cv2.drawContours(b, [con_b[:, ::-1].copy()], 0, 255, 1)
    pa = np.argwhere(a == 255)
    pb = np.argwhere(b == 255)
    best = (np.inf, None, None)
    for lo in range(0, len(pa), 512):  # chunked squared distances: same argmin as cdist
        blk = pa[lo:lo + 512]
        d = ((blk[:, None, :] - pb[None, :, :]) ** 2).sum(-1)
        k = int(np.argmin(d))
        i, j = divmod(k, d.shape[1])
        if d[i, j] < best[0]:
            best = (d[i, j], blk[i], pb[j])
    return best[1], best[2]


class VlmapsNavigator:
    """Navigator.build_visgraph / plan_to with the cropped-map offset at 0."""

    def __init__(self, obs_map, workers):
        self.obs_map = obs_map
        self.workers = workers
        self.graph, self.polys = visgraph_from_obs_map(obs_map, workers)
        self.rebuilt = False

    def plan_to(self, start, goal):
        s = vg.Point(start[0], start[1])
        if self.graph.point_in_polygon(s) != -1 and self.obs_map[int(start[0]), int(start[1])] == 1:
            self.graph, self.polys = visgraph_from_obs_map(self.obs_map, self.workers, cut_at=start)
            self.rebuilt = True
        return self._plan_to_pos_v2(start, goal)

    def _plan_to_pos_v2(self, start, goal):
        path = []
        s = vg.Point(start[0], start[1])
        if self.obs_map[int(start[0]), int(start[1])] == 0:
            free = np.argwhere(self.obs_map == 1)
            k = int(np.argmin(((free - np.array(start)) ** 2).sum(1)))
            path.append([free[k][0], free[k][1]])
            s = vg.Point(free[k][0], free[k][1])
        g = vg.Point(goal[0], goal[1])
        if self.obs_map[int(goal[0]), int(goal[1])] == 0:
            pid = self.graph.point_in_polygon(g)
            try:
                g = self.graph.closest_point(g, pid, length=1)
            except Exception:
                for dr, dc in ((-1, -1), (1, -1), (-1, 1), (1, 1)):
                    cand = vg.Point(goal[0] + dr, goal[1] + dc)
                    if self.graph.point_in_polygon(cand) == -1:
                        g = cand
                        break
        for p in self.graph.shortest_path(s, g):
            path.append([p.x, p.y])
        return path


def path_len(path):
    return sum(((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5 for a, b in zip(path, path[1:]))


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, max(0, int(round(q * (len(xs) - 1)))))]


def run_vlmaps(grid_path, pairs, cell, workers, repeats):
    t0 = time.perf_counter()
    grid = np.load(grid_path)
    obs_map = (grid == 0).astype(np.uint8)  # VLMaps: 1 = free, 0 = occupied
    t_load = time.perf_counter()
    nav = VlmapsNavigator(obs_map, workers)
    t_build = time.perf_counter()
    first = nav.plan_to(pairs[0][0], pairs[0][1])
    t_first = time.perf_counter()
    n_edges = len(nav.graph.visgraph.get_edges())
    n_vertices = sum(len(p) for p in nav.polys)
    lengths, warm = [], []
    for s, g in pairs:
        times = []
        for _ in range(repeats):
            q0 = time.perf_counter()
            path = nav.plan_to(s, g)
            times.append(time.perf_counter() - q0)
        warm.append(statistics.median(times) * 1e3)
        lengths.append(path_len(path) * cell)
    return {
        "load_ms": (t_load - t0) * 1e3,
        "build_ms": (t_build - t_load) * 1e3,
        "first_query_ms": (t_first - t_build) * 1e3,
        "first_path_total_ms": (t_first - t_load) * 1e3,
        "first_path_len_m": path_len(first) * cell,
        "rebuilt_on_first_query": nav.rebuilt,
        "polygons": len(nav.polys),
        "vertices": n_vertices,
        "edges": n_edges,
        "warm_ms": warm,
        "lengths_m": lengths,
    }


def run_ours(grid_path, queries_path):
    cmd = ["cargo", "run", "--quiet", "--release", "-p", "map_core", "--example", "plan_bench",
           "--", str(grid_path), str(queries_path)]
    # build first so that compile time never counts
    subprocess.run(["cargo", "build", "--quiet", "--release", "-p", "map_core", "--example", "plan_bench"],
                   cwd=REPO, check=True)
    out = subprocess.run(cmd, cwd=REPO, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", default=str(DEFAULT_DIR / "grid.npy"))
    ap.add_argument("--queries", default=str(DEFAULT_DIR / "queries.json"))
    ap.add_argument("--workers", type=int, default=1,
                    help="pyvisgraph build workers (VLMaps passes 4; 1 = single-threaded like ours)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per warm query (median)")
    ap.add_argument("--reference", help="write VLMaps' per-query lengths as JSON here")
    ap.add_argument("--json", help="write all figures as JSON here")
    ap.add_argument("--skip-ours", action="store_true")
    args = ap.parse_args()

    meta = json.loads(Path(args.queries).read_text())
    cell = float(meta.get("cell_size_m", 0.05))
    pairs = [(tuple(p["start"]), tuple(p["goal"])) for p in meta["pairs"]]

    print(f"VLMaps' planner (pyvisgraph {importlib.metadata.version('pyvisgraph')}, "
          f"workers={args.workers}) on {args.grid} ...", file=sys.stderr)
    v = run_vlmaps(args.grid, pairs, cell, args.workers, args.repeats)
    if args.reference:
        Path(args.reference).write_text(json.dumps({
            "grid": Path(args.grid).name, "queries": Path(args.queries).name,
            "note": "VLMaps visibility-graph path length per query (m), from bench/compare_vlmaps.py",
            "lengths_m": v["lengths_m"]}, indent=1) + "\n")
    result = {"vlmaps": v}
    if not args.skip_ours:
        print("ours (cargo run --release --example plan_bench) ...", file=sys.stderr)
        o = run_ours(args.grid, args.queries)
        result["ours"] = o
        ratios = [a / b for a, b in zip(o["lengths_m"], v["lengths_m"]) if b > 0]
        rows = [
            ("time to first path (load excluded, preprocessing incl.)",
             f"{v['first_path_total_ms']:.1f} ms", f"{o['first_path_total_ms']:.2f} ms",
             f"{v['first_path_total_ms'] / o['first_path_total_ms']:.0f}x faster"),
            ("  of which preprocessing (graph build / GridPlanner::new)",
             f"{v['build_ms']:.1f} ms", f"{o['new_ms']:.2f} ms", ""),
            ("  of which first query", f"{v['first_query_ms']:.1f} ms"
             + (" (rebuild)" if v["rebuilt_on_first_query"] else ""),
             f"{o['first_query_ms']:.2f} ms", ""),
            ("warm query, median", f"{statistics.median(v['warm_ms']):.2f} ms",
             f"{statistics.median(o['warm_ms']):.3f} ms",
             f"{statistics.median(v['warm_ms']) / statistics.median(o['warm_ms']):.0f}x faster"),
            ("warm query, p95", f"{pct(v['warm_ms'], 0.95):.2f} ms", f"{pct(o['warm_ms'], 0.95):.3f} ms",
             f"{pct(v['warm_ms'], 0.95) / pct(o['warm_ms'], 0.95):.0f}x faster"),
            ("path length, total (50 pairs)", f"{sum(v['lengths_m']):.2f} m", f"{sum(o['lengths_m']):.2f} m",
             f"ours/vlmaps {sum(o['lengths_m']) / sum(v['lengths_m']):.4f}"),
            ("path length, median", f"{statistics.median(v['lengths_m']):.2f} m",
             f"{statistics.median(o['lengths_m']):.2f} m",
             f"per-pair ratio median {statistics.median(ratios):.4f}, max {max(ratios):.4f}"),
        ]
        w0 = max(len(r[0]) for r in rows)
        print(f"\n{'':{w0}}  {'VLMaps (visgraph)':>20}  {'ivlmap (grid)':>16}  ratio")
        for name, a, b, c in rows:
            print(f"{name:{w0}}  {a:>20}  {b:>16}  {c}")
        print(f"\nVLMaps graph: {v['polygons']} polygons, {v['vertices']} vertices, {v['edges']} edges; "
              f"our raw grid path total {sum(o['raw_lengths_m']):.2f} m; map load (np.load / npy) "
              f"{v['load_ms']:.1f} ms / {o['load_ms']:.2f} ms")
    else:
        print(json.dumps(v, indent=1))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
