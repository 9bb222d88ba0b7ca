"""Files written by ``eyelume evaluate-tracking``: the per-frame table, the summary and error
maps over the gaze grid."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from eyelume.analysis.tracking.evaluate import error_map_rows
from eyelume.json_files import write_json
from eyelume.report.plots import agg_figure

__all__ = ["save_error_maps", "write_population_outputs", "write_tracking_outputs"]


def _grid(rows: list[dict], key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    hs = sorted({r["gaze"][0] for r in rows})
    vs = sorted({r["gaze"][1] for r in rows})
    out = np.full((len(vs), len(hs)), np.nan)
    for r in rows:
        v = r[key]
        out[vs.index(r["gaze"][1]), hs.index(r["gaze"][0])] = np.nan if v is None else v
    return np.array(hs), np.array(vs), out


def save_error_maps(rows: list[dict], path) -> None:
    """Four maps over the gaze grid: pupil-centre error (px), glints found, PCCR and geometric
    gaze errors (°); blank where the frame failed. ``rows`` are
    :func:`eyelume.analysis.tracking.evaluate.error_map_rows` (one per frame)."""
    maps = [
        ("pupil-centre error (px)", "pupil_error_px"),
        ("glints found and matched", "glints_found"),
        ("PCCR gaze error (°)", "pccr_error_deg"),
        ("geometric gaze error (°)", "geometric_error_deg"),
    ]
    fig = agg_figure(13, 3.4)
    axes = fig.subplots(1, 4)
    for ax, (title, key) in zip(axes, maps, strict=True):
        hs, vs, z = _grid(rows, key)
        im = ax.imshow(
            z,
            origin="lower",
            cmap="viridis",
            extent=(hs[0] - 5, hs[-1] + 5, vs[0] - 5, vs[-1] + 5),
            aspect="auto",
        )
        for i, v in enumerate(vs):
            for j, h in enumerate(hs):
                if np.isfinite(z[i, j]):
                    ax.text(h, v, f"{z[i, j]:.2g}", ha="center", va="center", fontsize=7)
                else:
                    ax.text(h, v, "×", ha="center", va="center", color="red")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("horizontal gaze (°)")
        fig.colorbar(im, ax=ax)
    axes[0].set_ylabel("vertical gaze (°)")
    fig.savefig(path, dpi=110, bbox_inches="tight", format="png")


def write_tracking_outputs(report, meta: dict, out) -> list[Path]:
    """``frames.csv``, ``summary.json`` and ``error_maps.png`` in folder ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "frames.csv", out / "summary.json", out / "error_maps.png"]
    with open(written[0], "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "gaze_h_deg", "gaze_v_deg", "detected", "failures", "pupil_error_px",
                "glints_found", "glints_true", "pccr_h_deg", "pccr_v_deg", "geometric_h_deg",
                "geometric_v_deg", "render_s", "detect_ms", "false_glints",
            ]
        )  # fmt: skip
        for fr in report.frames:
            p = fr.pccr or (math.nan, math.nan)
            g = fr.geometric or (math.nan, math.nan)
            w.writerow(
                [
                    f"{fr.gaze[0]:g}", f"{fr.gaze[1]:g}", int(fr.detection.ok),
                    "; ".join(fr.detection.failures), f"{fr.pupil_error_px:.4f}",
                    fr.glints_found, fr.glints_true, f"{p[0]:.4f}", f"{p[1]:.4f}",
                    f"{g[0]:.4f}", f"{g[1]:.4f}", f"{fr.render_s:.3f}", f"{fr.detect_ms:.3f}",
                    fr.false_glints,
                ]
            )  # fmt: skip
    summary = {"meta": meta, **report.summary}
    write_json(written[1], summary)
    save_error_maps(error_map_rows(report.frames), written[2])
    return written


def write_population_outputs(
    members: dict, scene_name: str, out, partial: str | None = None
) -> list[Path]:
    """Each member's tracking outputs (:func:`write_tracking_outputs`) in its own folder of
    ``out`` (its name with spaces, + and - spelled out) and ``population.json``: each member's
    summary without its failures, and ``"partial"``: what was cut when ``partial`` is given
    (an interrupted run: the members missing were not evaluated)."""
    out = Path(out)
    written, table = [], {}
    for name, rep in members.items():
        folder = out / name.replace(" ", "_").replace("+", "plus").replace("-", "minus")
        written += write_tracking_outputs(rep, {"scene": scene_name, "member": name}, folder)
        table[name] = {k: v for k, v in rep.summary.items() if k != "failures"}
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "population.json", {**table, "partial": partial} if partial else table)
    return [*written, out / "population.json"]
