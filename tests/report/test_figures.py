"""Every matplotlib figure eyelume writes, drawn on a small case, is checked from matplotlib's own
extents (tests/report/figure_checks.py): no two text elements overlap, every image panel has a
colour bar whose label names a unit, every numeric axis a label with a unit, and a caption names
the scene and the seed.

The figures are caught through :func:`eyelume.report.plots.observe_figures` (every writer saves
through :func:`eyelume.report.plots.save_figure`). The render's figures come from a real 40 × 30
render of ``paper2005``; the sweep, δ-study and tracking figures from inputs of the shapes those
commands pass (their computation is tested elsewhere; here only the drawing is).
"""

from __future__ import annotations

import numpy as np
import pytest
from figure_checks import (
    axes_without_unit_label,
    caption_missing,
    images_without_unit_colorbar,
    text_overlaps,
)

from eyelume.report.optimize_outputs import _caption as delta_caption
from eyelume.report.optimize_outputs import sweep_caption
from eyelume.report.optimize_plots import (
    save_delta_gallery,
    save_merit_vs_delta,
    save_pattern_vs_target,
    save_sweep_heatmaps,
)
from eyelume.report.plots import observe_figures, save_error_time_plot
from eyelume.report.tracking_outputs import _caption as tracking_caption
from eyelume.report.tracking_outputs import save_error_maps


class Caught:
    """Checks each figure as it is written; keeps the defects by file name."""

    def __init__(self, caption: tuple[str, int | None] | None) -> None:
        self.names: list[str] = []
        self.defects: dict[str, list] = {}
        self.caption = caption

    def __call__(self, fig, name: str) -> None:
        self.names.append(name)
        found = [f"texts overlap: {a!r} / {b!r}" for a, b in text_overlaps(fig)]
        found += images_without_unit_colorbar(fig)
        found += axes_without_unit_label(fig)
        if self.caption is not None:
            found += [m for m in [caption_missing(fig, *self.caption)] if m]
        if found:
            self.defects[name] = found


def _check(write, caption: tuple[str, int | None] | None) -> Caught:
    """Write the figures; each must pass the checks, with a caption naming ``caption``'s (scene,
    seed) unless it is None."""
    caught = Caught(caption)
    with observe_figures(caught):
        write()
    assert caught.names, "no figure was written"
    assert not caught.defects, "\n".join(f"{k}: {v}" for k, v in caught.defects.items())
    return caught


def _rows(gazes, *, pccr=True, fail=()):
    rows = []
    for k, (h, v) in enumerate(gazes):
        ok = k not in fail
        rows.append(
            {
                "gaze": [h, v],
                "pupil_error_px": 0.123 * (k + 1) if ok else None,
                "glints_found": 4 if ok else 0,
                "false_glints": 0,
                "pccr_error_deg": (0.456 * (k + 1) if ok else None) if pccr else None,
                "geometric_error_deg": 1.234 * (k + 1) if ok else None,
            }
        )
    return rows


@pytest.mark.parametrize(
    ("gazes", "pccr", "fail"),
    [
        ([(-10.0, 0.0), (10.0, 0.0)], True, ()),  # the smallest evaluation: 2 gazes
        ([(h, v) for v in (-10.0, 0.0, 10.0) for h in (-20.0, -10.0, 0.0, 10.0, 20.0)], True, (7,)),
        ([(h, v) for v in (-10.0, 0.0, 10.0) for h in (-10.0, 0.0, 10.0)], False, ()),
    ],
    ids=["2 gazes", "5 x 3 with a failure", "no PCCR estimate"],
)
def test_error_maps(tmp_path, gazes, pccr, fail):
    meta = {"scene": "paper2005", "seed": 3, "samples_per_pixel": 4, "sensor": [87, 65]}
    rows = _rows(gazes, pccr=pccr, fail=fail)
    _check(lambda: save_error_maps(rows, tmp_path / "e.png", tracking_caption(meta)),
           ("paper2005", 3))  # fmt: skip


def test_sweep_landscape_and_best_pattern(tmp_path):
    heights = np.array([20.0, 40.0])
    distances = np.array([50.0, 70.0])
    pitches = np.array([0.0, 15.0])
    merit = np.array([[[0.3, 0.2], [0.25, np.nan]], [[0.1, 0.4], [0.5, 0.6]]])
    rng = np.random.default_rng(0)
    pattern, target = rng.uniform(1, 2, (30, 40)), np.ones((30, 40))

    def write():
        save_sweep_heatmaps(
            heights, distances, pitches, merit, tmp_path / "landscape.png",
            "generator merit against the δ = 0.3 target", sweep_caption("paper2005"),
        )  # fmt: skip
        save_pattern_vs_target(
            pattern, target, (-20, 20, -15, 15), tmp_path / "best_pattern.png",
            "best of 8: Y 40 mm, Z 50 mm, θ 0° (merit 0.1)", sweep_caption("paper2005"),
        )  # fmt: skip

    assert len(_check(write, ("paper2005", None)).names) == 2


def test_delta_study_figures(tmp_path):
    rng = np.random.default_rng(1)
    deltas = [0.1, 0.5]
    patterns = [rng.uniform(0, 1e-4, (30, 40)) for _ in deltas]
    images = [rng.uniform(0, 1e-5, (30, 40)) for _ in deltas]

    caption = delta_caption({"scene": "paper2005", "seed": 2, "samples_per_pixel": 16})

    def write():
        save_merit_vs_delta(
            deltas, [0.02, 0.015], [0.1, 0.3, 0.5], [3.0, 2.0, 2.5], tmp_path / "m.png",
            caption=caption,
        )  # fmt: skip
        save_delta_gallery(
            deltas, patterns, images, ["Y20 Z50 θ0", "Y40 Z70 θ15"], tmp_path / "deltas.png",
            caption=caption,
        )  # fmt: skip

    assert len(_check(write, ("paper2005", 2)).names) == 2


def test_error_time_plot(tmp_path):
    _check(
        lambda: save_error_time_plot(
            [("forward", [1, 2, 4], [0.02, 0.014, 0.01]), ("fast", [0.5, 1], [0.01, 0.007])],
            tmp_path / "c.png",
            title="relative error of the eye image against wall time",
            targets=[("target", 1.0, 0.01)],
        ),
        None,  # a benchmark's figure: benchmarks/eye_image.py's title names the scene and seed
    )


@pytest.mark.slow
def test_render_figures_of_a_40_by_30_render(tmp_path):
    from eyelume.compile import compile_scene
    from eyelume.render import RenderOptions, render, render_extras
    from eyelume.report.outputs import write_render_outputs
    from eyelume.scene.io import load_scene

    scene = load_scene(
        "paper2005", {"run.estimator": "forward", "sensor.cols": "40", "sensor.rows": "30"}
    )
    result = render(scene, RenderOptions(rays=50_000, seed=1))
    caught = _check(
        lambda: write_render_outputs(
            result, render_extras(compile_scene(scene), result.seed), tmp_path
        ),
        ("paper2005", 1),
    )
    assert sorted(caught.names) == [
        "eye_image_plot.png", "eye_plane_plot.png", "layout.png", "layout_xz.png",
    ]  # fmt: skip


def test_the_checks_find_overlapping_texts_and_a_missing_colour_bar():
    """The checks can fail: two titles on one spot, an image with no colour bar, and one whose
    colour bar names no unit."""
    from eyelume.report.plots import agg_figure

    fig = agg_figure(6, 3, layout=None)
    a, b = fig.subplots(1, 2)
    a.imshow(np.ones((3, 3)))
    fig.colorbar(b.imshow(np.ones((3, 3))), ax=b, label="irradiance")
    fig.text(0.5, 0.5, "first text here")
    fig.text(0.5, 0.5, "second text here")
    fig.canvas.draw()
    assert ("first text here", "second text here") in text_overlaps(fig)
    bad = images_without_unit_colorbar(fig)
    assert len(bad) == 2 and "without a colour bar" in bad[0] + bad[1]
    assert any("names no unit" in d for d in bad)
    assert len(axes_without_unit_label(fig)) == 4  # x and y scales of both panels: no label
    a.set_xlabel("column (px)")
    a.set_ylabel("height")
    assert len(axes_without_unit_label(fig)) == 3  # "height" names no unit
    assert caption_missing(fig, "paper2005", 1) is not None  # no caption at all
    fig.suptitle("scene paper2005, seed 12")
    assert caption_missing(fig, "paper2005", 1) is not None  # seed 12 is not seed 1
    assert caption_missing(fig, "paper2005", None) is not None  # nor says there is none
    assert caption_missing(fig, "paper2005", 12) is None


def test_sweep_outputs_of_a_real_two_point_sweep(tmp_path):
    """``write_sweep_outputs`` as ``eyelume sweep-leds`` calls it, on a 1 × 2 × 1 grid of the
    paper's generator: landscape.png and best_pattern.png pass the checks."""
    from eyelume.analysis.targets import gaussian_target
    from eyelume.optimize.sweep import sweep_leds
    from eyelume.report.optimize_outputs import write_sweep_outputs
    from eyelume.scene.io import load_scene

    scene = load_scene("paper2005")
    goal = gaussian_target(0.3, scene.eye_plane)
    result = sweep_leds(scene, goal, [30.0], [50.0, 70.0], [10.0])
    b = result.best
    refined = (b["height_mm"], b["distance_mm"], b["pitch_deg"], b["merit"])
    plane = scene.eye_plane
    extent = (-plane.width_mm / 2, plane.width_mm / 2, -plane.height_mm / 2, plane.height_mm / 2)
    caught = _check(
        lambda: write_sweep_outputs(
            result, goal, refined, 0.3, extent, tmp_path, sweep_caption(scene.name)
        ),
        (scene.name, None),
    )
    assert sorted(caught.names) == ["best_pattern.png", "landscape.png"]


def test_glint_count_colour_bar_has_integer_ticks_only(tmp_path):
    """The number of glints found is a whole number: its colour bar has one colour per count
    and ticks on integers only (a continuous scale would show 3.25 glints)."""
    from matplotlib.colors import BoundaryNorm

    rows = _rows([(h, v) for v in (-10.0, 0.0, 10.0) for h in (-10.0, 0.0, 10.0)])
    for k, r in enumerate(rows):
        r["glints_found"] = 1 + k % 4  # 1 … 4
    bars = {}

    def keep(fig, name):  # read while the figure is drawn (save_figure clears it)
        fig.canvas.draw()
        for ax in fig.axes:
            for im in ax.images:
                cb = im.colorbar
                labels = [t.get_text() for t in cb.ax.get_yticklabels() if t.get_text()]
                bars[cb.ax.get_ylabel()] = (im.norm, list(cb.get_ticks()), labels)

    with observe_figures(keep):
        save_error_maps(rows, tmp_path / "e.png")
    norm, ticks, labels = bars["glints found and matched (count)"]
    assert isinstance(norm, BoundaryNorm)
    assert ticks == [1, 2, 3, 4] and labels == ["1", "2", "3", "4"]
