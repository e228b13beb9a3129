"""Write the SAM-output fixtures of map_build/tests/perception_sam.rs with pycocotools.

The same masks in the three forms SAM's automatic mask generator can give:
  sam_coco.json          segmentation = COCO RLE, compressed counts (pycocotools.mask.encode,
                         as SAM's coco_encode_rle does for output_mode="coco_rle")
  sam_uncompressed.json  segmentation = COCO RLE, counts as a list of ints (numpy, Fortran order)
  sam_bitmap.json        segmentation = mask.tolist() (output_mode="binary_mask")
with area (pycocotools.mask.area) and SAM's bbox convention [x0, y0, x1 - x0, y1 - y0]
(x1, y1 inclusive, as SAM's batched_mask_to_box + box_xyxy_to_xywh give).

Run once (outputs are committed):
  python3 -m venv /tmp/coco && /tmp/coco/bin/pip install numpy pycocotools
  /tmp/coco/bin/python map_build/tests/perception_data/make_sam_fixtures.py
"""
import json
import os

import numpy as np
from pycocotools import mask as mask_utils

H, W = 61, 83
rng = np.random.default_rng(20240611)
yy, xx = np.mgrid[0:H, 0:W]

masks = []
masks.append(np.zeros((H, W), bool))                         # empty
m = np.zeros((H, W), bool); m[0, 0] = True; masks.append(m)  # first pixel: counts start with 0
m = np.zeros((H, W), bool); m[-1, -1] = True; masks.append(m)
masks.append(np.ones((H, W), bool))                          # full
masks.append((yy - 30) ** 2 / 20.0 ** 2 + (xx - 40) ** 2 / 35.0 ** 2 < 1.0)  # ellipse, long runs
m = np.zeros((H, W), bool); m[5:50, 3:9] = True; m[10:12, 20:80] = True; masks.append(m)
masks.append(rng.random((H, W)) < 0.5)                       # noise: many short runs
masks.append(((yy // 7 + xx // 5) % 2 == 0) & (yy < 45))     # checkerboard blocks
masks.append((np.abs(yy - 0.6 * xx - 5) < 3))                # thin diagonal band


def sam_bbox(m):
    if not m.any():
        return [0, 0, 0, 0]
    rows = np.where(m.any(axis=1))[0]
    cols = np.where(m.any(axis=0))[0]
    return [int(cols[0]), int(rows[0]), int(cols[-1] - cols[0]), int(rows[-1] - rows[0])]


def uncompressed_counts(m):
    flat = m.flatten(order="F").astype(np.int8)
    counts = []
    cur, n = 0, 0
    for v in flat:
        if v == cur:
            n += 1
        else:
            counts.append(n)
            cur, n = v, 1
    counts.append(n)
    return counts


records = {"coco": [], "uncompressed": [], "bitmap": []}
for i, m in enumerate(masks):
    rle = mask_utils.encode(np.asfortranarray(m.astype(np.uint8)))
    rle["counts"] = rle["counts"].decode("utf-8")
    assert (mask_utils.decode({"size": rle["size"], "counts": rle["counts"].encode()}) == m).all()
    base = {
        "area": int(mask_utils.area(mask_utils.encode(np.asfortranarray(m.astype(np.uint8))))),
        "bbox": sam_bbox(m),
        "predicted_iou": round(float(0.8 + 0.01 * i), 6),
        "point_coords": [[float(W / 2), float(H / 2)]],
        "stability_score": round(float(0.9 + 0.005 * i), 6),
        "crop_box": [0, 0, W, H],
    }
    records["coco"].append({"segmentation": {"size": [H, W], "counts": rle["counts"]}, **base})
    records["uncompressed"].append(
        {"segmentation": {"size": [H, W], "counts": uncompressed_counts(m)}, **base}
    )
    records["bitmap"].append({"segmentation": m.tolist(), **base})

here = os.path.dirname(os.path.abspath(__file__))
for name, recs in records.items():
    path = os.path.join(here, f"sam_{name}.json")
    with open(path, "w") as f:
        if name == "bitmap":
            json.dump(recs, f, separators=(",", ":"))
        else:
            json.dump(recs, f, indent=1)
        f.write("\n")
    print(path, os.path.getsize(path))
