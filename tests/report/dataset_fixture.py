"""A small dataset folder in the layout ``eyelume dataset`` writes (/work/dataset_spec.md:
labels.jsonl, dataset.json, images/, segmentation/), drawn with OpenCV instead of rendered, so
the report's tests run in a second: the pictures and their labels agree by construction (the
same ellipses draw the picture, the segmentation and the label), which is what the exporter,
the contact sheet and the detector benchmark's scoring read.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
from PIL import Image

#: Grey levels (8-bit DN) of the drawn classes.
_DN = {4: 90, 5: 60, 1: 180, 2: 110, 3: 25, 6: 250}


def _ellipse(cx, cy, a, b, angle):
    return {"center_px": [cx, cy], "semi_axes_px": [a, b], "angle_deg": angle}


def write_fake_dataset(
    out: Path, n: int = 6, size: tuple[int, int] = (96, 72), bits: int = 8, seed: int = 3
) -> list[dict]:
    """Write ``n`` pictures of ``size`` (cols, rows) to ``out``; return their label lines."""
    cols, rows = size
    rng = np.random.default_rng(seed)
    (out / "images").mkdir(parents=True, exist_ok=True)
    (out / "segmentation").mkdir(exist_ok=True)
    labels = []
    for i in range(n):
        seg = np.full((rows, cols), 4, np.uint8)  # skin
        cx, cy = cols / 2 + rng.uniform(-6, 6), rows / 2 + rng.uniform(-4, 4)
        iris_r, pupil_a, pupil_b = rows * 0.3, rows * rng.uniform(0.08, 0.14), rows * 0.09
        angle = float(rng.uniform(-80, 80))
        s = 1 << 4  # cv2's sub-pixel drawing (shift=4): 4 fractional bits
        cv2.ellipse(seg, (round(cols / 2 * s), round(rows / 2 * s)),
                    (round(cols * 0.42 * s), round(rows * 0.3 * s)), 0, 0, 360, 1, -1,
                    lineType=cv2.LINE_8, shift=4)  # fmt: skip
        cv2.circle(seg, (round(cx * s), round(cy * s)), round(iris_r * s), 2, -1, shift=4)
        cv2.ellipse(seg, (round(cx * s), round(cy * s)), (round(pupil_a * s), round(pupil_b * s)),
                    angle, 0, 360, 3, -1, shift=4)  # fmt: skip
        seg[: rows // 8] = 5  # an upper eyelid band
        glints = []
        for led, (dx, dy) in enumerate([(-14, -4), (14, -4), (-14, 6), (14, 6)]):
            gx, gy = cx + dx + rng.uniform(-0.5, 0.5), cy + dy + rng.uniform(-0.5, 0.5)
            cv2.circle(seg, (round(gx * s), round(gy * s)), round(1.5 * s), 6, -1, shift=4)
            glints.append({"led": led, "position_px": [gx, gy], "on_cornea": True,
                           "on_sclera": False, "hidden": False, "saturated": led == 0,
                           "visible": True})  # fmt: skip
        glints.append({"led": 4, "position_px": None, "on_cornea": False, "on_sclera": False,
                       "hidden": True, "saturated": False, "visible": False})  # fmt: skip
        pic = np.zeros((rows, cols), np.float64)
        for k, v in _DN.items():
            pic[seg == k] = v
        pic = cv2.GaussianBlur(pic, (0, 0), 0.7) + rng.normal(0, 1.5, pic.shape)
        full = 2**bits - 1
        dn = np.clip(np.rint(pic * full / 255.0), 0, full).astype(
            np.uint8 if bits == 8 else np.uint16
        )
        name = f"{i:06d}"
        Image.fromarray(dn).save(out / "images" / f"{name}.png")
        Image.fromarray(seg).save(out / "segmentation" / f"{name}.png")
        labels.append({
            "index": i, "seed": 1000 + i, "image": f"images/{name}.png",
            "irradiance": f"irradiance/{name}.npy", "segmentation": f"segmentation/{name}.png",
            "image_bits": bits, "size_px": [cols, rows],
            "varied": {"eye.pupil_diameter_mm": float(rng.uniform(2, 7)),
                       "eye_pose.head_offset_mm": rng.uniform(-1, 1, 3).tolist(),
                       "sensor.exposure_ms": float(rng.uniform(2, 8))},
            "person": {"index": i % 3, "values": {"kappa_horizontal_deg": float(rng.normal(5, 1)),
                                                   "iris_diameter_mm": 11.5}},
            "glasses": bool(i % 3 == 0),
            "gaze_deg": {"horizontal": float(rng.uniform(-25, 25)),
                         "vertical": float(rng.uniform(-20, 20))},
            "pupil": {"ellipse": _ellipse(cx, cy, pupil_a, pupil_b, angle),
                      "diameter_mm": float(rng.uniform(2, 7)), "visible_share": 1.0},
            "iris": {"ellipse": _ellipse(cx, cy, iris_r, iris_r, 0.0), "diameter_mm": 11.5,
                     "visible_share": 0.9},
            "glints": glints,
            "reflections": [{"led": 1, "chain": ["element 0"],
                             "position_px": [cols * 0.2, rows * 0.8], "visible": True}],
            "eye_openness": 0.85,
        })  # fmt: skip
    (out / "labels.jsonl").write_text(
        "".join(json.dumps(lab) + "\n" for lab in labels), encoding="utf-8"
    )
    (out / "dataset.json").write_text(
        json.dumps(
            {
                "name": "fake-set",
                "scene": "vr-offaxis",
                "seed": 7,
                "pictures": n,
                "image_bits": bits,
            }
        ),  # fmt: skip
        encoding="utf-8",
    )
    return labels
