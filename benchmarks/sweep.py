"""The illumination generator (issue 4): the paper's 385-configuration LED sweep and its refinement.

Run from the repository root::

    python benchmarks/sweep.py               # ~15 s; --delta 0.5, --repeats 5

On ``paper2005`` with the δ target (:func:`eyelume.analysis.targets.gaussian_target`):

- ``sweep``: :func:`eyelume.optimize.sweep_leds` over the paper's grid (Y 20–40, Z 20–70,
  θ 0–30 in steps of 5: 385 configurations), the whole call — geometry checks, the closed-form
  eye-plane irradiance of every configuration (:mod:`eyelume.estimators.closed_form`, with its
  automatic quadrature order) and the merits. Target ≤ 1 s after compilation.
- ``irradiance``: :func:`eyelume.estimators.closed_form.sweep_irradiance` alone, the same grid.
- ``refine``: :func:`eyelume.optimize.refine` from the sweep's best within the paper's bounds.

Each is warmed up once (compilation, or loading the Numba cache in
``$TMPDIR/eyelume-bench-numba-cache-<digest of the sources>``), then timed as the best of
``--repeats``. Prints the figures and how they were run, and appends a JSON line to
``benchmarks/results/sweep.jsonl``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402

os.environ.setdefault("NUMBA_CACHE_DIR", str(C.WARM_CACHE))

import numba  # noqa: E402
import numpy as np  # noqa: E402

import eyelume  # noqa: E402
from eyelume.analysis.targets import gaussian_target  # noqa: E402
from eyelume.estimators.closed_form import (  # noqa: E402
    auto_order,
    led_emitters,
    plane_edges,
    product_grid,
    sweep_irradiance,
)
from eyelume.optimize import refine, sweep_leds  # noqa: E402
from eyelume.optimize.sweep import PAPER_GRID  # noqa: E402

TARGET_SWEEP_S = 1.0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--delta", type=float, default=0.3, help="target falloff at the corner")
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()

    info = C.machine()
    C.print_header("LED sweep (385 configurations) and refinement, paper2005", info)
    threads = numba.get_num_threads()

    scene = eyelume.load_scene("paper2005")
    target = gaussian_target(a.delta, scene.eye_plane)
    y, z, t = product_grid(*PAPER_GRID)
    emit, axes = led_emitters(scene.leds, y, z, t)
    xe, ye = plane_edges(scene.eye_plane)
    order = auto_order(xe, ye, emit, axes, scene.leds.profiles())
    n_int = len(y) * scene.leds.count * scene.eye_plane.rows * scene.eye_plane.cols * order**2

    t0 = time.perf_counter()
    first = sweep_leds(scene, target)
    first_s = time.perf_counter() - t0
    sweep = C.timed(lambda: sweep_leds(scene, target), a.repeats, threads)
    irr = C.timed(lambda: sweep_irradiance(scene, *PAPER_GRID), a.repeats, threads)
    b = first.best
    start = (b["height_mm"], b["distance_mm"], b["pitch_deg"])
    t0 = time.perf_counter()
    refined = refine(scene, target, start=start)
    refine_first_s = time.perf_counter() - t0
    ref = C.timed(lambda: refine(scene, target, start=start), a.repeats, threads)

    ok = sweep["best_s"] <= TARGET_SWEEP_S
    print(
        f"   δ = {a.delta}, {len(y)} configurations, {scene.leds.count} LEDs, "
        f"{scene.eye_plane.cols} × {scene.eye_plane.rows} bins, Gauss–Legendre order {order} "
        f"({n_int / 1e6:.1f} M integrand evaluations), {threads} Numba threads"
    )
    print(f"   first call (compile or cache load): {first_s:.3f} s")
    print(
        f"   sweep_leds       best {sweep['best_s']:.3f} s  median {sweep['median_s']:.3f} s  "
        f"spread {sweep['spread_pct']:.0f} %  (target ≤ {TARGET_SWEEP_S} s: "
        f"{'PASS' if ok else 'FAIL'}){C.disturbed(sweep)}"
    )
    print(
        f"   sweep_irradiance best {irr['best_s']:.3f} s  "
        f"({C.fmt_rate(n_int / irr['best_s'])}evaluations/s){C.disturbed(irr)}"
    )
    print(
        f"   best: Y {b['height_mm']:g} mm, Z {b['distance_mm']:g} mm, θ {b['pitch_deg']:g}°, "
        f"merit {b['merit']:.5g}"
    )
    print(
        f"   refine           best {ref['best_s']:.3f} s  median {ref['median_s']:.3f} s "
        f"(first {refine_first_s:.3f} s){C.disturbed(ref)}"
    )
    print("   refined: Y {:.3f} mm, Z {:.3f} mm, θ {:.3f}°, merit {:.5g}".format(*refined))

    def clean(tm: dict) -> dict:
        return {k: v for k, v in tm.items() if k != "last"}

    path = C.append_result(
        "sweep",
        {
            "command": C.command_line(),
            "machine": info,
            "numba_threads": threads,
            "delta": a.delta,
            "configurations": len(y),
            "order": order,
            "integrand_evaluations": n_int,
            "first_call_s": first_s,
            "sweep_leds": clean(sweep),
            "sweep_irradiance": clean(irr),
            "target_sweep_s": TARGET_SWEEP_S,
            "pass": ok,
            "best": b,
            "refine": clean(ref),
            "refine_first_s": refine_first_s,
            "refined": dict(
                zip(("height_mm", "distance_mm", "pitch_deg", "merit"), refined, strict=True)
            ),
            "merit_finite": int(np.isfinite(first.merit).sum()),
        },
    )
    print(f"   appended to {path}")


if __name__ == "__main__":
    main()
