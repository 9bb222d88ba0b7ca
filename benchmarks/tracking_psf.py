"""Tracking on the off-axis presets with and without the camera's diffraction PSF (issue 11).

Run from the repository root::

    python benchmarks/tracking_psf.py --scene vr-offaxis --samples 4
    python benchmarks/tracking_psf.py --scene glasses-frame --samples 2 --no-calibration

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
"""

from __future__ import annotations

import argparse
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="vr-offaxis")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-calibration", action="store_true")
    ap.add_argument("--set", action="append", default=[], help="dotted.path=value")
    args = ap.parse_args()

    import eyelume
    from eyelume.analysis.tracking.evaluate import (
        CALIBRATION_H,
        CALIBRATION_V,
        TEST_H,
        TEST_V,
        analyse_frame,
        led_picture_azimuths,
    )
    from eyelume.analysis.truth import eye_truth
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
    grid_c = [] if args.no_calibration else [(h, v) for v in CALIBRATION_V for h in CALIBRATION_H]
    grid_t = [(h, v) for v in TEST_V for h in TEST_H]
    out = {"none": ([], []), "diffraction": ([], [])}
    t_start = time.perf_counter()
    for which, grid in ((0, grid_c), (1, grid_t)):
        for h, v in grid:
            gaze = {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v}
            sc = apply_overrides(base, {**gaze, "camera.psf": "none"})
            cs = compile_scene(sc)
            opts = eyelume.RenderOptions(
                estimator="fast", samples_per_pixel=args.samples, seed=args.seed
            )
            r = eyelume.render(cs, opts)
            truth, az = eye_truth(cs), led_picture_azimuths(cs)
            line = f"{'calib' if which == 0 else 'test '} ({h:+.0f}, {v:+.0f}):"
            for kind, img in (("none", r.eye_image), ("diffraction", None)):
                if img is None:
                    img = convolve_irradiance(r.eye_image, psf)
                d = digitize(img, sc.sensor, sc.wavelength_nm, seed=args.seed)
                f = analyse_frame((h, v), d.counts, truth, az, render_s=r.wall_time_s)
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
