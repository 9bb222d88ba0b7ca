"""eyelume's own detector against a labelled dataset's truth (issue 17): the dataset as a test
bench for a detector.

Run from the repository root::

    python benchmarks/dataset_detect.py DATASET_DIR            # a folder `eyelume dataset` wrote
    python benchmarks/dataset_detect.py --make 40 [--workers 2] [--keep DIR]
        # first makes a `vr-offaxis` dataset of 40 pictures (400 × 400) with `eyelume dataset`
        # (the file it runs is printed): gaze uniform ±25° × ±20°, pupil 2–7 mm, slip ±1 mm,
        # 8-bit PNG, render noise below the sensor's shot noise

Each picture (``images/NNNNNN.png`` as stored: the sensor's DN) goes through
:func:`eyelume.analysis.tracking.detect` — what ``eyelume track`` and ``evaluate-tracking`` run —
with the LED azimuths and glint pattern the base scene predicts
(:func:`~eyelume.analysis.tracking.evaluate.led_picture_azimuths`,
:func:`~eyelume.analysis.tracking.evaluate.led_picture_pattern`; none when the scene in
``dataset.json`` cannot be loaded). Against the label line (``labels.jsonl``):

* **pupil**: the distance (px) from the detected pupil centre to the label's apparent pupil
  ellipse centre (``pupil.ellipse.center_px``), over the pictures whose label has a pupil
  ellipse with ``visible_share`` ≥ 0.5 (``--min-visible``). Median and 95th percentile over the
  pictures the detector answered ``ok``; the shares ≤ 1 px and ≤ 5 px over *all* those pictures
  (a failed or untrusted detection counts as a miss). ``ok`` is False also when the glints do
  not fit the LEDs (the detector's rule), so the pupil candidate it returned anyway is scored
  apart (``pupil_candidate_*``: its median error and share ≤ 5 px), for diagnosis.
* **glints**: the label's glints with ``visible`` and a position are the truth; every glint the
  detector returns (matched to an LED or not) is a detection. They are paired one to one by
  least total distance (Hungarian, ``scipy.optimize.linear_sum_assignment``) within
  ``--glint-radius`` px (3 px: glints on a 400 × 400 eye picture are a few pixels across and
  several apart): *matched*, *false* (detections left over), *missed* (truths left over; those
  whose label says they are not on the cornea — a reflection off the sclera — counted apart
  too, ``glints_missed_off_cornea``: the detector looks for glints near the pupil only); the
  matched glints' position error (median, p95) and, of those the detector gave an LED, the
  share whose LED id is the label's.

Prints the figures and how they were run, and appends a JSON line (with the command) to
``benchmarks/results/dataset_detect.jsonl``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402
import numpy as np  # noqa: E402

from eyelume.analysis.tracking.detect import detect  # noqa: E402
from eyelume.report.dataset_outputs import read_dataset, read_picture  # noqa: E402

DATASET_TOML = """name = "detect-bench"
scene = "vr-offaxis"
seed = {seed}
pictures = {n}
image_bits = 8
irradiance = false
render_noise = "sensor"
[gaze]
distribution = "uniform"
horizontal = [-25.0, 25.0]
vertical = [-20.0, 20.0]
[[vary]]
path = "eye.pupil_diameter_mm"
range = [2.0, 7.0]
[[vary]]
path = "head_offset_mm"
range = [[-1, 1], [-1, 1], [-1, 1]]
"""


def led_layout(info: dict, folder: Path):
    """(LED azimuths, glint pattern) the dataset's base scene predicts, or (None, None)."""
    from eyelume.analysis.tracking.evaluate import led_picture_azimuths, led_picture_pattern
    from eyelume.compile import compile_scene
    from eyelume.scene.io import load_scene

    name = info.get("scene")
    if not isinstance(name, str):
        return None, None, "dataset.json names no scene"
    reason = ""
    for cand in (name, str(folder / name)):
        try:
            cs = compile_scene(load_scene(cand))
            return led_picture_azimuths(cs), led_picture_pattern(cs), f"scene {cand}"
        except Exception as exc:  # noqa: BLE001 - reported: the benchmark goes on without
            reason = f"{cand}: {exc}"
    return None, None, f"no LED layout ({reason})"


def pair_glints(truth: list[tuple[float, float]], found: list[tuple[float, float]],
                radius: float) -> list[tuple[int, int, float]]:  # fmt: skip
    """(truth index, found index, distance px) of the one-to-one pairs within ``radius`` of
    least total distance."""
    if not truth or not found:
        return []
    from scipy.optimize import linear_sum_assignment

    d = np.hypot(
        *(np.asarray(truth)[:, None, :] - np.asarray(found)[None, :, :]).transpose(2, 0, 1)
    )
    cost = np.where(d <= radius, d, 1e6)
    rows, cols = linear_sum_assignment(cost)
    return [(int(r), int(c), float(d[r, c])) for r, c in zip(rows, cols, strict=True)
            if d[r, c] <= radius]  # fmt: skip


def score_picture(pic: np.ndarray, label: dict, azimuths, pattern, *, radius: float = 3.0,
                  min_visible: float = 0.5) -> dict:  # fmt: skip
    """One picture's detection against its label (module doc)."""
    t0 = time.perf_counter()
    det = detect(pic, led_azimuths_deg=azimuths, led_pattern_px=pattern)
    ms = 1e3 * (time.perf_counter() - t0)
    pupil = label.get("pupil") or {}
    ellipse = pupil.get("ellipse") or {"center_px": pupil.get("center_px")}
    out = {"index": label["index"], "ok": det.ok, "detect_ms": ms, "pupil_error_px": None,
           "pupil_candidate_error_px": None, "pupil_scored": False,
           "failures": [f for f in det.failures if not f.startswith("warning")]}  # fmt: skip
    if ellipse.get("center_px") is not None and (pupil.get("visible_share") or 0) >= min_visible:
        out["pupil_scored"] = True
        if det.pupil is not None:
            err = float(np.hypot(*np.subtract(det.pupil.centre_px, ellipse["center_px"])))
            out["pupil_candidate_error_px"] = err  # also when not ok: the rejected candidate's
            out["pupil_error_px"] = err if det.ok else None
    truth = [g for g in label.get("glints") or [] if g.get("visible") and g.get("position_px")]
    found = det.glints
    pairs = pair_glints([tuple(g["position_px"]) for g in truth],
                        [tuple(g.centre_px) for g in found], radius)  # fmt: skip
    out["glints_true"], out["glints_found"], out["glints_matched"] = (
        len(truth),
        len(found),
        len(pairs),
    )
    out["glint_errors_px"] = [d for _, _, d in pairs]
    paired = {t for t, _, _ in pairs}
    out["glints_missed_off_cornea"] = sum(
        1 for t, g in enumerate(truth) if t not in paired and not g.get("on_cornea", True)
    )
    with_led = [(truth[t]["led"], found[f].led) for t, f, _ in pairs if found[f].led is not None]
    out["led_pairs"] = len(with_led)
    out["led_agree"] = sum(a == b for a, b in with_led)
    return out


def _pct(v, q) -> float | None:
    return float(np.percentile(v, q)) if len(v) else None


def summarise(rows: list[dict]) -> dict:
    scored = [r for r in rows if r["pupil_scored"]]
    errs = [r["pupil_error_px"] for r in scored if r["pupil_error_px"] is not None]
    cand = [r["pupil_candidate_error_px"] for r in scored
            if r["pupil_candidate_error_px"] is not None]  # fmt: skip
    n = len(scored)
    g_err = [e for r in rows for e in r["glint_errors_px"]]
    true, found = sum(r["glints_true"] for r in rows), sum(r["glints_found"] for r in rows)
    matched = sum(r["glints_matched"] for r in rows)
    leds = sum(r["led_pairs"] for r in rows)
    return {
        "pictures": len(rows),
        "ok_share": sum(r["ok"] for r in rows) / len(rows),
        "pupil_pictures_scored": n,
        "pupil_detected": len(errs),
        "pupil_error_px_median": _pct(errs, 50),
        "pupil_error_px_p95": _pct(errs, 95),
        "pupil_share_within_1px": sum(e <= 1 for e in errs) / n if n else None,
        "pupil_share_within_5px": sum(e <= 5 for e in errs) / n if n else None,
        "pupil_candidate_error_px_median": _pct(cand, 50),
        "pupil_candidate_share_within_5px": sum(e <= 5 for e in cand) / n if n else None,
        "glints_true": true,
        "glints_found": found,
        "glints_matched": matched,
        "glints_false": found - matched,
        "glints_missed": true - matched,
        "glints_missed_off_cornea": sum(r["glints_missed_off_cornea"] for r in rows),
        "glint_error_px_median": _pct(g_err, 50),
        "glint_error_px_p95": _pct(g_err, 95),
        "led_id_agreement": sum(r["led_agree"] for r in rows) / leds if leds else None,
        "detect_ms_median": _pct([r["detect_ms"] for r in rows], 50),
    }


def make_dataset(n: int, seed: int, workers: int, out: Path) -> str:
    """Run ``eyelume dataset`` on :data:`DATASET_TOML`; returns the command run."""
    spec = out.parent / f"{out.name}.toml"
    text = DATASET_TOML.format(seed=seed, n=n)
    spec.write_text(text, encoding="utf-8")
    cmd = ["eyelume", "dataset", str(spec), "--out", str(out), "--workers", str(workers)]
    print(f"making the dataset ({spec}):\n{text}\n$ {' '.join(cmd)}", flush=True)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True)
    print(f"made in {time.perf_counter() - t0:.0f} s", flush=True)
    return " ".join(cmd)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", nargs="?", type=Path, help="a dataset folder")
    ap.add_argument("--make", type=int, default=0, help="first make a dataset of N pictures")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--keep", type=Path, help="with --make: the folder to make it in")
    ap.add_argument("--glint-radius", type=float, default=3.0)
    ap.add_argument("--min-visible", type=float, default=0.5)
    ap.add_argument("--no-record", action="store_true", help="do not append to results")
    ap.add_argument("--made-with", help="how DIR was made (recorded; --make records its own)")
    args = ap.parse_args()
    made = args.made_with
    if args.make:
        folder = args.keep or Path(tempfile.mkdtemp(prefix="eyelume-ds-")) / "set"
        made = make_dataset(args.make, args.seed, args.workers, folder)
    elif args.folder is None:
        ap.error("give a dataset folder or --make N")
    else:
        folder = args.folder
    ds = read_dataset(folder)
    azimuths, pattern, layout = led_layout(ds.spec, ds.folder)
    C.print_header("eyelume detector against a dataset's labels", C.machine())
    print(f"dataset {ds.name}: scene {ds.scene}, seed {ds.seed}, {len(ds.labels)} pictures; "
          f"LED layout from {layout}")  # fmt: skip
    rows = []
    for lab in ds.labels:
        pic = read_picture(ds, lab)
        rows.append(score_picture(pic, lab, azimuths, pattern, radius=args.glint_radius,
                                  min_visible=args.min_visible))  # fmt: skip
    s = summarise(rows)
    for k, v in s.items():
        print(f"  {k}: {v:.4g}" if isinstance(v, float) else f"  {k}: {v}")
    if not args.no_record:
        rec = {"command": C.command_line(), "dataset_command": made, "dataset": str(folder),
               "name": ds.name, "scene": ds.scene, "seed": ds.seed,
               "size_px": ds.labels[0].get("size_px"), "led_layout": layout,
               "glint_radius_px": args.glint_radius, "min_visible_share": args.min_visible,
               **s, "machine": C.machine(), "git": C.git_state()}  # fmt: skip
        print(f"appended to {C.append_result('dataset_detect', rec)}")
    from collections import Counter

    reasons = Counter(f.split(":")[0] for r in rows for f in r["failures"])
    if reasons:
        print(
            "why frames were not ok (count): "
            + "; ".join(f"{k} ({v})" for k, v in reasons.most_common(6))
        )


if __name__ == "__main__":
    main()
