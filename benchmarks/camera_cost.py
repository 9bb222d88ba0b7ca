"""CPU time of a fast camera sample per region of the picture (issue 11): where to cut.

Run from the repository root::

    python benchmarks/camera_cost.py                    # vr-offaxis, every 2nd skin pixel
    python benchmarks/camera_cost.py --stride 8 --repeats 3

On one thread (``NUMBA_NUM_THREADS=1`` unless set; the script starts itself again with it and
the benchmarks' warm Numba cache, ``_common.WARM_CACHE``), ``fast.camera_pass`` with sets of
one sample (the grid the rel-error render of vr-offaxis chooses) over the pixels of each region
of ``region_masks`` — every ``stride``-th skin pixel, every ``stride // 2``-th of the others —
timed by ``time.process_time`` (the best of ``repeats``): µs per camera sample per region, and
the per-sample relative standard deviation of the median pixel with ``--sets`` ≥ 4. Prints one
line and appends a JSON line to ``benchmarks/results/camera_cost.jsonl``. Compare commits by
running it on each in turn (interleaved: the machine is shared).

Measured (session 11, load 5–8, interleaved A/B of one round each): 5a1e238 skin 11.4–15.4,
iris 55–66, sclera 10–17 µs a sample; 2c00045 skin 9.0–10.4, iris 40–44, sclera 8–9 µs.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import _common as C

if "NUMBA_NUM_THREADS" not in os.environ or "NUMBA_CACHE_DIR" not in os.environ:
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    os.environ.setdefault("NUMBA_CACHE_DIR", str(C.WARM_CACHE))
    os.execv(sys.executable, [sys.executable, *sys.argv])

import numpy as np  # noqa: E402

from eyelume.analysis.regions import region_masks  # noqa: E402
from eyelume.compile import compile_scene  # noqa: E402
from eyelume.estimators import fast as F  # noqa: E402
from eyelume.scene.io import load_scene  # noqa: E402

REGIONS = ("skin", "iris", "sclera", "pupil")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="vr-offaxis")
    p.add_argument("--stride", type=int, default=2)
    p.add_argument("--sets", type=int, default=2)
    p.add_argument("--repeats", type=int, default=1)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()
    info = C.machine()
    C.print_header(f"camera cost per region: {a.scene}", info)
    cs = compile_scene(load_scene(a.scene))
    masks = region_masks(cs)
    out = {}
    for name in REGIONS:
        step = a.stride if name == "skin" else max(1, a.stride // 2)
        idx = np.ascontiguousarray(np.flatnonzero(masks[name].reshape(-1))[::step], np.int64)
        if idx.size == 0:
            continue
        warm = F.CameraSums(idx[:4].copy(), np.zeros(min(4, idx.size)), np.zeros(min(4, idx.size)))
        F.camera_pass(a.seed, 0, 1, cs.tables, cs.camera, 1, warm)  # compiled or loaded
        best = np.inf
        for _ in range(a.repeats):
            sums = F.CameraSums(idx, np.zeros(idx.size), np.zeros(idx.size))
            c0 = time.process_time()
            F.camera_pass(a.seed, 0, a.sets, cs.tables, cs.camera, 1, sums)
            best = min(best, time.process_time() - c0)
        us = best / (idx.size * a.sets) * 1e6
        row = {"pixels": int(idx.size), "us_per_sample": round(us, 2)}
        if a.sets >= 4:
            mean = sums.total / a.sets
            var = np.maximum(sums.squares / a.sets - mean**2, 0.0) * a.sets / (a.sets - 1)
            ok = mean > 0
            row["per_sample_rel_sd"] = round(float(np.median(np.sqrt(var[ok]) / mean[ok])), 5)
        out[name] = row
    print(f"{a.scene}: " + ", ".join(f"{k} {v['us_per_sample']} µs" for k, v in out.items()))
    C.append_result(
        "camera_cost",
        {
            "machine": info,
            "command": C.command_line(),
            "scene": a.scene,
            "sets": a.sets,
            "regions": out,
            "load_after": C.loadavg(),
        },
    )


if __name__ == "__main__":
    main()
