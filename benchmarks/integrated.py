"""The paper's integrated ET-HMD (``paper2005-integrated``, its Fig. 1) against ``paper2005`` at
the same noise (issue 14): the paper's point was that the eyepiece's large F-number would cost
forward ray tracing ~100×; the camera-side estimator should not pay it.

Run from the repository root::

    python benchmarks/integrated.py                 # ~3 min on 2 shared cores
    python benchmarks/integrated.py --fwd-rays 2e6 --repeats 2
    python benchmarks/integrated.py --start-spp 32  # only from the presets' own first round

For each preset at its own resolution (paper2005 87 × 65, paper2005-integrated 160 × 120) and
each first round S of ``--start-spp`` (default 8 and 32):
``render(cs, RenderOptions(estimator="fast", rel_error=0.01, samples_per_pixel=S, seed=1))``
— the fast estimator's first round is S samples per pixel, then it adds rounds until the
median skin pixel's relative standard error is ≤ 1 % (the skin mask follows the hot mirror's
fold) — timed over ``--repeats`` calls after a warm-up (``_common.timed``: best wall time,
process CPU time, disturbance flags), with the samples per pixel it chose and the error it
reached. Each preset's figure is its cheaper start: 8 is the least a fast render runs (2 sets
of 2 × 2), where a preset that needs few samples stops; 32 (the presets' own
``run.samples_per_pixel``) stratifies in 4 × 4 sets, which paper2005 needs (from 8 its rounds
of 2 × 2 sets end at 48 samples per pixel and more CPU). A run that ends below 1 % did more
work than the target needs, so beside the CPU ratio the ratio at equal noise is given too:
CPU × error² (the camera samples' variance falls as 1 / samples), a prediction from the
measured figures. Forward on ``paper2005-integrated``: one render of
``--fwd-rays`` rays, its counts in the median skin pixel, and the forward time a 1 % median skin
pixel would take, predicted from Poisson statistics (1 % needs 10⁴ counts) with the expected
counts per ray from the fast image (E · A_pixel / power per ray). Prints the figures and the
command, appends a JSON line to ``benchmarks/results/integrated.jsonl`` and writes the two eye
images the README shows (``docs/figures/integrated_eye_image.png``,
``docs/figures/paper2005_eye_image_1pct.png``: grey, linear, clipped at the 99.5th percentile).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import _common as C

os.environ.setdefault("NUMBA_CACHE_DIR", str(C.WARM_CACHE))

import numpy as np  # noqa: E402

SCENES = ("paper2005", "paper2005-integrated")
FIGURES = {
    "paper2005": C.REPO / "docs" / "figures" / "paper2005_eye_image_1pct.png",
    "paper2005-integrated": C.REPO / "docs" / "figures" / "integrated_eye_image.png",
}


def _skin_error(res) -> float:
    from eyelume.estimators.statistics import median_pixel_rel_error

    skin = res.regions["skin"]
    return median_pixel_rel_error(res.eye_image[skin], res.eye_image_variance[skin])


def _fast(name: str, repeats: int, threads: int, start_spp: int) -> dict:
    import eyelume
    from eyelume.compile import compile_scene

    cs = compile_scene(eyelume.load_scene(name))
    opt = eyelume.RenderOptions(
        estimator="fast", rel_error=0.01, samples_per_pixel=start_spp, seed=1
    )
    t = C.timed(lambda: eyelume.render(cs, opt), repeats, threads)
    res = t.pop("last")
    cpu = [w * u * threads for w, u in zip(t["walls_s"], t["cpu_util"], strict=True)]
    return {
        "scene": name,
        "start_samples_per_pixel": start_spp,
        "cpu_s": min(cpu),
        "picture": [cs.picture.cols, cs.picture.rows],
        "call": t,
        "samples_per_pixel": res.samples_per_pixel,
        "light_paths": res.light_paths,
        "skin_median_pixel_rel_error": _skin_error(res),
        "skin_pixels": int(res.regions["skin"].sum()),
        "rel_error_achieved": res.rel_error_achieved,
        "target_reached": res.target_reached,
        "image": res.eye_image,
        "pixel_area_mm2": res.pixel_area_mm2,
        "skin": res.regions["skin"],
    }


def _forward(rays: int, fast: dict) -> dict:
    import eyelume
    from eyelume.compile import compile_scene

    cs = compile_scene(eyelume.load_scene("paper2005-integrated"))
    t0, c0 = time.perf_counter(), time.process_time()
    res = eyelume.render(cs, eyelume.RenderOptions(estimator="forward", rays=rays, seed=1))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    skin = fast["skin"]
    per_ray = fast["image"][skin] * fast["pixel_area_mm2"] / res.ray_power_w / rays
    median_per_ray = float(np.median(per_ray))
    need = 1e4 / median_per_ray  # rays for 10⁴ counts in the median skin pixel
    return {
        "rays": rays,
        "wall_s": wall,
        "cpu_s": cpu,
        "median_skin_counts": float(np.median(res.image_counts[skin])),
        "expected_median_skin_counts": median_per_ray * rays,
        "rays_for_1pct": need,
        "predicted_wall_s_for_1pct": wall * need / rays,
        "predicted_cpu_s_for_1pct": cpu * need / rays,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--fwd-rays", type=float, default=4e6)
    ap.add_argument("--start-spp", type=int, nargs="+", default=[8, 32], help="first rounds to try")
    args = ap.parse_args()
    info = C.machine()
    C.print_header("paper2005-integrated against paper2005 at 1 % median skin error", info)
    import eyelume

    threads = int(os.environ.get("NUMBA_NUM_THREADS", os.cpu_count() or 1))
    for name in SCENES:  # warm-up: compile or load the kernels, untimed
        eyelume.render(
            eyelume.load_scene(name, {"sensor.cols": 16, "sensor.rows": 12}),
            eyelume.RenderOptions(estimator="fast", samples_per_pixel=4),
        )
    from eyelume.report.plots import save_grey_png

    out, record = {}, {"machine": info, "command": C.command_line()}
    for name in SCENES:
        runs = [_fast(name, args.repeats, threads, start) for start in args.start_spp]
        for r in runs:
            call = r["call"]
            print(
                f"   {name:21s} {r['picture'][0]}×{r['picture'][1]}, first round "
                f"{r['start_samples_per_pixel']}: fast to 1 %: best {call['best_s']:.2f} s "
                f"wall, {r['cpu_s']:.2f} CPU-s, {r['samples_per_pixel']} samples/pixel, median "
                f"skin pixel {100 * r['skin_median_pixel_rel_error']:.3f} % over "
                f"{r['skin_pixels']} skin pixels{C.disturbed(call)}"
            )
        out[name] = min(runs, key=lambda r: r["cpu_s"])
        save_grey_png(out[name]["image"], FIGURES[name])
        strip = ("image", "skin")
        record[name] = {k: v for k, v in out[name].items() if k not in strip}
        record[name]["runs"] = [{k: v for k, v in r.items() if k not in strip} for r in runs]
    fwd = _forward(int(args.fwd_rays), out["paper2005-integrated"])
    record["forward_integrated"] = fwd
    a, b = out["paper2005"], out["paper2005-integrated"]
    ratio_px = b["cpu_s"] / a["cpu_s"] / (b["skin_pixels"] / a["skin_pixels"])
    record["cpu_ratio"] = b["cpu_s"] / a["cpu_s"]
    record["cpu_ratio_per_skin_pixel"] = ratio_px
    noise = (b["skin_median_pixel_rel_error"] / a["skin_median_pixel_rel_error"]) ** 2
    record["cpu_ratio_at_equal_noise"] = record["cpu_ratio"] * noise
    print(
        f"   integrated / paper2005 (each from its cheaper first round, "
        f"{a['start_samples_per_pixel']} and {b['start_samples_per_pixel']}): "
        f"{record['cpu_ratio']:.2f}× the CPU time, "
        f"{ratio_px:.2f}× per skin pixel (the pictures differ in size); at equal noise "
        f"(CPU × error²): {record['cpu_ratio_at_equal_noise']:.2f}×"
    )
    print(
        f"   forward, paper2005-integrated, {fwd['rays']:.3g} rays: {fwd['wall_s']:.1f} s wall; "
        f"median skin pixel {fwd['median_skin_counts']:.0f} counts "
        f"(expected {fwd['expected_median_skin_counts']:.2f}); 1 % would need "
        f"{fwd['rays_for_1pct']:.3g} rays ≈ {fwd['predicted_cpu_s_for_1pct'] / 3600:.1f} CPU-h "
        f"({fwd['predicted_cpu_s_for_1pct'] / b['cpu_s']:.0f}× the fast estimator)"
    )
    record["forward_over_fast_cpu"] = fwd["predicted_cpu_s_for_1pct"] / b["cpu_s"]
    path = C.append_result("integrated", record)
    print(f"   appended {path.relative_to(C.REPO)}; wrote the eye images to docs/figures/")


if __name__ == "__main__":
    sys.exit(main())
