"""Figures of the illumination optimisation (paper Section 4): merit landscapes, patterns against
their targets, the merit against δ beside the paper's values, and the eye images per δ."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.ticker import LogFormatterSciNotation, LogLocator, NullFormatter

from eyelume.report.plots import (
    CMAP_IRRADIANCE,
    CMAP_MAGNITUDE,
    CMAP_SENSOR,
    agg_figure,
    draw_maps,
    save_figure,
)

__all__ = [
    "save_sweep_heatmaps",
    "save_pattern_vs_target",
    "save_merit_vs_delta",
    "save_delta_gallery",
]


def save_sweep_heatmaps(
    heights: np.ndarray,
    distances: np.ndarray,
    pitches: np.ndarray,
    merit: np.ndarray,
    path: str | Path,
    title: str,
    caption: str = "",
) -> None:
    """One Z × θ heatmap of the generator merit per LED height Y, on one colour scale (log,
    viridis reversed: dark is better), with one colour bar; the best configuration is circled
    (legend). ``merit`` has shape (len(heights), len(distances), len(pitches)); NaN marks
    impossible configurations (drawn blank). ``caption`` (scene, seed, budget) goes under the
    title."""
    from matplotlib.lines import Line2D

    finite = merit[np.isfinite(merit)]
    vmin, vmax = float(finite.min()), float(finite.max())
    norm = LogNorm(vmin=max(vmin, vmax * 1e-6), vmax=vmax if vmax > vmin else vmin * 1.01)
    # at least 6.4 in wide: one height's panel leaves room for the caption; taller per title line
    width = max(3.0 * len(heights) + 1.6, 6.4)
    heading = _wrapped(title, caption, width)
    fig = agg_figure(width, 3.4 + 0.2 * heading.count("\n") + 0.2)
    axes = fig.subplots(1, len(heights), sharey=True, squeeze=False)
    best = np.unravel_index(np.nanargmin(merit), merit.shape)

    def edges(v: np.ndarray) -> tuple[float, float]:
        half = float(np.min(np.diff(v))) / 2 if v.size > 1 else 2.5
        return float(v[0]) - half, float(v[-1]) + half

    im = None
    for i, (ax, y) in enumerate(zip(axes[0], heights, strict=True)):
        im = ax.imshow(
            merit[i].T,
            origin="lower",
            aspect="auto",
            norm=norm,
            cmap=CMAP_MAGNITUDE + "_r",
            extent=(*edges(distances), *edges(pitches)),
        )
        ax.set_title(f"LED height Y = {y:g} mm", fontsize=10)
        ax.set_xlabel("LED distance Z (mm)")
        if i == best[0]:
            ax.plot(distances[best[1]], pitches[best[2]], "o", mfc="none", mec="red", ms=12)
    axes[0][0].set_ylabel("LED pitch θ (°)")
    cb = fig.colorbar(im, ax=axes[0].tolist(),
                      label="generator merit, lower is better (dimensionless)")  # fmt: skip
    # labels at 1, 2 and 5 × 10^k only: matplotlib's default labels every minor tick of a short
    # log range, and on a short colour bar those labels run into each other
    cb.ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    cb.ax.yaxis.set_major_formatter(LogFormatterSciNotation(labelOnlyBase=False))
    cb.ax.yaxis.set_minor_formatter(NullFormatter())
    marker = Line2D([], [], marker="o", mfc="none", mec="red", ms=9, linestyle="none",
                    label="best configuration")  # fmt: skip
    fig.legend(handles=[marker], loc="outside lower left", fontsize="small", frameon=False)
    fig.suptitle(heading, fontsize=10)
    save_figure(fig, path, dpi=110)


def _wrapped(title: str, caption: str, width_in: float) -> str:
    """``title`` and ``caption`` on their own lines, each wrapped to the figure's width (about
    12 characters of a 10 pt font per inch), so a narrow figure's suptitle does not run into its
    colour bar."""
    import textwrap

    width = max(20, int(width_in * 12))
    lines = [title, caption] if caption else [title]
    return "\n".join(textwrap.fill(line, width) for line in lines)


def save_pattern_vs_target(
    pattern: np.ndarray,
    target: np.ndarray,
    extent_mm: tuple[float, float, float, float],
    path: str | Path,
    title: str,
    caption: str = "",
) -> None:
    """The eye-plane pattern and the target side by side, each scaled to unit mean, on one
    colour scale (:data:`~eyelume.report.plots.CMAP_IRRADIANCE`) with one colour bar.
    ``caption`` (scene, seed, budget) goes under the title."""
    a, b = pattern / pattern.mean(), target / target.mean()
    vmax = float(max(a.max(), b.max()))
    fig = agg_figure(9, 3.8)
    axes = fig.subplots(1, 2, sharey=True)
    im = None
    for ax, data, name in ((axes[0], a, "best pattern"), (axes[1], b, "target")):
        im = ax.imshow(data, extent=extent_mm, cmap=CMAP_IRRADIANCE, vmin=0, vmax=vmax)
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("eye plane x (mm)")
    axes[0].set_ylabel("eye plane y (mm)")
    fig.colorbar(im, ax=axes.tolist(), label="irradiance / its own mean (dimensionless)")
    fig.suptitle(_wrapped(title, caption, fig.get_figwidth()), fontsize=10)
    save_figure(fig, path, dpi=110)


def save_merit_vs_delta(
    deltas: Sequence[float],
    merits: Sequence[float],
    paper_deltas: Sequence[float],
    paper_merits: Sequence[float],
    path: str | Path,
    merit_se: Sequence[float] | None = None,
    caption: str = "",
) -> None:
    """Our evaluator merit and the paper's published LightTools merits against δ, each divided
    by its own minimum, on one axis. The paper's merit scale is undocumented, so only where each
    curve is lowest and how steeply it rises relative to its minimum can be compared; the axis
    says so. ``merit_se`` (our standard errors) draws error bars, scaled alike."""
    ours = np.asarray(merits, dtype=float)
    paper = np.asarray(paper_merits, dtype=float)
    fig = agg_figure(6.4, 4.4)
    ax = fig.subplots()
    m0 = float(np.min(ours))
    yerr = None if merit_se is None else np.asarray(merit_se, dtype=float) / m0
    ax.errorbar(deltas, ours / m0, yerr=yerr, fmt="o-", color="tab:blue", capsize=3,
                label="eyelume evaluator merit (± 1 standard error)")  # fmt: skip
    if paper.size:
        ax.plot(paper_deltas, paper / float(np.min(paper)), "s--", color="tab:red",
                label="paper, SPIE 5875 (LightTools merit)")  # fmt: skip
    ax.set_xlabel("target falloff δ at the eye plane's corner (dimensionless)")
    ax.set_ylabel("merit / its own minimum (dimensionless)")
    ax.legend(loc="upper center", fontsize="small")
    ax.grid(True, linewidth=0.3, alpha=0.5)
    ax.set_title(
        "Evaluator merit against δ, each curve divided by its own minimum\n"
        "(the paper's merit scale is unknown: compare minima and shapes, not values)"
        + (f"\n{caption}" if caption else ""),
        fontsize=9,
    )
    save_figure(fig, path, dpi=110)


def save_delta_gallery(
    deltas: Sequence[float],
    patterns: Sequence[np.ndarray],
    images: Sequence[np.ndarray],
    labels: Sequence[str],
    path: str | Path,
    caption: str = "",
    plane_mm: tuple[float, float] | None = None,
    picture_mm: tuple[float, float] | None = None,
) -> None:
    """For each δ, its best eye-plane pattern (top, :data:`~eyelume.report.plots.CMAP_IRRADIANCE`)
    and the simulated eye image (bottom, grey as the camera shows it, glints clipped at the
    99.5th percentile), each row on one colour scale with a colour bar in SI-prefixed W/mm².
    The eye plane is drawn in mm of the receiver (``plane_mm`` = its width, height), the eye
    image in mm on the sensor (``picture_mm`` = the picture's width, height) with the pixel size
    in the row's label; without them, in array columns and rows (px)."""
    n = len(deltas)
    fig = agg_figure(2.6 * n + 1.6, 5.6)
    axes = fig.subplots(2, n, squeeze=False, sharex="row", sharey="row")
    p_max = max(float(np.max(p)) for p in patterns)
    i_max = max(float(np.percentile(i, 99.5)) for i in images)
    clipped = any(float(np.max(i)) > i_max for i in images)
    if plane_mm is not None:
        w, h = plane_mm
        extent = (-w / 2, w / 2, -h / 2, h / 2)
        xlab, ylab = "eye plane x (mm)", "eye plane\ny (mm)"
    else:
        extent, xlab, ylab = None, "eye plane column (px)", "eye plane\nrow (px)"
    draw_maps(fig, axes[0], patterns, extent=extent, cmap=CMAP_IRRADIANCE, vmax=p_max,
              label="eye-plane irradiance (W/mm²)", xlabel=xlab, ylabel=ylab)  # fmt: skip
    if picture_mm is not None:
        w, h = picture_mm
        extent = (-w / 2, w / 2, -h / 2, h / 2)
        pitch = w / images[0].shape[1]  # square pixels: one size said once, beside the row
        xlab = "image x on the sensor (mm)"
        ylab = f"eye image, 1 px = {pitch:.3g} mm\ny on the sensor (mm)"
    else:
        extent, xlab, ylab = None, "image column (sensor px)", "eye image\nrow (sensor px)"
    draw_maps(fig, axes[1], images, extent=extent, cmap=CMAP_SENSOR, vmax=i_max, clipped=clipped,
              label="image-plane irradiance (W/mm²)", xlabel=xlab, ylabel=ylab)  # fmt: skip
    for j in range(n):
        axes[0][j].set_title(f"δ = {deltas[j]:.1f}\n{labels[j]}", fontsize=8)
    fig.suptitle("Best pattern and eye image per δ" + (f"\n{caption}" if caption else ""),
                 fontsize=10)  # fmt: skip
    save_figure(fig, path, dpi=110)
