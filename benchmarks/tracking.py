"""Tracking on the presets: the README's "Tracking on the presets" table, one row per preset.

Run from the repository root::

    python benchmarks/tracking.py                          # all four presets (~30-60 min)
    python benchmarks/tracking.py --only vr-offaxis        # one of them
    python benchmarks/tracking.py --only paper2005 --out /tmp/track

What ``eyelume evaluate-tracking --scene S --samples N --seed 0 --out D`` does (its API,
:func:`eyelume.optimize.tracking.evaluate_tracking`, and its files in ``D``:
:func:`eyelume.report.tracking_outputs.write_tracking_outputs`) for each preset at the
README table's settings: ``paper2005`` and ``vr-offaxis`` at 4 camera samples per pixel,
``eyetrackvr`` and ``glasses-frame`` at 8, seed 0 (``--seed`` to change it), the 7 × 5 test
grid (±30° × ±20°) after the 3 × 3 calibration. ``D`` is ``<--out>/<preset>`` (default
``/tmp/eyelume-tracking-bench``).

Prints, per preset, the table's row: test frames ``ok``, pupil error mean / p95 (px, against
``truth.json``), PCCR gaze error mean / p95 / max (or none, with fewer than 6 calibration
frames), geometric gaze error mean / p95 (after its one-point kappa; how many ``ok`` frames it
refused, and how many of them for too few glints within its spherical cornea's validity zone,
:data:`eyelume.analysis.tracking.gaze.SPHERE_ZONE_DEG`), and the most common detection failure
with its count. Appends one JSON line per preset to ``benchmarks/results/tracking.jsonl``
(commit, date, settings, the figures, wall time). CPU is shared: the figures are accuracies,
not timings; the wall time is only what the run took.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import append_result, command_line, git_state, loadavg  # noqa: E402

#: The README table's camera samples per pixel for each preset.
PRESETS = {"paper2005": 4, "vr-offaxis": 4, "eyetrackvr": 8, "glasses-frame": 8}


def _fmt(x, spec: str = ".2f", unit: str = "") -> str:
    return "–" if x is None else f"{x:{spec}}{unit}"


def figures(summary: dict, frames: list) -> dict:
    """The table's figures from ``evaluate_tracking``'s summary and test frames."""
    ok = sum(f.detection.ok for f in frames)
    pe, gp, gg = summary["pupil_error_px"], summary["gaze_pccr"], summary["gaze_geometric"]
    causes = summary.get("failure_causes") or {}
    most = next(iter(causes.items()), None)
    return {
        "frames": len(frames),
        "frames_ok": ok,
        "pupil_error_px": {"mean": pe["mean"], "p95": pe["p95"]},
        "pccr_deg": (
            {k: gp.get(f"{k}_deg") for k in ("mean", "p95", "max")} | {"frames": gp["frames"]}
            if gp.get("frames")
            else None
        ),
        "geometric_deg": {k: gg.get(f"{k}_deg") for k in ("mean", "p95", "max")}
        | {
            "frames": gg.get("frames", 0),
            "refused": gg.get("refused"),
            "refused_outside_zone": gg.get("refused_outside_zone"),
        },
        "most_common_refusal": None if most is None else {"kind": most[0], "frames": most[1]},
        "failure_causes": causes,
    }


def row(preset: str, samples: int, commit: str, fig: dict) -> str:
    """The README table's row."""
    pe, gp, gg = fig["pupil_error_px"], fig["pccr_deg"], fig["geometric_deg"]
    pccr = (
        "none (< 6 calibration frames)"
        if gp is None
        else f"{_fmt(gp['mean'])}° / {_fmt(gp['p95'])}° / {_fmt(gp['max'])}°"
    )
    geo = f"{_fmt(gg['mean'])}° / {_fmt(gg['p95'])}° over {gg['frames']}"
    if gg["refused"]:
        geo += f" ({gg['refused']} `ok` refused, {gg['refused_outside_zone']} outside its zone)"
    most = fig["most_common_refusal"]
    refused = "none" if most is None else f"{most['kind']} {most['frames']}"
    return (
        f"| {preset} ({samples}, {commit}) | {fig['frames_ok']} / {fig['frames']} | "
        f"{_fmt(pe['mean'], '.3f')} / {_fmt(pe['p95'])} px | {pccr} | {geo} | {refused} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(PRESETS), action="append", default=None,
                    help="this preset only (repeatable)")  # fmt: skip
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("/tmp/eyelume-tracking-bench"))
    args = ap.parse_args()

    import eyelume
    from eyelume.json_files import finite_or_null
    from eyelume.optimize.tracking import evaluate_tracking
    from eyelume.report.tracking_outputs import write_tracking_outputs

    state = git_state()
    commit = state["commit"] + ("+dirty" if state["src_dirty"] else "")
    print(f"== tracking on the presets: {command_line()}  (commit {commit}, load {loadavg()})")
    print(
        "| preset (`--samples`, commit) | frames `ok` | pupil error mean / p95 | "
        "PCCR mean / p95 / max | geometric mean / p95 | refused (most) |"
    )
    print("|---|---|---|---|---|---|")
    for preset in args.only or list(PRESETS):
        samples = PRESETS[preset]
        scene = eyelume.load_scene(preset)
        t0 = time.perf_counter()
        report = evaluate_tracking(scene, samples_per_pixel=samples, seed=args.seed)
        wall = time.perf_counter() - t0
        out = args.out / preset
        meta = {
            "scene": preset,
            "samples_per_pixel": samples,
            "seed": args.seed,
            "sensor": [scene.sensor.cols, scene.sensor.rows],
            "wall_time_s": round(wall, 2),
        }
        write_tracking_outputs(report, meta, out)
        fig = figures(report.summary, report.frames)
        print(row(preset, samples, state["commit"], fig), flush=True)
        append_result(
            "tracking",
            finite_or_null(
                {
                    "script": "tracking.py",
                    "command": command_line(),
                    **state,
                    "preset": preset,
                    "samples_per_pixel": samples,
                    "seed": args.seed,
                    "out": str(out),
                    "wall_s": round(wall, 1),
                    "loadavg": loadavg(),
                    **fig,
                }
            ),
        )
    print("appended to benchmarks/results/tracking.jsonl")


if __name__ == "__main__":
    main()
