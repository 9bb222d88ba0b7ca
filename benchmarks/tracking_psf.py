"""Tracking on the off-axis presets with and without the camera's diffraction PSF (issue 11).

Run from the repository root::

    python benchmarks/tracking_psf.py --scene vr-offaxis --samples 4
    python benchmarks/tracking_psf.py --scene glasses-frame --samples 2 --no-calibration
    python benchmarks/tracking_psf.py --scene eyetrackvr --samples 2 --no-calibration \
        --cache /tmp/eyelume-frames      # render once, then re-detect from the cache in seconds

What ``eyelume evaluate-tracking`` does per frame — render the gaze (fast estimator, the
``--samples`` per pixel, ``--seed``), read it out with the sensor (:func:`eyelume.detectors.
sensor.digitize`, the same seed), detect and compare with the truth — done twice on ONE render
per gaze: once on the traced picture (``camera.psf = "none"``, the renders before the PSF) and
once on that picture convolved with the preset's diffraction PSF (``camera.psf = "diffraction"``,
the default for an ideal lens). ``render`` applies the PSF in exactly that way after tracing
(the same samples: the pair differs by the PSF alone), so the second column is what
``evaluate-tracking`` gives for the same seed and samples, for half the rendering.

Prints, per gaze of the 7 × 5 test grid (and the 3 × 3 calibration grid unless
``--no-calibration``), whether detection is ``ok`` and else its first failure, each way; then
the summaries of :func:`eyelume.analysis.tracking.evaluate.analyse_frames` (frames ok, pupil
and gaze errors). Appends a JSON line to ``benchmarks/results/tracking_psf.jsonl``.

``--cache DIR`` keeps each gaze's traced irradiance, truth and render time in
``DIR/<scene>_s<samples>_seed<seed>[_<sets hash>]/h<h>_v<v>.npz`` the first time and reads it
back afterwards, so the detector can be re-run on the same frames in seconds (the PSF and the
sensor read-out are redone from the stored irradiance with the same seed: the same pictures).
A frame is written when it is rendered: an interrupted run keeps what it finished.
``--cached-only`` detects on the cached gazes alone (none rendered; the summaries are then over
those frames only, and say how many).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import append_result, loadavg  # noqa: E402


def _git_head() -> str:
    try:
        cmd = ["git", "rev-parse", "--short", "HEAD"]
        out = subprocess.run(cmd, capture_output=True, text=True)
        return out.stdout.strip()
    except OSError:
        return "unknown"


def _cached(cache: Path, h: float, v: float) -> Path:
    """The cache file of gaze (h, v) (it may not exist)."""
    return cache / f"h{h:+.0f}_v{v:+.0f}.npz"


def _traced(cs, args, cache: Path | None, h: float, v: float):
    """The gaze's traced irradiance (rows, cols; W/mm²), truth and render time (s): read from
    the ``cache`` folder when there, else rendered (and stored when ``cache`` is given)."""
    import numpy as np

    import eyelume
    from eyelume.analysis.truth import eye_truth

    cached = None if cache is None else _cached(cache, h, v)
    if cached is not None and cached.exists():
        with np.load(cached) as z:
            return z["eye_image"], json.loads(str(z["truth"])), float(z["render_s"])
    opts = eyelume.RenderOptions(estimator="fast", samples_per_pixel=args.samples, seed=args.seed)
    r = eyelume.render(cs, opts)
    truth = eye_truth(cs)
    if cached is not None:
        tmp = cached.with_name(cached.stem + ".tmp.npz")
        np.savez_compressed(
            tmp, eye_image=r.eye_image, truth=json.dumps(truth), render_s=r.wall_time_s
        )
        tmp.replace(cached)
    return r.eye_image, truth, r.wall_time_s


def _grids(args, ap):
    """The cache folder (or None) and the calibration and test gazes to run (module doc)."""
    from eyelume.analysis.tracking.evaluate import CALIBRATION_H, CALIBRATION_V, TEST_H, TEST_V

    cache = None
    if args.cache is not None:
        name = f"{args.scene}_s{args.samples}_seed{args.seed}"
        if args.set:
            name += "_" + hashlib.sha1("\n".join(sorted(args.set)).encode()).hexdigest()[:8]
        cache = args.cache / name
        cache.mkdir(parents=True, exist_ok=True)
    grid_c = [] if args.no_calibration else [(h, v) for v in CALIBRATION_V for h in CALIBRATION_H]
    grid_t = [(h, v) for v in TEST_V for h in TEST_H]
    if args.cached_only:
        if cache is None:
            ap.error("--cached-only needs --cache")
        grid_c = [g for g in grid_c if _cached(cache, *g).exists()]
        grid_t = [g for g in grid_t if _cached(cache, *g).exists()]
        print(f"cached only: {len(grid_c)} calibration, {len(grid_t)} test gazes", flush=True)
    return cache, grid_c, grid_t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="vr-offaxis")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-calibration", action="store_true")
    ap.add_argument("--set", action="append", default=[], help="dotted.path=value")
    ap.add_argument("--cache", type=Path, default=None, help="folder of rendered frames (npz)")
    ap.add_argument("--cached-only", action="store_true", help="only the gazes in --cache")
    args = ap.parse_args()

    import eyelume
    from eyelume.analysis.tracking.evaluate import (
        analyse_frame,
        led_picture_azimuths,
        led_picture_pattern,
    )
    from eyelume.compile import compile_scene
    from eyelume.detectors.psf import camera_psf, convolve_irradiance
    from eyelume.detectors.sensor import digitize
    from eyelume.scene.io import apply_overrides

    sets = dict(item.split("=", 1) for item in args.set)
    base = eyelume.load_scene(args.scene, sets or None)
    diffraction = apply_overrides(base, {"camera.psf": "diffraction"})
    psf = camera_psf(compile_scene(diffraction))
    assert psf is not None
    print(
        f"{args.scene}: {base.sensor.cols} x {base.sensor.rows}, PSF N_w = "
        f"{psf.working_f_number:.3f}, Airy radius {psf.airy_radius_mm * 1e3:.2f} um "
        f"({psf.airy_radius_mm / psf.pitch_mm[0]:.2f} px), kernel {psf.kernel.shape}, "
        f"centre pixel {psf.kernel[psf.kernel.shape[0] // 2, psf.kernel.shape[1] // 2]:.3f}",
        flush=True,
    )
    cache, grid_c, grid_t = _grids(args, ap)
    out = {"none": ([], []), "diffraction": ([], [])}
    t_start = time.perf_counter()
    for which, grid in ((0, grid_c), (1, grid_t)):
        for h, v in grid:
            gaze = {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v}
            sc = apply_overrides(base, {**gaze, "camera.psf": "none"})
            cs = compile_scene(sc)
            eye_image, truth, render_s = _traced(cs, args, cache, h, v)
            az, pattern = led_picture_azimuths(cs), led_picture_pattern(cs)
            line = f"{'calib' if which == 0 else 'test '} ({h:+.0f}, {v:+.0f}):"
            for kind, img in (("none", eye_image), ("diffraction", None)):
                if img is None:
                    img = convolve_irradiance(eye_image, psf)
                d = digitize(img, sc.sensor, sc.wavelength_nm, seed=args.seed)
                f = analyse_frame(
                    (h, v), d.counts, truth, az, render_s=render_s, led_pattern_px=pattern
                )
                f.saturated_share = d.saturated_pixels / d.counts.size
                out[kind][which].append(f)
                fails = [x for x in f.detection.failures if not x.startswith("warning")]
                state = "ok" if f.detection.ok else (fails[0] if fails else "not ok")
                line += f"  {kind}: {state} [{f.glints_found}/{f.glints_true} glints]"
            print(line, f"({time.perf_counter() - t_start:.0f} s)", flush=True)
    record = {
        "script": "tracking_psf.py",
        "commit": _git_head(),
        "scene": args.scene,
        "sets": args.set,
        "samples": args.samples,
        "seed": args.seed,
        "calibration": not args.no_calibration,
        "cached_only": args.cached_only,
        "loadavg": loadavg(),
        "wall_s": round(time.perf_counter() - t_start, 1),
        "psf": psf.summary(),
    }
    _report(base, out, record)


def _report(base, out: dict, record: dict) -> None:
    """Each way's frames ok and summary, printed and appended to the results."""
    from eyelume.analysis.tracking.evaluate import analyse_frames
    from eyelume.compile import compile_scene
    from eyelume.json_files import finite_or_null

    leds = compile_scene(base).led.points
    for kind, (calib, frames) in out.items():
        s = analyse_frames(base, leds, frames, calib).summary
        ok = [list(f.gaze) for f in frames if f.detection.ok]
        record[kind] = {"frames_ok": ok, "summary": s}
        print(f"{kind}: {len(ok)}/{len(frames)} test frames ok: {ok}")
        print(f"  summary: { {k: s[k] for k in list(s)[:8]} }")
    path = append_result("tracking_psf", finite_or_null(record))
    print(f"appended to {path}")


if __name__ == "__main__":
    main()
