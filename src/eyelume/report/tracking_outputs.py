"""Files written by ``eyelume evaluate-tracking``: the per-frame table, the summary and error
maps over the gaze grid; over sampled people, their table and the distribution over them."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from eyelume.analysis.tracking.evaluate import error_map_rows
from eyelume.json_files import write_json
from eyelume.report.plots import agg_figure, save_figure

__all__ = [
    "save_error_maps",
    "write_people_outputs",
    "write_population_outputs",
    "write_tracking_outputs",
]


def _grid(rows: list[dict], key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    hs = sorted({r["gaze"][0] for r in rows})
    vs = sorted({r["gaze"][1] for r in rows})
    out = np.full((len(vs), len(hs)), np.nan)
    for r in rows:
        v = r[key]
        out[vs.index(r["gaze"][1]), hs.index(r["gaze"][0])] = np.nan if v is None else v
    return np.array(hs), np.array(vs), out


def _caption(meta: dict | None) -> str:
    """The scene, seed and budget of a run, for a figure's caption."""
    if not meta:
        return ""
    parts = []
    for key, say in (("scene", "scene {}"), ("member", "member {}"), ("seed", "seed {}"),
                     ("samples_per_pixel", "{} camera samples per pixel")):  # fmt: skip
        if meta.get(key) is not None:
            parts.append(say.format(meta[key]))
    if meta.get("sensor"):
        parts.append("sensor {} × {} px".format(*meta["sensor"]))
    return ", ".join(parts)


def _half_step(values: np.ndarray) -> float:
    return float(np.min(np.diff(values))) / 2 if values.size > 1 else 5.0


def _draw_map(fig, ax, z: np.ndarray, extent, label: str, discrete: bool) -> None:
    """``z`` (viridis) with its colour bar labelled ``label``; ``discrete`` (a count): one
    colour per whole number and ticks on whole numbers only (BoundaryNorm)."""
    from matplotlib.colors import BoundaryNorm
    from matplotlib.ticker import MaxNLocator

    norm = None
    if discrete:
        lo, hi = int(np.nanmin(z)), int(np.nanmax(z))
        norm = BoundaryNorm(np.arange(lo - 0.5, hi + 1.0), ncolors=256)
    im = ax.imshow(z, origin="lower", cmap="viridis", extent=extent, aspect="auto", norm=norm)
    cb = fig.colorbar(im, ax=ax, label=label)
    if norm is not None:  # every count up to 10 of them, else whole numbers MaxNLocator picks
        ticks = MaxNLocator(nbins=min(hi - lo + 1, 10), integer=True).tick_values(lo, hi)
        cb.set_ticks(np.unique(ticks[(ticks >= lo) & (ticks <= hi)]))
        cb.ax.minorticks_off()


def save_error_maps(rows: list[dict], path, caption: str = "") -> None:
    """Four maps over the gaze grid (2 × 2 panels): pupil-centre error (px), glints found (a
    count: one colour per whole number, integer ticks), PCCR and geometric gaze errors (°), each
    with its colour bar (viridis) and each cell's value
    written in it; a red × marks a frame that failed (legend below), and a panel with no value
    at all says so instead of drawing an empty scale. ``rows`` are
    :func:`eyelume.analysis.tracking.evaluate.error_map_rows` (one per frame); ``caption``
    (scene, seed, budget) is written under the panels. ``path``: a file or a binary buffer."""
    from matplotlib.lines import Line2D

    maps = [
        ("pupil-centre error", "pupil_error_px", "px"),
        ("glints found and matched", "glints_found", "count"),
        ("PCCR gaze error", "pccr_error_deg", "°"),
        ("geometric gaze error", "geometric_error_deg", "°"),
    ]
    fig = agg_figure(10, 7.6)
    axes = fig.subplots(2, 2).ravel()
    failed = False
    for ax, (title, key, unit) in zip(axes, maps, strict=True):
        hs, vs, z = _grid(rows, key)
        dh, dv = _half_step(hs), _half_step(vs)
        extent = (hs[0] - dh, hs[-1] + dh, vs[0] - dv, vs[-1] + dv)
        ax.set_title(f"{title} ({unit})", fontsize=10)
        ax.set_xlabel("horizontal gaze (°)")
        ax.set_ylabel("vertical gaze (°)")
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
        finite = np.isfinite(z)
        # each cell's number in a font that fits its cell (5 characters wide at most)
        cell_in = 4.0 / max(len(hs), 1)
        size = float(np.clip(cell_in * 72 / 3.2, 4.0, 8.0))
        if finite.any():
            _draw_map(fig, ax, z, extent, f"{title} ({unit})", discrete=unit == "count")
            mid = 0.5 * (np.nanmin(z) + np.nanmax(z))
        else:
            ax.text(
                0.5, 0.5, "no frame gave a value", transform=ax.transAxes, ha="center",
                va="center", fontsize=9, bbox={"facecolor": "white", "edgecolor": "0.6"},
            )  # fmt: skip
        for i, v in enumerate(vs):
            for j, h in enumerate(hs):
                if finite[i, j]:
                    dark = z[i, j] < mid or np.nanmin(z) == np.nanmax(z)
                    ax.text(h, v, f"{z[i, j]:.2g}", ha="center", va="center", fontsize=size,
                            color="white" if dark else "black")  # fmt: skip
                elif finite.any():
                    ax.plot(h, v, "x", color="red", ms=7, mew=1.5)
                    failed = True
    handles = []
    if failed:
        handles.append(Line2D([], [], marker="x", color="red", linestyle="none", mew=1.5,
                              label="no value: detection failed or no estimate"))  # fmt: skip
    if handles:
        fig.legend(handles=handles, loc="outside lower left", fontsize="small", frameon=False)
    if caption:
        fig.suptitle(caption, fontsize=9)
    save_figure(fig, path, dpi=110)


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
    save_error_maps(error_map_rows(report.frames), written[2], _caption(meta))
    return written


def write_population_outputs(
    members: dict, scene_name: str, out, partial: str | None = None, meta: dict | None = None
) -> list[Path]:
    """Each member's tracking outputs (:func:`write_tracking_outputs`) in its own folder of
    ``out`` (its name with spaces, + and - spelled out) and ``population.json``: each member's
    summary without its failures, and ``"partial"``: what was cut when ``partial`` is given
    (an interrupted run: the members missing were not evaluated). ``meta`` (e.g. ``seed``,
    ``samples_per_pixel``) joins each member's ``scene`` and ``member`` in its summary and
    figure caption."""
    out = Path(out)
    written, table = [], {}
    for name, rep in members.items():
        folder = out / name.replace(" ", "_").replace("+", "plus").replace("-", "minus")
        member = {**(meta or {}), "scene": scene_name, "member": name}
        written += write_tracking_outputs(rep, member, folder)
        table[name] = {k: v for k, v in rep.summary.items() if k != "failures"}
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "population.json", {**table, "partial": partial} if partial else table)
    return [*written, out / "population.json"]


#: people.csv's result columns, before the person's sampled parameters.
_PEOPLE_COLUMNS = ("person", "tracked", "detection_rate", "pccr_mean_deg", "pccr_max_deg",
                   "geometric_mean_deg", "score_deg")  # fmt: skip


def write_people_outputs(rows: list[dict], summary: dict, meta: dict, out) -> list[Path]:
    """``population.json`` (``meta``: scene, budget, seeds, the population and its resolved
    distributions; ``summary``: the distribution over people; ``people``: each person's row —
    sampled parameters and results, :meth:`eyelume.optimize.tracking.PersonResult.row`) and
    ``people.csv`` (one line per person: the results, then every sampled parameter) in folder
    ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "population.json", out / "people.csv"]
    write_json(written[0], {"meta": meta, "summary": summary, "people": rows})
    params = list(rows[0]["parameters"]) if rows else []
    with open(written[1], "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow([*_PEOPLE_COLUMNS, *params])
        for r in rows:
            cells = ["" if r[k] is None else r[k] for k in _PEOPLE_COLUMNS]
            cells[1] = int(r["tracked"])
            w.writerow([*cells, *(f"{r['parameters'][k]:.6g}" for k in params)])
    return written
