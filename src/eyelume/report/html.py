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
from eyelume.optimize.best_run import BEST_RUN_FILES, best_runs
from eyelume.report.plots import agg_figure, save_figure
from eyelume.report.tracking_outputs import save_error_maps

__all__ = ["write_report"]


def _png(fig: Figure) -> str:
    buf = io.BytesIO()
    save_figure(fig, buf, dpi=90)
    return base64.b64encode(buf.getvalue()).decode("ascii")


#: Units read from a parameter's or metric's name ending (the scene's and metrics' own naming:
#: ``leds.height_mm``, ``pitch_deg``, ``corneal_margin`` = exposure limit / exposure).
_NAME_UNITS = (
    ("_w_mm2", "W/mm²"),
    ("_w_sr", "W/sr"),
    ("_mm", "mm"),
    ("_deg", "°"),
    ("_nm", "nm"),
    ("_px", "px"),
    ("_ms", "ms"),
    ("_margin", "limit / exposure"),
    ("_merit", "dimensionless"),
)


def axis_label(name: str) -> str:
    """``name`` with its unit in parentheses when its ending says it (``_NAME_UNITS``)."""
    for end, unit in _NAME_UNITS:
        if name.endswith(end):
            return f"{name} ({unit})"
    return name


def study_caption(folder: Path) -> str:
    """The study's scene, seed and budget, as its runner recorded them in ``study.json``
    (:data:`eyelume.optimize.runner.STUDY_FILE`), for the captions; says so when the folder has
    none (a study run before eyelume wrote it) or it cannot be read."""
    from eyelume.optimize.runner import STUDY_FILE

    try:
        info = json.loads((folder / STUDY_FILE).read_text(encoding="utf-8"))
        return (
            f"Study {info['study']}: scene {info['scene']}, seed {info['seed']}, "
            f"{info['samples_per_pixel']} camera samples per pixel."
        )
    except (OSError, ValueError, KeyError, TypeError):
        return f"The folder records no study scene or seed ({STUDY_FILE} missing or unreadable)."


def _landscapes(
    rows: list[dict], params: list[str], metrics: list[str], study: str
) -> list[tuple[str, str]]:
    out = []
    n = max(1, len(params))
    for m in metrics:
        fig = agg_figure(3.4 * n, 3.0)
        axes = fig.subplots(1, n, squeeze=False, sharey=True)[0]
        for ax, p in zip(axes, params, strict=False):
            xs = [r["overrides"].get(p) for r in rows]
            ys = [r["metrics"].get(m) for r in rows]
            pts = [(x, y) for x, y in zip(xs, ys, strict=True)
                   if isinstance(y, int | float) and isinstance(x, int | float)]  # fmt: skip
            if pts:
                ax.plot(*zip(*pts, strict=True), "o", ms=4)
            ax.set_xlabel(axis_label(p), fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, linewidth=0.3, alpha=0.5)
        axes[0].set_ylabel(axis_label(m), fontsize=8)
        caption = (
            f"{m} of each committed run (one dot per run) against each varied parameter "
            f"({', '.join(params) or 'none'}), the other parameters at the run's own values; "
            f"read from the study's store, not recomputed. {study}"
        )
        out.append((caption, _png(fig)))
    return out


def _best_images(folder: Path) -> list[tuple[str, str]]:
    """The best run's stored eye-plane pattern and eye image, and its tracking-error maps."""
    arrays, meta = folder / BEST_RUN_FILES[0], folder / BEST_RUN_FILES[1]
    if not (arrays.exists() and meta.exists()):
        return []
    with np.load(arrays) as data:
        pattern, image = data["eye_plane"], data["eye_image"]
    info = json.loads(meta.read_text(encoding="utf-8"))
    how = (
        f"scene {info.get('scene_name', info.get('scene'))} with the run's overrides, "
        f"seed {info['seed']}, {info['samples_per_pixel']} camera samples per pixel"
        if "seed" in info
        else "seed not recorded (best_run.json written before eyelume recorded it)"
    )
    fig = agg_figure(9, 3.4)
    a, b = fig.subplots(1, 2)
    im = a.imshow(pattern, cmap="inferno", vmin=0)
    a.set_title("eye-plane irradiance", fontsize=10)
    fig.colorbar(im, ax=a, label="irradiance (W/mm²)")
    im = b.imshow(image, cmap="gray", vmin=0, vmax=float(np.percentile(image, 99.5)) or 1.0)
    b.set_title("eye image (glints clipped at 99.5 %)", fontsize=10)
    fig.colorbar(im, ax=b, label="irradiance (W/mm²)", extend="max")
    for ax in (a, b):
        ax.set_xlabel("column (px)", fontsize=8)
        ax.set_ylabel("row (px)", fontsize=8)
        ax.tick_params(labelsize=7)
    out = [
        (
            f"Best run (#{info['index']}): its eye-plane irradiance toward the eye and the "
            "simulated eye image, rendered anew with the fast estimator after the study "
            f"(eyelume report --scene) and stored beside its results: {how}.",
            _png(fig),
        )
    ]
    if info.get("tracking_rows"):
        buf = io.BytesIO()
        save_error_maps(info["tracking_rows"], buf)
        spp = info.get("tracking_samples_per_pixel")
        track = how.replace(f"{info.get('samples_per_pixel')} camera", f"{spp} camera")
        out.append(("Best run: pupil-centre, glint and gaze errors of the tracking evaluation "
                    "over the gaze grid (one cell per gaze; a red × where the frame failed): "
                    f"{track}.",
                    base64.b64encode(buf.getvalue()).decode("ascii")))  # fmt: skip
    return out


def write_report(folder: str | Path, out: str | Path | None = None) -> Path:
    """Write the study's page to ``out`` (default ``folder/report.html``) from what its store
    has committed and the best run's stored pictures; returns the page's path. The store is
    read read-only (:func:`eyelume.optimize.store.read_rows`), so a study still running or a
    read-only folder can be reported. StoreError for a missing, damaged or empty store, and
    for a default ``out`` in a folder that cannot be written (give ``out``)."""
    from eyelume.optimize.store import read_rows

    folder = Path(folder)
    rows, note = read_rows(folder)
    if not rows:
        raise StoreError("the study has no finished run yet", file=folder)
    path = folder / "report.html" if out is None else Path(out)
    studies = sorted({r["study"] for r in rows})
    params = sorted({k for r in rows for k in r["overrides"]})
    metrics = sorted({k for r in rows for k, v in r["metrics"].items()
                      if isinstance(v, int | float) and not isinstance(v, bool)})  # fmt: skip
    figures = _landscapes(rows, params, metrics, study_caption(folder))
    merit, best = best_runs(rows)
    if best:
        figures += _best_images(folder)

    def cell(v) -> str:
        if v is None:  # not measured, or not a finite number (flagged in "non_finite")
            return "—"
        if isinstance(v, float):
            return f"{v:.5g}" if math.isfinite(v) else "—"
        return html.escape(str(v))

    head = "".join(f"<th>{html.escape(c)}</th>" for c in ["#", *params, *metrics])
    body = []
    for r in rows:
        unsafe = r["metrics"].get("within_exempt_group") is False
        tds = [cell(r["index"]), *(cell(r["overrides"].get(p)) for p in params),
               *(cell(r["metrics"].get(m)) for m in metrics)]  # fmt: skip
        cls = ' class="unsafe"' if unsafe else ""
        body.append(f"<tr{cls}>" + "".join(f"<td>{t}</td>" for t in tds) + "</tr>")
    best_html = "".join(
        f"<li>run {html.escape(str(r['index']))}: {html.escape(str(r['overrides']))} — "
        f"{html.escape(str(merit))} "
        f"{r['metrics'][merit]:.5g}</li>"
        for r in best
    )
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
</title><style>
body {{ font-family: sans-serif; margin: 1em auto; padding: 0 1em; max-width: 1600px; }}
.scroll {{ overflow-x: auto; max-width: 100%; }}
table {{ border-collapse: collapse; font-size: 0.9em; }}
td, th {{ border: 1px solid #ccc; padding: 2px 6px; text-align: right; white-space: nowrap; }}
th {{ background: #f4f4f4; position: sticky; top: 0; }}
tr.unsafe td {{ color: #b00; font-weight: bold; }}
figure {{ display: inline-block; vertical-align: top; max-width: 100%; margin: 0.5em; }}
figure img {{ max-width: 100%; height: auto; }}
figcaption {{ font-size: 0.9em; color: #333; max-width: 60em; }}
</style></head>
<body data-figures="0">
<h1>Study {html.escape(", ".join(studies))}</h1>
<p>{len(rows)} runs committed; {n_unsafe} over an IEC 62471 exempt-group limit (red).</p>
{f"<p>{html.escape(note)}</p>" if note else ""}
{
        f"<p>{n_nonfinite} runs have a metric that is not a finite number (shown —).</p>"
        if n_nonfinite
        else ""
    }
<h2>Merit landscapes</h2>{figs}
<h2>Best runs{f" by {html.escape(str(merit))}" if merit else ""}</h2><ol>{best_html}</ol>
<h2>All runs</h2><div class="scroll"><table><tr>{head}</tr>{"".join(body)}</table></div>
<script>
window.addEventListener("load", () => {{
  const ok = [...document.images].filter(i => i.complete && i.naturalWidth > 0).length;
  document.body.dataset.figures = String(ok);
  // for a headless check of the layout: how far the page overflows the window sideways
  document.body.dataset.overflowPx = String(
    Math.max(0, document.documentElement.scrollWidth - window.innerWidth));
}});
</script></body></html>
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
