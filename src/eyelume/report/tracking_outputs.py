"""Files written by ``eyelume evaluate-tracking``: the per-frame table, the summary and error
maps over the gaze grid; over sampled people, their table and the distribution over them."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from eyelume.analysis.tracking.evaluate import error_map_rows, is_kappa_frame
from eyelume.json_files import write_json
from eyelume.report.plots import CMAP_MAGNITUDE, agg_figure, save_figure, wrap_title

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
    """``z`` (:data:`~eyelume.report.plots.CMAP_MAGNITUDE`) with its colour bar labelled
    ``label``; ``discrete`` (a count): one colour per whole number and ticks on whole numbers
    only (BoundaryNorm)."""
    from matplotlib.colors import BoundaryNorm
    from matplotlib.ticker import MaxNLocator

    norm = None
    if discrete:
        lo, hi = int(np.nanmin(z)), int(np.nanmax(z))
        norm = BoundaryNorm(np.arange(lo - 0.5, hi + 1.0), ncolors=256)
    im = ax.imshow(z, origin="lower", cmap=CMAP_MAGNITUDE, extent=extent, aspect="auto", norm=norm)
    cb = fig.colorbar(im, ax=ax, label=label)
    if norm is not None:  # every count up to 10 of them, else whole numbers MaxNLocator picks
        ticks = MaxNLocator(nbins=min(hi - lo + 1, 10), integer=True).tick_values(lo, hi)
        cb.set_ticks(np.unique(ticks[(ticks >= lo) & (ticks <= hi)]))
        cb.ax.minorticks_off()


def save_error_maps(rows: list[dict], path, caption: str = "") -> None:
    """Four maps over the gaze grid (2 × 2 panels): pupil-centre error (px), glints found (a
    count: one colour per whole number, integer ticks), PCCR and geometric gaze errors (°), each
    with its colour bar (:data:`~eyelume.report.plots.CMAP_MAGNITUDE`), each cell's value
    written in it and the panel's mean in its title; a red × marks a frame that failed (legend
    below), and a panel with no value at all says so instead of drawing an empty scale.

    A row with ``"calibration": true`` is a calibration frame (the PCCR polynomial was fitted on
    that very picture): its PCCR cell is hatched and marked "cal" instead of showing the fit's
    in-sample residual as if it were a held-out measurement, and is left out of the PCCR
    panel's colour scale and mean (the title says how many were left out); likewise the
    geometric cell of a row with ``"geometric_calibration": true`` (the model's one-point kappa
    frame, error 0 by construction). ``rows`` are
    :func:`eyelume.analysis.tracking.evaluate.error_map_rows` (one per frame); ``caption``
    (scene, seed, budget) is written above the panels. ``path``: a file or a binary buffer."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    maps = [
        ("pupil-centre error", "pupil_error_px", "px"),
        ("glints found and matched", "glints_found", "count"),
        ("PCCR gaze error", "pccr_error_deg", "°"),
        ("geometric gaze error", "geometric_error_deg", "°"),
    ]
    fig = agg_figure(10, 7.8)
    axes = fig.subplots(2, 2).ravel()
    failed = marked = False
    for ax, (title, key, unit) in zip(axes, maps, strict=True):
        hs, vs, z, is_cal = _calibrated_grid(rows, key, _CALIBRATION_FLAG.get(key))
        dh, dv = _half_step(hs), _half_step(vs)
        extent = (hs[0] - dh, hs[-1] + dh, vs[0] - dv, vs[-1] + dv)
        ax.set_title(_panel_title(title, unit, z, int(is_cal.sum())), fontsize=9)
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
        else:
            ax.text(
                0.5, 0.5, "no frame gave a value", transform=ax.transAxes, ha="center",
                va="center", fontsize=9, bbox={"facecolor": "white", "edgecolor": "0.6"},
            )  # fmt: skip
        cells = _write_cells(ax, hs, vs, z, is_cal, (dh, dv), size, _CELL_FORMAT[unit])
        failed, marked = failed or cells[0], marked or cells[1]
    handles = []
    if failed:
        handles.append(Line2D([], [], marker="x", color="red", linestyle="none", mew=1.5,
                              label="no value: detection failed or no estimate"))  # fmt: skip
    if marked:
        handles.append(Patch(facecolor="0.85", edgecolor="0.45", hatch="///",
                             label="cal: a calibration gaze (PCCR polynomial or geometric "
                             "kappa fitted on this very picture: an in-sample residual, not a "
                             "test; left out of the mean)"))  # fmt: skip
    if handles:
        fig.legend(handles=handles, loc="outside lower left", fontsize="small", frameon=False)
    if caption:
        fig.suptitle(wrap_title(caption, 10.0, 9.0), fontsize=9)  # a long scene name wraps
    save_figure(fig, path, dpi=110)


#: Each gaze-error column's row flag of the frames its estimator was calibrated on (the same
#: picture: the value is an in-sample residual, not a measurement): the PCCR polynomial's 3 × 3
#: calibration gazes, the geometric model's one-point kappa frame
#: (:func:`eyelume.analysis.tracking.evaluate.is_kappa_frame`).
_CALIBRATION_FLAG = {
    "pccr_error_deg": "calibration",
    "geometric_error_deg": "geometric_calibration",
}


def _calibrated_grid(
    rows: list[dict], key: str, flag: str | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_grid` of ``key`` with the cells of rows flagged ``flag`` (a calibration frame
    with a value) emptied, and the boolean grid of those cells (hatched "cal", not on the
    colour scale nor in the mean)."""
    fitted = [bool(flag and r.get(flag)) and r.get(key) is not None for r in rows]
    kept = [dict(r, **{key: None}) if f else r for r, f in zip(rows, fitted, strict=True)]
    hs, vs, z = _grid(kept, key)
    _, _, cal = _grid([{**r, "cal": 1.0 if f else None} for r, f in zip(rows, fitted, strict=True)],
                      "cal")  # fmt: skip
    return hs, vs, z, np.isfinite(cal)


#: How a cell's value is written, by the panel's unit: degrees with one decimal (two
#: significant figures wrote 1.96° as "2", read as a count), counts whole, pixels to 2 figures.
_CELL_FORMAT = {"°": ".1f", "count": ".0f", "px": ".2g"}


def _write_cells(ax, hs, vs, z, is_cal, half, size, fmt: str = ".2g") -> tuple[bool, bool]:
    """Each cell's number (format ``fmt``), a red × where a frame gave none, a hatched "cal" on
    a calibration frame's cell; (any ×, any "cal")."""
    from matplotlib.patches import Rectangle

    finite = np.isfinite(z)
    failed = marked = False
    dh, dv = half
    mid = 0.5 * (np.nanmin(z) + np.nanmax(z)) if finite.any() else 0.0
    for i, v in enumerate(vs):
        for j, h in enumerate(hs):
            if is_cal[i, j]:
                ax.add_patch(Rectangle((h - dh, v - dv), 2 * dh, 2 * dv, facecolor="0.85",
                                       edgecolor="0.45", hatch="///", linewidth=0.5))  # fmt: skip
                ax.text(h, v, "cal", ha="center", va="center", fontsize=size,
                        bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5})  # fmt: skip
                marked = True
            elif finite[i, j]:
                dark = z[i, j] < mid or np.nanmin(z) == np.nanmax(z)
                ax.text(h, v, f"{z[i, j]:{fmt}}", ha="center", va="center", fontsize=size,
                        color="white" if dark else "black")  # fmt: skip
            elif finite.any():
                ax.plot(h, v, "x", color="red", ms=7, mew=1.5)
                failed = True
    return failed, marked


def _panel_title(title: str, unit: str, z: np.ndarray, n_cal: int) -> str:
    """A panel's title: the quantity and unit, then its mean over the cells with a value (and
    how many calibration gazes were left out of it)."""
    head = f"{title} ({unit})"
    n = int(np.isfinite(z).sum())
    if n == 0:
        return head
    mean = float(np.nanmean(z))
    shown = f"{mean:.2f}" if unit != "°" else f"{mean:.2f}°"
    left = f", {n_cal} calibration gaze{'s' if n_cal != 1 else ''} left out" if n_cal else ""
    return f"{head}\nmean {shown}{'' if unit == '°' else ' ' + unit} over {n} gazes{left}"


def write_tracking_outputs(report, meta: dict, out) -> list[Path]:
    """``frames.csv``, ``summary.json`` and ``error_maps.png`` in folder ``out``.

    ``frames.csv``'s ``calibration_frame`` (1: a PCCR calibration gaze, left out of
    ``gaze_pccr``) and ``geometric_calibration_frame`` (1: the geometric model's own one-point
    kappa frame, left out of ``gaze_geometric``) let its rows reproduce the summary's means;
    ``geometric_refused`` says why the geometric model gave no estimate on a frame detected
    ``ok`` (e.g. too few glints within its spherical cornea's validity zone), empty otherwise."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "frames.csv", out / "summary.json", out / "error_maps.png"]
    with open(written[0], "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "gaze_h_deg", "gaze_v_deg", "detected", "failures", "pupil_error_px",
                "glints_found", "glints_true", "pccr_h_deg", "pccr_v_deg", "geometric_h_deg",
                "geometric_v_deg", "render_s", "detect_ms", "false_glints", "calibration_frame",
                "geometric_calibration_frame", "rim_glints", "stray_glints",
                "geometric_refused",
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
                    fr.false_glints, int(fr.calibration), int(is_kappa_frame(fr)),
                    fr.rim_glints, fr.stray_glints, fr.geometric_refused,
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
