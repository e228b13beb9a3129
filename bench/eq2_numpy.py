"""Eq. 2 (paper Section III-A) in numpy: the reference the Rust labelling is timed against.

    python bench/eq2_numpy.py DIR [--reps N]

Reads DIR/labels.npy, DIR/masks.json (SAM output, COCO RLE) and DIR/config.json as
written by `cargo run --release -p map_build --example eq2_bench -- gen DIR`, labels
every mask, and writes DIR/numpy_result.json (per-mask outcome, label, score, top k,
and the median times). The algorithm is the one map_core implements:

  region matching   vals = labels[mask]                 (cells inside the mask only)
  numpy.unique      u, c = np.unique(vals, return_counts=True)
  Eq. 2 scores      s = c / mask pixels, sorted descending (stable: ties keep the
                    smaller label first)
  decision          too small (< min_area pixels) -> "TooSmall"; no non-background
                    label among the top k -> "NoObjectLabel"; best object label
                    below min_score -> "LowScore"; else kept with that label

Two numpy variants are timed: the paper's form, full-frame H x W boolean masks as SAM
returns them (`labels[mask]` scans all H x W cells per mask), and a stronger one that
first crops label map and mask to SAM's bbox. Masks are decoded (untimed for Eq. 2)
with pycocotools when it is installed, else with a pure-Python reading of the
compressed counts and np.repeat.
"""

import argparse
import json
import os
import statistics
import time

import numpy as np


def rle_string_to_counts(s):
    """pycocotools' rleFrString."""
    counts = []
    p = 0
    while p < len(s):
        x = 0
        k = 0
        more = 1
        while more:
            c = ord(s[p]) - 48
            x |= (c & 0x1F) << (5 * k)
            more = c & 0x20
            p += 1
            k += 1
            if not more and (c & 0x10):
                x |= -1 << (5 * k)
        if len(counts) > 2:
            x += counts[-2]
        counts.append(x)
    return counts


def decode(seg):
    h, w = seg["size"]
    counts = seg["counts"]
    if isinstance(counts, str):
        counts = rle_string_to_counts(counts)
    vals = np.zeros(len(counts), dtype=bool)
    vals[1::2] = True
    flat = np.repeat(vals, counts)
    return flat.reshape((w, h)).T  # COCO RLE is column-major


def decide(vals, cfg):
    area = int(vals.size)
    if area < cfg["min_area"] or area == 0:
        return {"outcome": "TooSmall", "area": area, "label": None, "score": None, "top_k": []}
    u, c = np.unique(vals, return_counts=True)
    order = np.argsort(-c, kind="stable")
    u = u[order][: cfg["top_k"]]
    c = c[order][: cfg["top_k"]]
    scores = c / area
    background = set(cfg["background"])
    best = next((i for i in range(len(u)) if int(u[i]) not in background), None)
    if best is None:
        return {"outcome": "NoObjectLabel", "area": area, "label": None, "score": None, "top_k": []}
    label, score = int(u[best]), float(scores[best])
    if score < cfg["min_score"]:
        return {"outcome": "LowScore", "area": area, "label": label, "score": score, "top_k": []}
    top = [[int(a), int(b)] for a, b in zip(u, c)]
    return {"outcome": "kept", "area": area, "label": label, "score": score, "top_k": top}


def eq2_full_frame(labels, masks, cfg):
    return [decide(labels[m], cfg) for m in masks]


def eq2_bbox_crop(labels, masks, boxes, cfg):
    out = []
    for m, (x, y, w, h) in zip(masks, boxes):
        # SAM's bbox: [x0, y0, x1 - x0, y1 - y0] with x1, y1 inclusive
        sl = (slice(y, y + h + 1), slice(x, x + w + 1))
        out.append(decide(labels[sl][m[sl]], cfg))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    cfg = json.load(open(os.path.join(a.dir, "config.json")))
    labels = np.load(os.path.join(a.dir, "labels.npy"))
    times = {}

    t = time.perf_counter()
    records = json.load(open(os.path.join(a.dir, "masks.json")))
    try:
        from pycocotools import mask as mask_utils

        masks = [
            mask_utils.decode({"size": r["segmentation"]["size"], "counts": r["segmentation"]["counts"].encode()}).astype(bool)
            for r in records
        ]
        times["pycocotools"] = 1.0
    except ImportError:
        masks = [decode(r["segmentation"]) for r in records]
    times["decode_masks_json"] = (time.perf_counter() - t) * 1e3
    boxes = [[int(v) for v in r["bbox"]] for r in records]
    for m, r in zip(masks, records):
        assert int(m.sum()) == r["area"]

    results = None
    for name, fn in [
        ("eq2_full_frame", lambda: eq2_full_frame(labels, masks, cfg)),
        ("eq2_bbox_crop", lambda: eq2_bbox_crop(labels, masks, boxes, cfg)),
    ]:
        fn()  # warm-up
        runs = []
        for _ in range(a.reps):
            t = time.perf_counter()
            res = fn()
            runs.append(time.perf_counter() - t)
        times[name] = statistics.median(runs) * 1e3
        if results is None:
            results = res
        assert res == results, name
        print(f"numpy {name:16s} {times[name]:10.3f} ms (median of {a.reps})")

    out = []
    for i, r in enumerate(results):
        out.append({"mask": i, **r})
    with open(os.path.join(a.dir, "numpy_result.json"), "w") as f:
        json.dump({"results": out, "times_ms": times, "reps": a.reps}, f)
    kept = sum(1 for r in out if r["outcome"] == "kept")
    print(f"numpy: {len(out)} masks, {kept} kept; decode {times['decode_masks_json']:.1f} ms")


if __name__ == "__main__":
    main()
