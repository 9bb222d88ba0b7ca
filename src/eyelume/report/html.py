"""``eyelume report DIR``: one self-contained HTML page of a study (figures embedded as PNG).

The page holds the study's table (runs over an IEC 62471 exempt-group limit in red), one figure
per metric against each varied parameter (the merit landscapes), the best runs, and — when the
study's folder holds them (:func:`eyelume.optimize.best_run.save_best_run`, which
``eyelume report --scene`` runs first) — the best run's eye-plane pattern and eye image, and its
tracking-error maps when the study measured tracking. The report only reads what is stored: it
renders nothing. When the page has loaded, a script counts the figures that decoded into
``data-figures`` on the body and writes how many CSS pixels the page overflows the window
sideways into ``data-overflow-px``, so a headless browser can check that it renders with its
figures and without a horizontal scroll bar (wide tables scroll in their own box).
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from eyelume.errors import StoreError
from eyelume.optimize.best_run import BEST_RUN_FILES, best_runs, over_limit
from eyelume.report.plots import (
    CMAP_IRRADIANCE,
    CMAP_SENSOR,
    agg_figure,
    draw_maps,
    pixel_pitch_label,
    save_figure,
)
from eyelume.report.tracking_outputs import save_error_maps

__all__ = ["check_report_folder", "write_dataset_report", "write_report"]


#: Run when a page has loaded: counts the figures that decoded and measures the layout, for a
#: headless browser's check (module doc).
_LOAD_SCRIPT = """<script>
window.addEventListener("load", () => {
  const ok = [...document.images].filter(i => i.complete && i.naturalWidth > 0).length;
  document.body.dataset.figures = String(ok);
  // the narrowest and widest figure as drawn (CSS px): figures grow with the window
  const widths = [...document.images].map(i => i.getBoundingClientRect().width);
  document.body.dataset.figureMinPx = String(Math.round(widths.length ? Math.min(...widths) : 0));
  document.body.dataset.figureMaxPx = String(Math.round(widths.length ? Math.max(...widths) : 0));
  // for a headless check of the layout: how far the page overflows the window sideways
  document.body.dataset.overflowPx = String(
    Math.max(0, document.documentElement.scrollWidth - window.innerWidth));
});
</script>"""


#: The pages' style sheet: figures in a grid that grows with the window, wide tables in their
#: own scrolling box.
_STYLE = """<style>
body { font-family: sans-serif; margin: 1em auto; padding: 0 1em; max-width: 2400px; }
.scroll { overflow-x: auto; max-width: 100%; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ccc; padding: 2px 6px; text-align: right; white-space: nowrap; }
th { background: #f4f4f4; position: sticky; top: 0; }
tr.unsafe td, .over-limit { color: #b00; font-weight: bold; }
.figures { display: grid; gap: 1em;
  grid-template-columns: repeat(auto-fill, minmax(min(100%, 720px), 1fr)); }
figure { margin: 0; min-width: 0; }
figure img { width: 100%; max-width: 100%; height: auto; }
figcaption { font-size: 0.9em; color: #333; overflow-wrap: anywhere; }
</style>"""


def _png(fig: Figure) -> str:
    buf = io.BytesIO()
    save_figure(fig, buf, dpi=120)  # sharp when a wide window draws it larger
    return base64.b64encode(buf.getvalue()).decode("ascii")


#: Units of the study's metrics by their full name (counts, shares, a yes/no).
_METRIC_UNITS = {
    "eye_image_merit_se": "dimensionless",
    "skin_cv": "dimensionless",
    "detection_rate": "share of frames",
    "glints_visible_min": "count",
    "glints_visible_mean": "count",
    "gaze_share_all_glints": "share of gazes",
    "false_glints_mean": "count",
    "false_glints_max": "count",
    "false_glint_to_glint_px_min": "px",
    "false_glint_to_pupil_px_min": "px",
    "within_exempt_group": "yes/no",
}

#: Units read from a parameter's or metric's name ending (the scene's and metrics' own naming:
#: ``leds.height_mm``, ``pitch_deg``, ``corneal_margin`` = exposure limit / exposure).
_NAME_UNITS = (
    ("_w_mm2", "W/mm²"),
    ("_w_sr", "W/sr"),
    ("_mm", "mm"),
    ("_deg", "°"),
    ("_nm", "nm"),
    ("_um", "µm"),
    ("_px", "px"),
    ("_ms", "ms"),
    ("_margin", "limit / exposure"),
    ("_merit", "dimensionless"),
)


def unit_of(name: str) -> str | None:
    """The unit a parameter's or metric's name says (:data:`_METRIC_UNITS`, else its ending,
    ``_NAME_UNITS``), or None: none is invented."""
    if name in _METRIC_UNITS:
        return _METRIC_UNITS[name]
    return next((unit for end, unit in _NAME_UNITS if name.endswith(end)), None)


def axis_label(name: str) -> str:
    """``name`` with its unit in parentheses when its name says it (:func:`unit_of`)."""
    unit = unit_of(name)
    return name if unit is None else f"{name} ({unit})"


def _value_with_unit(name: str, value) -> str:
    """``value`` as a reader writes it: a number with its unit (``30 mm``, ``10°``)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value)
    unit = unit_of(name)
    text = f"{value:.5g}"
    if unit in (None, "dimensionless", "yes/no"):
        return text
    return f"{text}{unit}" if unit == "°" else f"{text} {unit}"


def _study_info(folder: Path) -> dict | None:
    from eyelume.optimize.runner import STUDY_FILE

    try:
        info = json.loads((folder / STUDY_FILE).read_text(encoding="utf-8"))
        return info if all(k in info for k in ("study", "scene", "seed")) else None
    except (OSError, ValueError, TypeError):
        return None


def metric_budget(metric: str, info: dict | None) -> str:
    """How a study's ``metric`` was computed, with the budget that computation actually used:
    the camera samples per pixel and the seed only for the metrics rendered with them
    (:func:`eyelume.optimize.study.run_metrics`); closed-form metrics say they used none."""
    seed = f"seed {info['seed']}" if info else "seed not recorded"
    spp = info.get("samples_per_pixel") if info else None
    rendered = f"{spp} camera samples per pixel" if spp is not None else "camera samples unknown"
    if metric.startswith(("eye_image_merit", "skin_")):
        return f"rendered with the fast estimator, glints removed: {rendered}, {seed}"
    if metric in ("tracking_score_deg", "detection_rate"):
        return (
            f"rendered with the fast estimator over a 3 × 3 gaze grid (±20° × ±10°), geometric "
            f"gaze model: {rendered} per frame, {seed}"
        )
    if metric == "eye_plane_merit":
        return "closed-form eye-plane irradiance: no camera samples, no random seed"
    if metric.startswith(("glints_", "gaze_share", "false_glint")):
        return "from the renderer's truth over a gaze grid: no camera samples, no random seed"
    if metric.endswith("_margin") or metric == "within_exempt_group":
        return "closed-form IEC 62471 exposure: no camera samples, no random seed"
    return f"budget of the study: {rendered}, {seed}"


def study_caption(folder: Path) -> str:
    """The study's name and scene, as its runner recorded them in ``study.json``
    (:data:`eyelume.optimize.runner.STUDY_FILE`), for the captions; says so when the folder has
    none (a study run before eyelume wrote it) or it cannot be read. The budget a figure used
    is :func:`metric_budget`'s."""
    from eyelume.optimize.runner import STUDY_FILE

    info = _study_info(folder)
    if info is None:
        return f"The folder records no study scene or seed ({STUDY_FILE} missing or unreadable)."
    return f"Study {info['study']}: scene {info['scene']}."


def _landscapes(
    rows: list[dict], params: list[str], metrics: list[str], folder: Path
) -> list[tuple[str, str]]:
    out = []
    n = max(1, len(params))
    info = _study_info(folder)
    for m in metrics:
        fig = agg_figure(max(3.4 * n, 6.4), 3.2)
        axes = fig.subplots(1, n, squeeze=False, sharey=True)[0]
        for ax, p in zip(axes, params, strict=False):
            xs = [r["overrides"].get(p) for r in rows]
            ys = [r["metrics"].get(m) for r in rows]
            pts = [(x, y, over_limit(r)) for x, y, r in zip(xs, ys, rows, strict=True)
                   if isinstance(y, int | float) and isinstance(x, int | float)]  # fmt: skip
            styles = ((False, {"marker": "o", "ms": 4}),
                      (True, {"marker": "x", "ms": 5, "color": "#b00", "mew": 1.2}))  # fmt: skip
            for unsafe, style in styles:
                kept = [(x, y) for x, y, u in pts if u is unsafe]
                if kept:
                    label = "over the IEC 62471 exempt-group limit" if unsafe else "run"
                    ax.plot(*zip(*kept, strict=True), linestyle="none", label=label, **style)
            if any(u for _, _, u in pts):
                ax.legend(fontsize=7)
            ax.set_xlabel(axis_label(p), fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, linewidth=0.3, alpha=0.5)
        axes[0].set_ylabel(axis_label(m), fontsize=8)
        caption = (
            f"{m} of each committed run (one dot per run; a red × over the IEC 62471 "
            f"exempt-group limit) against each varied parameter "
            f"({', '.join(params) or 'none'}), the other parameters at the run's own values; "
            f"read from the study's store, not recomputed. {study_caption(folder)} "
            f"{m}: {metric_budget(m, info)}."
        )
        out.append((caption, _png(fig)))
    return out


def _extent(size_mm) -> tuple[float, float, float, float] | None:
    if not size_mm:
        return None
    w, h = size_mm
    return (-w / 2, w / 2, -h / 2, h / 2)


def _best_images(folder: Path) -> list[tuple[str, str]]:
    """The best run's stored eye-plane pattern and eye image, and its tracking-error maps."""
    arrays, meta = folder / BEST_RUN_FILES[0], folder / BEST_RUN_FILES[1]
    if not (arrays.exists() and meta.exists()):
        return []
    with np.load(arrays) as data:
        pattern, image = data["eye_plane"], data["eye_image"]
    info = json.loads(meta.read_text(encoding="utf-8"))
    scene = info.get("scene_name", info.get("scene"))
    seeded = "seed" in info
    how = (
        f"scene {scene} with the run's overrides, seed {info['seed']}, "
        f"{info['samples_per_pixel']} camera samples per pixel (fast estimator)"
        if seeded
        else "seed not recorded (best_run.json written before eyelume recorded it)"
    )
    fig = agg_figure(10, 3.8)
    a, b = fig.subplots(1, 2)
    plane = _extent(info.get("eye_plane_mm"))
    draw_maps(fig, [a], [pattern], extent=plane, cmap=CMAP_IRRADIANCE,
              label="eye-plane irradiance (W/mm²)", vmax=float(np.max(pattern)),
              xlabel="eye plane x (mm)" if plane else "eye plane column (px)",
              ylabel="eye plane y (mm)" if plane else "eye plane row (px)")  # fmt: skip
    a.set_title("eye-plane irradiance (closed form)", fontsize=10)
    picture = _extent(info.get("picture_mm"))
    top = float(np.percentile(image, 99.5))
    if picture:
        labels = pixel_pitch_label("x", picture, image.shape[1]), "image y on the sensor (mm)"
    else:
        labels = "image column (sensor px)", "image row (sensor px)"
    draw_maps(fig, [b], [image], extent=picture, cmap=CMAP_SENSOR, vmax=top,
              clipped=bool(np.max(image) > top), label="image-plane irradiance (W/mm²)",
              xlabel=labels[0], ylabel=labels[1])  # fmt: skip
    b.set_title("eye image on the sensor (glints clipped at 99.5 %)", fontsize=10)
    out = [
        (
            f"Best run (#{info['index']}): its eye-plane irradiance toward the eye (closed form: "
            "no rays) and the simulated eye image as the camera sees it, rendered anew after "
            f"the study (eyelume report --scene) and stored beside its results: {how}."
            + (
                " OVER the IEC 62471 exempt-group limit: no run of the study is within it."
                if info.get("over_limit")
                else ""
            ),  # fmt: skip
            _png(fig),
        )
    ]
    if info.get("tracking_rows"):
        spp = info.get("tracking_samples_per_pixel")
        track = (
            f"scene {scene} with the run's overrides, seed {info['seed']}, {spp} camera samples "
            "per pixel per frame (fast estimator), geometric gaze model (no calibration)"
            if seeded
            else how
        )
        buf = io.BytesIO()
        save_error_maps(info["tracking_rows"], buf, caption=track)
        out.append(("Best run: pupil-centre, glint and gaze errors of the tracking evaluation "
                    "over the gaze grid (one cell per gaze; a red × where the frame failed): "
                    f"{track}.",
                    base64.b64encode(buf.getvalue()).decode("ascii")))  # fmt: skip
    return out


def _best_list(best: list[dict], merit: str | None) -> str:
    """The best runs as readable lines: ``run 3: leds.height_mm = 30 mm, leds.pitch_deg = 10°
    — eye_plane_merit = 0.0123 (dimensionless)``."""
    items = []
    for r in best:
        setting = ", ".join(
            f"{html.escape(str(k))} = {html.escape(_value_with_unit(k, v))}"
            for k, v in sorted(r["overrides"].items())
        )
        value = r["metrics"][merit]
        unit = unit_of(merit)
        flag = (
            ' <strong class="over-limit">OVER the IEC 62471 exempt-group limit</strong>'
            if over_limit(r)
            else ""
        )
        items.append(
            f"<li>run {html.escape(str(r['index']))}: {setting or 'the base scene'} — "
            f"{html.escape(merit)} = {value:.5g}{f' ({html.escape(unit)})' if unit else ''}"
            f"{flag}</li>"
        )
    return "".join(items)


def _best_warning(rows: list[dict], best: list[dict]) -> str:
    """A loud line when the best run is over the eye-safety limit (no run is within it)."""
    if not best or not over_limit(best[0]):
        return ""
    return (
        '<p class="over-limit"><strong>No run of this study is within the IEC 62471 exempt-group '
        f"limit ({len(rows)} runs): the best run below is over it and is not a safe design."
        "</strong></p>"
    )


#: What ``eyelume report`` takes, said when it is given something else.
_TAKES = (
    "eyelume report takes a study's folder (`eyelume study --out`: results.sqlite) or a "
    "dataset's (`eyelume dataset --out`: labels.jsonl)"
)


def check_report_folder(folder: str | Path) -> str:
    """ "study" or "dataset": the kind of folder ``folder`` is. StoreError in one line for a
    path that does not exist, a file, a render's folder (``eyelume render --out``: its
    figures are already there) or a folder of neither kind, saying what the report takes."""
    folder = Path(folder)
    if not folder.exists():
        raise StoreError(f"no such folder; {_TAKES}", file=folder)
    if not folder.is_dir():
        raise StoreError(f"is a file, not a folder; {_TAKES}", file=folder)
    if (folder / "labels.jsonl").exists() or (folder / "dataset.json").exists():
        return "dataset"
    if (folder / "results.sqlite").exists():
        return "study"
    if (folder / "summary.json").is_file():
        raise StoreError(
            f"a render's folder (summary.json): its figures are already in it; {_TAKES}",
            file=folder,
        )
    raise StoreError(f"neither a study's nor a dataset's folder; {_TAKES}", file=folder)


def write_report(folder: str | Path, out: str | Path | None = None) -> Path:
    """Write the study's page to ``out`` (default ``folder/report.html``) from what its store
    has committed and the best run's stored pictures; returns the page's path. The store is
    read read-only (:func:`eyelume.optimize.store.read_rows`), so a study still running or a
    read-only folder can be reported. StoreError for a missing, damaged or empty store, and
    for a default ``out`` in a folder that cannot be written (give ``out``)."""
    from eyelume.optimize.store import read_rows

    folder = Path(folder)
    if check_report_folder(folder) == "dataset":
        return write_dataset_report(folder, out)
    rows, note = read_rows(folder)
    if not rows:
        raise StoreError("the study has no finished run yet", file=folder)
    path = folder / "report.html" if out is None else Path(out)
    studies = sorted({r["study"] for r in rows})
    params = sorted({k for r in rows for k in r["overrides"]})
    metrics = sorted({k for r in rows for k, v in r["metrics"].items()
                      if isinstance(v, int | float) and not isinstance(v, bool)})  # fmt: skip
    figures = _landscapes(rows, params, metrics, folder)
    merit, best = best_runs(rows)
    if best:
        figures += _best_images(folder)

    def cell(v) -> str:
        if v is None:  # not measured, or not a finite number (flagged in "non_finite")
            return "—"
        if isinstance(v, float):
            return f"{v:.5g}" if math.isfinite(v) else "—"
        return html.escape(str(v))

    head = "".join(f"<th>{html.escape(axis_label(c))}</th>" for c in ["#", *params, *metrics])
    body = []
    for r in rows:
        unsafe = r["metrics"].get("within_exempt_group") is False
        tds = [cell(r["index"]), *(cell(r["overrides"].get(p)) for p in params),
               *(cell(r["metrics"].get(m)) for m in metrics)]  # fmt: skip
        cls = ' class="unsafe"' if unsafe else ""
        body.append(f"<tr{cls}>" + "".join(f"<td>{t}</td>" for t in tds) + "</tr>")
    best_html = _best_list(best, merit)
    figs = "".join(
        f'<figure><img alt="{html.escape(t)}" src="data:image/png;base64,{d}">'
        f"<figcaption>{html.escape(t)}</figcaption></figure>"
        for t, d in figures
    )
    n_unsafe = sum(r["metrics"].get("within_exempt_group") is False for r in rows)
    n_nonfinite = sum(
        bool(r["metrics"].get("non_finite"))
        or any(isinstance(v, float) and not math.isfinite(v) for v in r["metrics"].values())
        for r in rows
    )
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1"><title>eyelume study {
        html.escape(", ".join(studies))
    }
</title>{_STYLE}</head>
<body data-figures="0">
<h1>Study {html.escape(", ".join(studies))}</h1>
<p>{len(rows)} runs committed; {n_unsafe} over an IEC 62471 exempt-group limit (red).</p>
{f"<p>{html.escape(note)}</p>" if note else ""}
{
        f"<p>{n_nonfinite} runs have a metric that is not a finite number (shown —).</p>"
        if n_nonfinite
        else ""
    }
<h2>Merit landscapes</h2><div class="figures">{figs}</div>
<h2>Best runs{f" by {html.escape(str(merit))}" if merit else ""}</h2>
{_best_warning(rows, best)}<p>Runs within the eye-safety limit rank first.</p><ol>{best_html}</ol>
<h2>All runs</h2><div class="scroll"><table><tr>{head}</tr>{"".join(body)}</table></div>
{_LOAD_SCRIPT}</body></html>
"""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(page, encoding="utf-8")
    except OSError as exc:
        hint = "; give --out FILE elsewhere" if out is None else ""
        raise StoreError(
            f"cannot write the report ({exc.strerror or exc}){hint}", file=path
        ) from None
    return path


def _dataset_summary(ds) -> list[tuple[str, str]]:
    """(quantity, value) rows of the dataset page's table, read from the label lines."""
    labels = ds.labels
    n = len(labels)
    sizes = sorted(
        {tuple(lab["size_px"]) for lab in labels if isinstance(lab.get("size_px"), list)}
    )
    bits = sorted({lab.get("image_bits") for lab in labels if lab.get("image_bits")})

    def mean_of(values) -> str:
        v = [x for x in values if isinstance(x, int | float) and not isinstance(x, bool)]
        return f"{np.mean(v):.3g} (over {len(v)} pictures)" if v else "—"

    glints = [lab.get("glints") for lab in labels if isinstance(lab.get("glints"), list)]
    rows = [
        ("pictures", str(n)),
        ("indices", f"{labels[0]['index']} … {labels[-1]['index']}"),
        ("scene", ds.scene),
        ("seed", str(ds.seed) if ds.seed is not None else "not recorded"),
        ("picture size (columns × rows, px)", ", ".join(f"{c} × {r}" for c, r in sizes) or "—"),
        ("PNG bit depth", ", ".join(str(b) for b in bits) or "—"),
        ("share with glasses", f"{np.mean([bool(lab.get('glasses')) for lab in labels]):.3f}"),
        (
            "pupil visible share, mean",
            mean_of((lab.get("pupil") or {}).get("visible_share") for lab in labels),
        ),  # fmt: skip
        ("eye openness, mean", mean_of(lab.get("eye_openness") for lab in labels)),
        (
            "glints visible per picture, mean",
            mean_of(sum(bool(g.get("visible")) for g in gs) for gs in glints),
        ),  # fmt: skip
        (
            "glints saturated per picture, mean",
            mean_of(sum(bool(g.get("saturated")) for g in gs) for gs in glints),
        ),  # fmt: skip
    ]
    render = [lab.get("render") or {} for lab in labels]
    for key, what in (
        ("samples_per_pixel", "render: camera samples per pixel, mean"),
        ("median_skin_rel_error", "render: median skin pixel's relative standard error, mean"),
        ("skin_shot_noise", "render: the sensor's relative shot noise there, mean"),
        ("seconds", "render: seconds per picture, mean"),
    ):
        rows.append((what, mean_of(r.get(key) for r in render)))
    return rows


def write_dataset_report(folder: str | Path, out: str | Path | None = None) -> Path:
    """Write a dataset folder's page (``eyelume dataset``'s output, read by
    :func:`eyelume.report.dataset_outputs.read_dataset`) to ``out`` (default
    ``folder/report.html``): a table of what the labels say, a contact sheet of sample pictures
    with their labels drawn on them and the distributions of the varied parameters
    (:mod:`eyelume.report.dataset_outputs`), embedded as PNG; returns the page's path.
    InputFileError for a folder without a readable ``labels.jsonl``; StoreError when the page
    cannot be written."""
    from eyelume.report.dataset_outputs import (
        dataset_caption,
        figure_png,
        read_dataset,
        save_contact_sheet,
        save_distributions,
    )

    folder = Path(folder)
    ds = read_dataset(folder)
    path = folder / "report.html" if out is None else Path(out)
    figures = [
        (
            f"Sample pictures as the camera recorded them (images/*.png, DN on one grey scale) "
            "with their labels drawn from labels.jsonl: pupil and iris ellipses, each glint's "
            "true position with its LED id (a white × when saturated, grey when hidden), "
            f"spurious reflections; read, not recomputed. {dataset_caption(ds)}.",
            figure_png(save_contact_sheet, ds),
        ),
        (
            "Distributions of what varied from picture to picture (gaze target, pupil diameter, "
            "each [[vary]] path, the people's sampled parameters) and the share with glasses, "
            f"read from labels.jsonl. {dataset_caption(ds)}.",
            figure_png(save_distributions, ds),
        ),
    ]
    figs = "".join(
        f'<figure><img alt="{html.escape(t)}" src="data:image/png;base64,'
        f'{base64.b64encode(d).decode("ascii")}"><figcaption>{html.escape(t)}</figcaption>'
        "</figure>"
        for t, d in figures
    )
    table = "".join(
        f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
        for k, v in _dataset_summary(ds)
    )
    name = html.escape(ds.name)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1"><title>eyelume dataset {
        name
    }</title>{_STYLE}</head>
<body data-figures="0">
<h1>Dataset {name}</h1>
<p>Folder {html.escape(str(folder))}: labels in labels.jsonl (one JSON object per picture; the
schema in schema.json), pictures in images/, segmentations in segmentation/. An OpenEDS-layout
copy for segmentation models: <code>eyelume dataset-export {html.escape(str(folder))} --out
DIR</code>.</p>
<div class="scroll"><table>{table}</table></div>
<h2>Pictures and labels</h2><div class="figures">{figs}</div>
{_LOAD_SCRIPT}</body></html>
"""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(page, encoding="utf-8")
    except OSError as exc:
        hint = "; give --out FILE elsewhere" if out is None else ""
        raise StoreError(
            f"cannot write the report ({exc.strerror or exc}){hint}", file=path
        ) from None
    return path
