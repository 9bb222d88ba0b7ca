"""Pupil and glint detection (issues 5, 13): ms per frame on one core. Target ≤ 5 ms (640 × 400).

Run from the repository root::

    python benchmarks/detect.py                       # synthetic frame only, ~5 s
    python benchmarks/detect.py --render              # + a paper2005 render (~30 s once)
    python benchmarks/detect.py --frame DIR           # + an existing render's output directory
    python benchmarks/detect.py --real                # + real pictures' sizes (../shared/realdata)
    python benchmarks/detect.py --population 3        # + 3 vr-offaxis frames of sampled people

:func:`eyelume.analysis.tracking.detect` alone (with the four LED azimuths, so the matching is
included) on one core (``cv2.setNumThreads(1)``), after ``--warmup`` calls: best, median and
worst of ``--repeats`` (50) calls on the same frame, and the median of each stage's share
(``Detection.timings_ms``). The verdict is on the median CPU time of the calls
(``time.process_time``: time on the one core; the wall time is shown beside it, not judged);
for the real pictures on the slowest 640 × 400 picture's median. Frames:

- ``synthetic``: ``draw_eye()`` of ``tests/analysis/test_detect.py`` (the tests' picture: a
  112 × 100 px pupil, 4 saturated glints, blur σ 1.5 px, noise σ 8 DN, 10-bit), its truth known;
  at 640 × 480 and at 640 × 400 (a headset eye camera's frame, issue 13's target size).

Besides wall time (best, median, worst) the median and the best CPU time of the process per
call (``time.process_time``) are printed: on a shared machine wall times include waiting for a
core, and even CPU times grow with the load (caches and the core shared with other processes):
the best of many calls is the nearest to an idle machine's figure; the load average at the start
is stored with the result.
- ``render``: ``eye_image_digital.npy`` (uint16 DN, 10 bit) of ``eyelume render --set
  sensor.cols=640 --set sensor.rows=480 --samples 8`` (``--render`` makes one in a temporary
  directory; ``--frame DIR`` uses yours); errors against the render's ``truth.json`` when there.
- ``person-<k>`` (``--population N``): the digital picture (DN, 400 × 400) of a test frame of
  ``vr-offaxis``'s sampled person k (population seed 1; person k at the k-th test gaze of
  ``evaluate-tracking --population``: (−10°, −5°), (0°, −5°), (10°, −5°), …), rendered as
  that command renders it (to the sensor's noise, the irradiance cache on) with its lashes,
  lids and 8 LEDs, detected with its own LED azimuths and picture pattern; errors against its
  truth. Not the issue's 640 × 400, but eyelume's own headset frame: the faint blobs near the
  pupil that its lashes leave (~23 a frame) each take a fit (:func:`~eyelume.analysis.
  tracking.glints.fit_spot`), which the synthetic frame never asks for.
- ``real-<source>`` (``--real N``, N = 5 by default): N pictures of each source of
  ``realdata/labels.csv`` (found as ``benchmarks/detect_real.py`` finds it; skipped with a
  message when absent), evenly spread over its rows — the ``itmo`` close-ups (200 × 200, 8 bit)
  and the ``openeds`` headset frames (640 × 400, 8 bit) — without LED azimuths (the pictures
  have no LED layout). Per source: the median over the pictures of each one's median CPU and
  wall time per call, the slowest picture's, and how many were answered ``ok``. The pictures
  are read where they are; only these aggregates are printed and stored (no picture, crop or
  per-picture figure: the data set is for internal evaluation only).

Prints the figures and how they were run, and appends a JSON line to
``benchmarks/results/detect.jsonl``.

On a shared machine compare two trees by interleaving, not by runs at different times: session
13's cuts (77c21a9, c483419, 76c9b61, 0d1d8da) against 87de5c5, two worker processes alternating
batches of 20 ``detect()`` calls per frame for 30 rounds, one thread, load 8–10, median CPU per
call new / old (these frames, LEDs given for the synthetic ones): synthetic 640 × 400 0.93 (4.39
vs 4.71 ms), 640 × 480 0.94, openeds 000160 0.98 (5.16 vs 5.27 ms; the slowest frame: a lid-cut
pupil whose robust fit tries 26 run hypotheses), 000170 0.96, 000180 0.98 — ratios under load,
not quiet-machine figures.

History (figures once in the README's speed row). Session 12, quiet machine (load 1.3–1.4,
41dd02c, 05:22 UTC): synthetic 640 × 400 4.98 ms CPU per call (median of 20; best 4.49; normalise
0.35, glints 1.36, pupil 2.95, match 0.26), 640 × 480 7.20 ms (a disturbed median), openeds 3.98
ms median over its 3 frames (the slowest 5.12), itmo 200 × 200 2.53 ms; at 24ba11f (03:48 UTC)
synthetic 4.91 ms, openeds 4.52 (slowest 5.65). Session 12's cuts (e09aad6: the glints' box mean
from an integral image only where it is compared, the ladder's 5 × 5 area reduction as block
means, the hot-pixel test compiled; 8562ede: the glints' 8-bit histogram, the LEDs' matching
angle remembered), ``detect()``'s answers identical on 280 pictures: interleaved A/B against
24ba11f, load 7–11, best call synthetic ×0.9, openeds ×0.93–0.97. A Numba port of
``cv2.fitEllipse`` (3× faster a fit) was reverted (179299a): outside the physics a library beats
our own copy of it. Session 13's cuts above (answers identical on 589 (picture, LEDs) pairs: the
255 realdata pictures, 144 renders 87 × 65 to 1024 × 768, 23 synthetic): the glints' closing and
outlines only on the box of the glint pixels found, no refit of the very points a fit was made
to, 16-bit labels for the glint fill, the 16-bit picture's glint smoothing by
``cv2.sepFilter2D``, the ladder's dark levels labelled on the box of their dark pixels.

Tried and not kept (session 13, det13b): scoring the robust fit's run hypotheses
(``pupil._best_run``) with fits on every 2nd or 3rd point of each run, refitting on all points
those within 5 % of the outline's points of the best. ``cv2.fitEllipse`` costs ~8 µs a call plus
~0.2 µs a point (19 µs at 47 points, 24 at 79), so a thinned fit saves ~10 µs and the refits and
second scoring take it back: interleaved A/B (two processes alternating batches of 20 calls, 20
rounds, one thread, load 6–7), median CPU per call new / old on openeds 000160 1.05 (every 2nd
point; faster in 4 rounds of 20) and 1.02 (every 3rd; in 1 of 20). And the answers change: a
run's spread about its own fit sets the edge noise σ (the smallest over the runs) and with it
the inlier tolerance, so every hypothesis' fit counts, not only the winner's — 6 of 279 answers
changed (the 255 realdata pictures, 24 synthetic), one itmo picture from ``ok`` to "pupil cut or
hidden".

Session 16 (2fdff8b): the one-pixel-glint search near the pupil (``glints.glints_near``, run on
a smoothed picture without LEDs: the real frames) works out only the blobs its caller can take
(≤ 2 px, peak at the top), not every blob's skirt and centroid; answers byte-identical on the
255 realdata pictures and paper2005's 315-answer grid. Interleaved A/B against 9ba1345 (two
processes alternating batches of 40 calls, 4 rounds, one thread, load 4–6), median CPU ms per
call old / new: openeds 000160 5.98/5.73, 5.90/5.62, 5.94/5.56, 7.25/5.56; 000170 4.71/4.54,
4.69/4.40, 4.67/4.43, 5.73/5.54; 000180 4.43/4.34, 4.36/4.19, 4.50/4.40, 5.36/4.23; synthetic
640 × 400 (LEDs given: the search was already skipped) 4.78/4.85, 4.62/4.67, 4.62/4.62,
5.71/4.62. Where 000160's 5.6 ms goes (one thread, CPU, each step's own clock): the robust fit
1.28 ms (its 24 run hypotheses 0.89), the glints' step 2 1.09 (Gaussian 0.23, bright masks
0.33), the working picture 0.61, the ladder 0.55, the glint fill 0.40, the full-resolution
blob 0.33; nothing there repeats work the answer does not use.

Session 17 (3e8827d, 346e3e6, f57eade; answers identical on 613 (picture, LEDs) pairs: the 255
realdata pictures, 144 renders 87 × 65 to 1024 × 768, 24 synthetic frames with and without
LEDs, 24 close-ups): the glints' one-pixel search reuses its ``DetectParams``
(``dataclasses.replace`` of 66 fields, ~40 µs a frame) and leaves out, before drawing its mask,
a blob whose outline alone has more pixels than the largest area it takes (8, 7, 3 of the ~10
a frame on the openeds frames); a dark blob's big bright neighbours labelled on the glints' box,
not the blob's whole window (~0.15 ms on the synthetic frame); the working picture's scale
taken from step 1 (the 99th percentile counted with the hot pixels' 99.9th over the same
pixels, step 1's min and max) when no pixel is missing or mended. Interleaved A/B against
2ebea58 (two processes alternating batches of 15 calls per frame, 12 rounds, one thread, load
1.3), median CPU ms per batch old/new: synthetic 640 × 400 5.67/6.11, 5.06/4.54, 4.70/4.40,
4.77/4.35, 5.66/4.37, 4.99/5.34, 6.35/4.39, 5.06/4.49, 5.07/4.61, 4.48/4.24, 4.50/4.18,
4.56/4.33 (median ratio 0.92; best call 4.36 → 3.93); openeds 000160 5.55/7.97, 5.94/5.74,
6.23/5.75, 5.89/5.86, 6.63/7.41, 7.74/7.90, 6.17/5.96, 8.26/5.54, 5.74/5.40, 5.43/5.38,
5.48/5.93, 5.77/5.39 (0.98; 5.30 → 5.16); 000170 0.945 (4.21 → 4.01); 000180 0.935 (4.04 →
3.84). Tried and not kept: working out step 2's blobs (skirt, centroid) only for those near
the pupil found — on these frames every blob is within the search radius (2 × the pupil's
major axis, 115 px) and passes, so nothing was saved. Not cut, as the answers would change:
000160's 26 run hypotheses (one ``cv2.fitEllipse`` each, ~0.5 ms: each run's spread about its
own fit can set σ, and every fit's inlier count can win). The rest is spread over ~40 steps of
0.03–0.3 ms each (whole-frame OpenCV passes: the glints' Gaussian, 8-bit scaling and histogram,
the ladder's 7–13 labellings, the glints' fill), none repeating work the answer does not use.

Session 18 (0f0c96f): the robust fit's run hypotheses (``pupil._best_run``) stop once they can no
longer matter — with 3σ under the tolerance's floor (no later run can move it), a 50 % run whose
fit holds ≥ 85 % of the outline ends the search, and the 30 % runs are left out when the best so
far holds ≥ 60 % — and ``darker_core`` works out the interior's noise only when its 5th percentile
is near the black level. A quality rule, not an identity: answers identical on the 613 (picture,
LEDs) pairs (their 144 robust fits: 2194 ``cv2.fitEllipse`` calls instead of 3896; 000160 fits 4
runs instead of 26); a stop at 80 % changed one itmo answer (0.17 px farther from its annotation).
Interleaved A/B against 1f7bafa (two processes alternating batches of 15 calls per frame, 12
rounds, one thread, load 6–7), median CPU ms per batch old/new: openeds 000160 8.52/7.28,
8.79/7.64, 9.09/7.50, 8.42/7.34, 7.74/6.54, 8.41/7.51, 6.94/6.87, 8.75/8.02, 8.76/7.42, 8.16/6.21,
7.38/6.19, 8.13/5.93 (median ratio 0.851; best call 5.52 → 4.96); 000170 1.011 (4.58 → 4.29),
000180 1.010 (4.65 → 4.34), synthetic 640 × 400 0.992 (4.39 → 4.34): the slowest frame's excess
over the others is gone, the others are untouched. Then (``pupil._label_type``; the same answers on
the 613 pairs): 16-bit labels for the glints beside the dark blob and those joined to it (32-bit
labelling is ~2× slower here; the same labels), and the glint fill labels the glints' box, not the
roi padded by their reach (000160: 24 instead of 65 µs). Interleaved A/B against 334c439 (as above,
load 4.6–5), median CPU ms per batch old/new: 000160 5.73/5.65, 5.40/5.57, 5.46/5.84, 5.44/5.20,
8.42/8.21, 7.99/7.59, 8.34/8.32, 8.36/7.44, 7.94/7.74, 8.67/8.20, 6.86/6.31, 7.99/6.54 (median
ratio 0.966; best call 4.93 → 4.69); 000170 0.935 (4.44 → 4.20), 000180 0.965 (4.30 → 3.97),
synthetic 640 × 400 0.984 (4.37 → 4.28) — more than the ~0.1 ms these labellings measure alone (the
machine's noise is of that size). Where a 640 × 400 frame's time goes now, by cProfile's own time
on 000170: the ladder's 16 labellings of the 128 × 80 picture ~0.6 ms (each of the whole picture:
from the 4th level on its dark pixels, 12–27 % of it, span every row), the glints' Gaussian ~0.35,
the glint fill ~0.3 (8 glints, ~10 OpenCV calls each), and the glint blobs' skirts and centroids
(10 blobs, ~20 OpenCV and NumPy calls each). Looked at and left (each exact cut found there saves
under 0.05 ms): the glints' Gaussian is already ``sepFilter2D`` with GaussianBlur's own 9-tap
kernel (the same floats) and its histogram, range and bright mask need the whole frame; a
one-pixel-glint blob whose box holds no pixel at the top (0–1 a frame on openeds) could skip its
mask; the glints' fill is ~40–60 µs a glint (under load) of ~10 OpenCV calls on small windows.

Session 19 (det19). Kept, 3e241d3 (det19's 82849f4): the
glints' smoothed float picture (1 MB at 640 × 400) freed once its 8-bit copy is made instead of
at ``find_glints``' return: held through the blob search, it lifted each frame's peak of
short-lived memory past glibc's trim threshold in a process given only 640 × 400 8-bit frames —
as a tracker is — so the heap was handed back and taken again page by page every frame: ~500
minor page faults a call (``getrusage``), none since. Concurrent pair of two such processes
(each frame 40 calls in a row after 3, one thread) before/after, median CPU ms per call:
000160 4.30/3.61, 000170 3.83/3.14, 000180 3.70/3.08 (twice, within 0.07 ms). This script runs
the synthetic frames (16-bit, their float copies larger) first, which lifts glibc's thresholds:
its openeds figures never had those faults and do not show that gain. Measured and not kept:
the ladder's levels from one hand-written component tree (a union-find over the reduced
picture's pixels taken darkest first, reproducing OpenCV's labels) instead of 13–16
``cv2.connectedComponentsWithStats``: the same answers, the ladder 0.33–0.39 → 0.18 ms, but the
whole call only 3–5 % faster on the openeds frames (concurrent pair, median CPU ms per call
3.90/3.78, 3.48/3.31, 3.35/3.21; synthetic 640 × 400 3.53/3.57) for ~280 lines of our own code
in place of OpenCV's, and the target is met without it. The glint fill's masked minimum by
``cv2.min`` + ``cv2.copyTo``: the same bytes, ~10 µs a frame, not kept.
Figures at 3e241d3 (03:00 UTC, load 1.05, another benchmark on the other core,
``NUMBA_NUM_THREADS=1 python benchmarks/detect.py --repeats 100 --real``): synthetic 640 × 400
3.52 ms CPU median (best 3.31), 640 × 480 3.90; openeds 3.48 / 3.95 ms median frame / slowest
(best calls 3.30 / 3.82); itmo 1.81 / 2.06.

Session 23 (spd23; answers identical on 1045 (picture, LEDs) pairs: the 255 realdata pictures,
cases21/22's pictures with and without their LEDs, renders and JPEG/stray variants, synthetic 640 ×
480 / 400): session 22 added ~0.3–0.5 ms a 640 × 400 frame (the glints' local ring noise, ~11 calls
a frame at ~18 µs, the stray checks, the pupil's core checks). Cut: the ring noise compiled end to
end (the other blobs' dilation looked up at the ring's pixels, sectors by sign tests, per-sector
runs with in-place medians: 18 → 8 µs a call) and skipped for a blob already under the bar;
``in_bright_run`` compiled (a flood fill for ``cv2.connectedComponents``: 0.28 → 0.04 ms a frame on
the slowest openeds frame); ``np.percentile`` in the core checks by ``pupil.float_percentiles``
(NumPy's floats to the bit, 30 → 8–13 µs a call); the glints' wanted-area check's ``np.unique``
compiled. Concurrent one-thread pair against ad52770 (3 rounds × 60 calls per frame, load 15),
median CPU ms per call old / new: synthetic 640 × 400 7.84 / 7.23, openeds 7.74 / 6.99, 6.98 / 6.32,
6.71 / 5.96; with the last cut too (bc6265b, load 19–26, the test suite running) 8.38 / 7.64, 8.16 /
7.24, 7.40 / 6.67, 7.16 / 6.72 (×0.89–0.94: a loaded machine's figures, ~1.5 × a quiet one's; on
ad52770's quiet 5.01 ms slowest openeds frame ×0.89 would be ~4.45 ms — not measured quiet). Where a
frame goes now (the slowest openeds frame, one process, CPU, load ~10; each step's own clock): the
pupil 3.2 ms (the candidates' fit 1.5: robust fit 0.6, full-resolution blob 0.3; the core checks
0.55, whose interior and 5 × 5 box averages are worked out twice, by ``_smoothed_bright_core`` and
``darker_core``; the working picture 0.5; the ladder 0.5), the glints 1.4 (Gaussian 0.26, bright
masks 0.37, blobs 0.6), the one-pixel search 0.4.

Session 25 (spd25; answers identical, ``repr`` of every ``Detection`` but its timings, on 357
(picture, LEDs) pairs: the 255 realdata pictures (openeds with and without 4 LEDs), the
synthetic 640 × 480 / 400 frames, 16 ``draw_eye`` sets × 3 LED cases, 12 of
``test_detect_pupil_cases3``'s eyes and 10 of ``test_detect_glint_match``'s, each with and
without LEDs, and a NaN, a tiny and a flat picture). Cut: ``pupil.edge_profile``'s sample
points (the float32 maps, their extent, the shift into the window and the off-window test)
compiled in two passes instead of six NumPy temporaries, and its line spread worked out once
(``EdgeProfile.g``; ``_ring_inside`` and ``edge_offset`` each made it again, ``np.pad``'s ~20 µs
by a concatenate); old and new ``edge_profile`` identical on 240 cases (the frames' own and
random ellipses, with and without glints and missing pixels), one process, alternated, median
CPU ms old/new (load ~11): synthetic 640 × 400 1.51 / 1.01, openeds 0.99 / 0.67, 1.27 / 0.84,
1.11 / 0.80. ``pupil._Interior``: ``darker_core`` and ``_smoothed_bright_core`` take one fit's
interior, float32 window and 5 × 5 px averages from one holder instead of each building them:
``_inner_core`` 1.32 / 1.06, 0.67 / 0.50, 0.67 / 0.53, 0.62 / 0.50 ms. Concurrent one-thread
pairs against 0b498a2 (4 rounds × 25–30 calls a frame), median CPU ms per call main / new: load
5.5–6: synthetic 640 × 400 12.69 / 12.52, openeds 12.55 / 11.67, 11.55 / 10.78, 11.08 / 9.95
(edge_profile's medians then compiled as a selection per column, since dropped); load ~20: 12.81
/ 11.84, 11.94 / 12.40, 11.74 / 10.12, 11.71 / 9.72 — figures 2–2.5 × a quiet machine's,
ratios 0.83–1.04, noise of the same size as the gain; as committed (e525d68), 20 rounds × 25
calls a frame, load 8–9: synthetic 640 × 400 13.34 / 12.49 (best call 8.67 / 7.98), openeds
000160 12.87 / 12.99 (8.03 / 7.89), 000170 11.81 / 11.24, 000180 11.63 / 11.01 (median ratios
0.94, 1.01, 0.95, 0.95): ~5 % on a 640 × 400 frame, not enough for issue 13's 5 ms on the
slowest openeds frame. Tried and dropped: the kept profiles'
medians by a compiled Hoare selection per column (exact) — 4 × slower than NumPy's SIMD sort
of whole columns (0.82 against 0.23 ms on 256 × 193 samples).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402
import cv2  # noqa: E402
import numpy as np  # noqa: E402

from eyelume.analysis.tracking import detect, detection_to_dict  # noqa: E402

TARGET_MS = 5.0
LEDS = (0.0, 90.0, 180.0, 270.0)


def _synthetic(rows: int = 480):
    path = C.REPO / "tests" / "analysis" / "test_detect.py"
    spec = importlib.util.spec_from_file_location("_test_detect", path)
    mod = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(mod)
    except ModuleNotFoundError as exc:  # the tests' module needs the test extra (pytest)
        print(f"benchmarks/detect.py draws its synthetic frames with {path.name}, which needs "
              f"{exc.name}: pip install -e '.[test]'", file=sys.stderr)  # fmt: skip
        sys.exit(2)
    centre = (mod.CENTRE[0], mod.CENTRE[1] - (480 - rows) / 2)
    truth = {
        "pupil": {"centre_px": list(centre)},
        "glints": [
            {"led": k, "centre_px": list(p)} for k, p in enumerate(mod.glint_positions(centre))
        ],
    }
    return mod.draw_eye(mod.EyePicture(shape=(rows, 640), centre=centre)), truth


def _render(out: Path) -> None:
    exe = Path(sys.executable).parent / "eyelume"
    cmd = [
        str(exe) if exe.exists() else "eyelume", "render", "--set", "sensor.cols=640",
        "--set", "sensor.rows=480", "--samples", "8", "--out", str(out),
    ]  # fmt: skip
    print(f"   rendering: eyelume {' '.join(cmd[1:])}")
    subprocess.run(cmd, check=True, capture_output=True, text=True)


def _errors(d, truth: dict | None) -> dict:
    if not truth:
        return {}
    out = {}
    if d.pupil is not None:
        t = truth["pupil"]["centre_px"]
        out["pupil_centre_err_px"] = math.hypot(
            d.pupil.centre_px[0] - t[0], d.pupil.centre_px[1] - t[1]
        )
    by_led = {g["led"]: g["centre_px"] for g in truth.get("glints", []) if g.get("centre_px")}
    errs = [
        math.hypot(g.centre_px[0] - by_led[g.led][0], g.centre_px[1] - by_led[g.led][1])
        for g in d.glints
        if g.led in by_led
    ]
    if errs:
        out["glint_err_px_max"] = max(errs)
    return out


def bench(name: str, frame: np.ndarray, truth: dict | None, a, leds=LEDS, pattern=None) -> dict:
    for _ in range(a.warmup):
        detect(frame, led_azimuths_deg=leds, led_pattern_px=pattern)
    stages: list[dict] = []

    cpu = []

    def one():
        c0 = time.process_time()
        d = detect(frame, led_azimuths_deg=leds, led_pattern_px=pattern)
        cpu.append(1e3 * (time.process_time() - c0))
        stages.append(d.timings_ms)
        return d

    t = C.timed(one, a.repeats)
    d = t.pop("last")
    share = {k: statistics.median(s[k] for s in stages) for k in stages[0]}
    err = _errors(d, truth)
    best, med = 1e3 * t["best_s"], 1e3 * t["median_s"]
    cpu_med = statistics.median(cpu)
    # The target is time on one core: the CPU time of the call (a shared machine's wall time
    # also holds the waits for a core, shown beside it but not judged).
    verdict = "PASS" if cpu_med <= TARGET_MS else "FAIL"
    print(
        f"   {name:9s} {frame.shape[1]}×{frame.shape[0]} {frame.dtype}: CPU per call median "
        f"{cpu_med:.2f} ms, best {min(cpu):.2f} ms (of {len(cpu)})  [{verdict} ≤ {TARGET_MS} ms]"
    )
    print(
        f"             wall: best {best:.2f} ms, median {med:.2f} ms, worst "
        f"{1e3 * t['worst_s']:.2f} ms{C.disturbed(t)}"
    )
    print("             stages (median ms): " + ", ".join(f"{k} {v:.2f}" for k, v in share.items()))
    res = detection_to_dict(d)
    print(
        f"             ok={res['ok']} failures={res['failures']} glints={len(res['glints'])}"
        + "".join(f"  {k}={v:.3f}" for k, v in err.items())
    )
    return {
        "frame": name,
        "shape": list(frame.shape),
        "dtype": str(frame.dtype),
        "best_ms": best,
        "median_ms": med,
        "worst_ms": 1e3 * t["worst_s"],
        "cpu_median_ms": cpu_med,
        "cpu_best_ms": min(cpu),
        "stages_median_ms": share,
        "timing": {k: v for k, v in t.items() if k != "walls_s"},
        "detection": res,
        "errors": err,
        "pass": cpu_med <= TARGET_MS,
    }


def bench_real(a) -> list[dict]:
    """``--real``: detection time on real pictures' sizes (module doc), aggregates only."""
    import csv

    import detect_real

    data = detect_real.find_data(a.data)
    if data is None:
        print("   real      no realdata folder (../shared/realdata, or --data DIR): skipped")
        return []
    by_source: dict[str, list[dict]] = {}
    for r in csv.DictReader((data / "labels.csv").open()):
        by_source.setdefault(r["source"], []).append(r)
    out = []
    for source, rows in by_source.items():
        pick = rows[:: max(1, len(rows) // a.real)][: a.real]
        cpu_med, cpu_best, wall_med, shapes, n_ok = [], [], [], set(), 0
        for r in pick:
            img = cv2.imread(str(data / r["file"]), cv2.IMREAD_UNCHANGED)
            if img is None:
                raise SystemExit(f"detect: cannot read {data / r['file']}")
            if img.ndim == 3:
                img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
            shapes.add(f"{img.shape[1]}×{img.shape[0]} {img.dtype}")
            for _ in range(2):
                d = detect(img)
            n_ok += bool(d.ok)
            cpu, wall = [], []
            for _ in range(a.repeats):
                c0, w0 = time.process_time(), time.perf_counter()
                detect(img)
                cpu.append(1e3 * (time.process_time() - c0))
                wall.append(1e3 * (time.perf_counter() - w0))
            cpu_med.append(statistics.median(cpu))
            cpu_best.append(min(cpu))
            wall_med.append(statistics.median(wall))
        rec = {
            "frame": f"real-{source}",
            "shapes": sorted(shapes),
            "n_pictures": len(pick),
            "ok": n_ok,
            "cpu_median_ms": statistics.median(cpu_med),
            "cpu_slowest_ms": max(cpu_med),
            "cpu_best_median_ms": statistics.median(cpu_best),
            "cpu_best_slowest_ms": max(cpu_best),
            "wall_median_ms": statistics.median(wall_med),
            "wall_slowest_ms": max(wall_med),
            "pass": max(cpu_med) <= TARGET_MS if "640" in "".join(shapes) else None,
        }
        verdict = {True: "  [PASS", False: "  [FAIL", None: "  [no target"}[rec["pass"]]
        print(
            f"   real-{source:9s} {', '.join(rec['shapes'])}, {len(pick)} pictures "
            f"({n_ok} ok): CPU per call {rec['cpu_median_ms']:.2f} ms median over the pictures, "
            f"{rec['cpu_slowest_ms']:.2f} ms the slowest (best calls "
            f"{rec['cpu_best_median_ms']:.2f} / {rec['cpu_best_slowest_ms']:.2f} ms); wall "
            f"{rec['wall_median_ms']:.2f} / "
            f"{rec['wall_slowest_ms']:.2f} ms{verdict}"
            + (
                f": slowest picture ≤ {TARGET_MS} ms]"
                if rec["pass"] is not None
                else ": not 640 × 400]"
            )
        )
        out.append(rec)
    return out


def _population_frames(n: int) -> list[tuple]:
    """``--population N``: N frames of ``vr-offaxis``'s sampled people (population seed 1),
    each as ``eyelume evaluate-tracking --population`` renders a test frame
    (:func:`eyelume.optimize.tracking.render_frame`, to the sensor's noise, the irradiance
    cache on): person k at the k-th test gaze. (name, picture, truth, LED azimuths, the LEDs'
    picture pattern)."""
    import eyelume
    from eyelume.optimize.render_budget import noise_options
    from eyelume.optimize.tracking import PEOPLE_TEST_H, PEOPLE_TEST_V, render_frame
    from eyelume.scene.population import sample_people

    scene = eyelume.load_scene("vr-offaxis", {"run.indirect": "cache"})
    people = sample_people(scene, n, 1)
    gazes = [(h, v) for v in PEOPLE_TEST_V for h in PEOPLE_TEST_H]
    out = []
    for k, person in enumerate(people):
        h, v = gazes[k % len(gazes)]
        target, _ = noise_options(person.scene, "sensor", 0)
        print(f"   rendering vr-offaxis person {k} at gaze ({h:+.0f}°, {v:+.0f}°) …", flush=True)
        f = render_frame(person.scene, h, v, 2, 0, target, keep_picture=True)
        pic = f.picture
        truth = {
            "pupil": {"centre_px": f.truth["pupil"]["centre_px"]},
            "glints": [g for g in f.truth["glints"] if g.get("visible")],
        }
        pattern = pic["led_pattern_px"]
        out.append((
            f"person-{k}", np.asarray(pic["counts"]), truth, list(pic["led_azimuths_deg"]),
            None if pattern is None else np.asarray(pattern),
        ))  # fmt: skip
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeats", type=int, default=50)
    p.add_argument("--warmup", type=int, default=5)
    p.add_argument("--frame", type=Path, help="a render's output directory or an .npy picture")
    p.add_argument("--render", action="store_true", help="render a 640 × 480 paper2005 frame")
    p.add_argument(
        "--real",
        type=int,
        nargs="?",
        const=5,
        default=0,
        metavar="N",
        help="also time N real pictures of each realdata source (default 5; aggregates only)",
    )
    p.add_argument("--data", type=Path, help="the realdata folder (default ../shared/realdata)")
    p.add_argument(
        "--population",
        type=int,
        default=0,
        metavar="N",
        help="also render and time N vr-offaxis frames of sampled people (~5 s a render)",
    )
    a = p.parse_args()

    cv2.setNumThreads(1)
    info = C.machine()
    info["opencv"] = cv2.__version__
    info["cv2_threads"] = cv2.getNumThreads()
    C.print_header("Pupil and glint detection, 640 × 480 and 640 × 400 frames, one core", info)
    print(f"   OpenCV {cv2.__version__}, cv2.getNumThreads() = {cv2.getNumThreads()}")

    frames = [("synthetic", *_synthetic()), ("synth-400", *_synthetic(400))]
    tmp = None
    src = a.frame
    if a.render and src is None:
        tmp = tempfile.TemporaryDirectory()
        src = Path(tmp.name)
        _render(src)
    if src is not None:
        npy = src / "eye_image_digital.npy" if src.is_dir() else src
        truth_path = npy.parent / "truth.json"
        truth = json.loads(truth_path.read_text()) if truth_path.exists() else None
        frames.append(("render", np.load(npy), truth))

    records = [bench(name, frame, truth, a) for name, frame, truth in frames]
    if a.population > 0:
        for name, frame, truth, leds, pattern in _population_frames(a.population):
            records.append(bench(name, frame, truth, a, leds, pattern))
    if a.real > 0:
        records += bench_real(a)
    if tmp is not None:
        tmp.cleanup()
    path = C.append_result(
        "detect",
        {"command": C.command_line(), "machine": info, "target_ms": TARGET_MS, "frames": records},
    )
    print(f"   appended to {path}")


if __name__ == "__main__":
    main()
