"""Where a fast render's CPU time goes (issue 11): the camera pass, the light pass and the rest.

Run from the repository root::

    python benchmarks/render_split.py                       # vr-offaxis, rel_error 0.01
    python benchmarks/render_split.py --scene paper2005 --repeats 3

On one thread (``NUMBA_NUM_THREADS=1`` unless set; the script starts itself again with it and
the benchmarks' warm Numba cache, ``_common.WARM_CACHE``, so CPU seconds are the work's and
not the machine's share of two cores), ``render(cs, RenderOptions(estimator="fast",
rel_error=…, seed=…))`` after a warm-up render, each call's process CPU time
(``time.process_time``) split by wrapping the fast estimator's kernels and the render's steps:
the camera pass (``fast.camera_pass`` outside the pilot), the pilot (``fast_run._pilot``), the
light pass (``fast.light_pass``), the eye plane (``direct_eye_plane``), the region map
(``region_masks``), the PSF's convolutions (``convolve_irradiance``/``convolve_variance``/
``convolve_with_points``)
and the statistics (``_Run.estimate``); "other" is the rest of the call. Also the samples per
pixel and light paths the run chose and the median pixel's relative error per region of the
delivered picture. Prints one line per repeat and appends a JSON line per repeat to
``benchmarks/results/render_split.jsonl``.

Measured (vr-offaxis, one thread, load ~10, 5207e6e, before the glint aim): 11.65 CPU-s —
camera pass 9.82 (84 %), light pass 1.30 (11 %: 640 000 paths, 160 000 of them the floor of
dcd6f2b), pilot 0.15, eye plane 0.13, region map 0.07, PSF 0.11, statistics 0.04.
At 24ba11f (load 8–11): 8.88 / 8.98 CPU-s, 3 samples/pixel + 480 000 light paths — camera pass
7.23 (81 %), light pass 1.08; with the preset's continuation grid 5 (4 on the iris), interleaved:
7.12 CPU-s (−20 %), 2 samples/pixel + 320 000 light paths — camera pass 6.01, light pass 0.63.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import time

import _common as C

if "NUMBA_NUM_THREADS" not in os.environ or "NUMBA_CACHE_DIR" not in os.environ:
    # Numba reads both when it loads (importing _common loaded it): start again with them
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    os.environ.setdefault("NUMBA_CACHE_DIR", str(C.WARM_CACHE))
    os.execv(sys.executable, [sys.executable, *sys.argv])

from eyelume.compile import compile_scene  # noqa: E402
from eyelume.estimators import fast as F  # noqa: E402
from eyelume.estimators import fast_run as FR  # noqa: E402
from eyelume.estimators.statistics import median_pixel_rel_error  # noqa: E402
from eyelume.render import RenderOptions  # noqa: E402
from eyelume.scene.io import load_scene  # noqa: E402

R = importlib.import_module("eyelume.render")  # the module (eyelume.render is the function)


class Split:
    """CPU seconds per step of a render, by wrapping the functions each step calls."""

    def __init__(self) -> None:
        self.cpu: dict[str, float] = {}
        self.in_pilot = False

    def _add(self, key: str, seconds: float) -> None:
        self.cpu[key] = self.cpu.get(key, 0.0) + seconds

    def wrap(self, module, name: str, key) -> None:
        orig = getattr(module, name)

        def timed(*args, **kwargs):
            c0 = time.process_time()
            out = orig(*args, **kwargs)
            self._add(key() if callable(key) else key, time.process_time() - c0)
            return out

        timed.signatures = getattr(orig, "signatures", None)
        setattr(module, name, timed)

    def install(self) -> None:
        orig_pilot = FR._pilot

        def pilot(*args, **kwargs):
            self.in_pilot = True
            try:
                return orig_pilot(*args, **kwargs)
            finally:
                self.in_pilot = False

        FR._pilot = pilot
        self.wrap(F, "camera_pass", lambda: "pilot" if self.in_pilot else "camera pass")
        self.wrap(F, "light_pass", "light pass")
        self.wrap(R, "direct_eye_plane", "eye plane")
        self.wrap(R, "region_masks", "region map")
        self.wrap(R, "convolve_irradiance", "PSF")
        self.wrap(R, "convolve_variance", "PSF")
        if hasattr(R, "convolve_with_points"):  # glints spread from their place (session 15)
            self.wrap(R, "convolve_with_points", "PSF")
        self.wrap(FR._Run, "estimate", "statistics")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="vr-offaxis")
    p.add_argument("--rel-error", type=float, default=0.01)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--repeats", type=int, default=1)
    a = p.parse_args()
    info = C.machine()
    C.print_header(f"render split: {a.scene}, rel_error {a.rel_error}", info)
    cs = compile_scene(load_scene(a.scene))
    opt = RenderOptions(estimator="fast", rel_error=a.rel_error, seed=a.seed)
    R.render(cs, opt)  # warm-up: kernels compiled or loaded
    split = Split()
    split.install()
    regions = R.region_masks(cs)
    for _ in range(a.repeats):
        split.cpu.clear()
        c0, t0 = time.process_time(), time.perf_counter()
        res = R.render(cs, opt)
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
        parts = dict(split.cpu)
        parts["other"] = cpu - sum(parts.values())
        img, var = res.eye_image, res.eye_image_variance
        noise = {}
        for name in ("skin", "iris", "sclera", "pupil"):
            m = regions[name] & (img > 0)
            if m.any():
                e = median_pixel_rel_error(img[m], var[m], res.variance_dof)
                noise[name] = round(float(e), 5)
        text = ", ".join(f"{k} {v:.2f}" for k, v in sorted(parts.items(), key=lambda kv: -kv[1]))
        print(
            f"{a.scene}: {cpu:.2f} CPU-s ({wall:.1f} s wall), {res.samples_per_pixel} samples/"
            f"pixel, {res.light_paths} light paths, error {res.rel_error_achieved:.4f}: {text}"
        )
        print(f"  median pixel error per region: {noise}")
        C.append_result(
            "render_split",
            {
                "machine": info,
                "command": C.command_line(),
                "scene": a.scene,
                "threads": int(os.environ["NUMBA_NUM_THREADS"]),
                "cpu_s": cpu,
                "wall_s": wall,
                "split_cpu_s": parts,
                "samples_per_pixel": res.samples_per_pixel,
                "light_paths": res.light_paths,
                "rel_error_achieved": res.rel_error_achieved,
                "median_error": noise,
                "load_after": C.loadavg(),
            },
        )


if __name__ == "__main__":
    main()
