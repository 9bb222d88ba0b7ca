"""Figures of the illumination optimisation (paper Section 4): merit landscapes, patterns against
their targets, the merit against δ beside the paper's values, and the eye images per δ."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm

from eyelume.report.plots import agg_figure

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
) -> None:
    """One Z × θ heatmap of the generator merit per LED height Y, on one colour scale (log).

    ``merit`` has shape (len(heights), len(distances), len(pitches)); NaN marks impossible
    configurations (drawn blank). The best configuration is circled.
    """
    finite = merit[np.isfinite(merit)]
    vmin, vmax = float(finite.min()), float(finite.max())
    norm = LogNorm(vmin=max(vmin, vmax * 1e-6), vmax=vmax)
    fig = agg_figure(3.0 * len(heights) + 1.2, 3.6)
    axes = fig.subplots(1, len(heights), sharey=True, squeeze=False)
    best = np.unravel_index(np.nanargmin(merit), merit.shape)
    im = None
    for i, (ax, y) in enumerate(zip(axes[0], heights, strict=True)):
        im = ax.imshow(
            merit[i].T,
            origin="lower",
            aspect="auto",
            norm=norm,
            cmap="viridis_r",
            extent=(
                distances[0] - 2.5,
                distances[-1] + 2.5,
                pitches[0] - 2.5,
                pitches[-1] + 2.5,
            ),
        )
        ax.set_title(f"Y = {y:g} mm")
        ax.set_xlabel("Z (mm)")
        if i == best[0]:
            ax.plot(distances[best[1]], pitches[best[2]], "o", mfc="none", mec="red", ms=12)
    axes[0][0].set_ylabel("pitch θ (°)")
    fig.colorbar(im, ax=axes[0].tolist(), label="generator merit (lower is better)")
    fig.suptitle(title)
    fig.savefig(path, dpi=110, bbox_inches="tight")


def save_pattern_vs_target(
    pattern: np.ndarray,
    target: np.ndarray,
    extent_mm: tuple[float, float, float, float],
    path: str | Path,
    title: str,
) -> None:
    """The eye-plane pattern and the target side by side, each scaled to unit mean."""
    fig = agg_figure(9, 3.6)
    axes = fig.subplots(1, 2)
    for ax, data, name in ((axes[0], pattern, "pattern"), (axes[1], target, "target")):
        im = ax.imshow(data / data.mean(), extent=extent_mm, cmap="inferno", vmin=0)
        ax.set_title(f"{name} / its mean")
        ax.set_xlabel("x (mm)")
        fig.colorbar(im, ax=ax)
    axes[0].set_ylabel("y (mm)")
    fig.suptitle(title)
    fig.savefig(path, dpi=110, bbox_inches="tight")


def save_merit_vs_delta(
    deltas: Sequence[float],
    merits: Sequence[float],
    paper_deltas: Sequence[float],
    paper_merits: Sequence[float],
    path: str | Path,
) -> None:
    """Our evaluator merit against δ (left axis) and the paper's published LightTools merits
    (right axis: another, undocumented scale — compare shapes and minima, not values)."""
    fig = agg_figure(6.4, 4)
    ax = fig.subplots()
    ax.plot(deltas, merits, "o-", color="tab:blue", label="eyelume evaluator merit")
    ax.set_xlabel("falloff δ at the eye plane's corner")
    ax.set_ylabel("eyelume evaluator merit", color="tab:blue")
    ax2 = ax.twinx()
    ax2.plot(paper_deltas, paper_merits, "s--", color="tab:red", label="paper (LightTools)")
    ax2.set_ylabel("paper's merit (LightTools scale)", color="tab:red")
    lines = ax.get_lines() + ax2.get_lines()
    ax.legend(lines, [ln.get_label() for ln in lines], loc="upper center")
    ax.set_title("Evaluator merit against the target's falloff δ")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")


def save_delta_gallery(
    deltas: Sequence[float],
    patterns: Sequence[np.ndarray],
    images: Sequence[np.ndarray],
    labels: Sequence[str],
    path: str | Path,
) -> None:
    """For each δ, its best eye-plane pattern (top) and the simulated eye image (bottom)."""
    n = len(deltas)
    fig = agg_figure(2.2 * n, 4.4)
    axes = fig.subplots(2, n, squeeze=False)
    for j in range(n):
        axes[0][j].imshow(patterns[j], cmap="inferno")
        axes[0][j].set_title(f"δ = {deltas[j]:.1f}", fontsize=9)
        axes[1][j].imshow(images[j], cmap="gray", vmin=0, vmax=np.percentile(images[j], 99.5))
        axes[1][j].set_xlabel(labels[j], fontsize=7)
        for ax in (axes[0][j], axes[1][j]):
            ax.set_xticks([])
            ax.set_yticks([])
    axes[0][0].set_ylabel("eye plane")
    axes[1][0].set_ylabel("eye image")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
