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
    colormaps_off_rule,
    exponent_texts,
    images_without_unit_colorbar,
    text_overlaps,
)
from matplotlib.text import Text

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
        found += exponent_texts(fig)
        found += colormaps_off_rule(fig)
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


def _rows(gazes, *, pccr=True, fail=(), cal=()):
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
                "calibration": (h, v) in cal,
                "geometric_calibration": (h, v) in cal and (h, v) == (0.0, 0.0),
            }
        )
        if (h, v) in cal and pccr:
            rows[-1]["pccr_error_deg"] = 1.2e-14  # the fit's residual on its own picture
        if rows[-1]["geometric_calibration"]:
            rows[-1]["geometric_error_deg"] = 0.0  # the kappa offset was taken on this picture
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
    rows = _rows(gazes, pccr=pccr, fail=fail, cal={(-20.0, 0.0), (0.0, 0.0), (20.0, 0.0)})
    _check(lambda: save_error_maps(rows, tmp_path / "e.png", tracking_caption(meta)),
           ("paper2005", 3))  # fmt: skip


def test_error_maps_mark_calibration_gazes_and_leave_them_out_of_the_mean(tmp_path):
    """A test gaze that is a calibration gaze (the PCCR polynomial fitted on that very picture:
    its value is an in-sample residual, here a near-zero one) is drawn hatched and marked "cal"
    in the PCCR panel, with a legend entry, and is neither a number in its cell nor part of the
    panel's colour scale or mean; in the geometric panel only the model's one-point kappa frame
    (0°, 0°), error exactly 0, is hatched and left out."""
    gazes = [(h, v) for v in (-10.0, 0.0, 10.0) for h in (-20.0, 0.0, 20.0)]
    cal = {(-20.0, 0.0), (0.0, 0.0), (20.0, 0.0)}
    rows = _rows(gazes, cal=cal)
    seen = {}

    def keep(fig, name):
        fig.canvas.draw()
        for ax in fig.axes:
            texts = [t.get_text() for t in ax.texts]
            norm = ax.images[0].norm if ax.images else None
            seen[ax.get_title().split("\n")[0]] = (ax.get_title(), texts, norm, len(ax.patches))
        seen["legend"] = [t.get_text() for lg in fig.legends for t in lg.get_texts()]

    with observe_figures(keep):
        save_error_maps(rows, tmp_path / "e.png", "scene paper2005, seed 0")
    title, texts, norm, patches = seen["PCCR gaze error (°)"]
    assert texts.count("cal") == 3 and patches == 3
    assert not any("e-14" in t or t == "1.2e-14" for t in texts)
    measured = [r["pccr_error_deg"] for r in rows if not r["calibration"]]
    assert norm.vmin == pytest.approx(min(measured))  # the residual is not on the scale
    assert f"mean {np.mean(measured):.2f}° over 6 gazes, 3 calibration gazes left out" in title
    g_title, g_texts, g_norm, g_patches = seen["geometric gaze error (°)"]
    assert g_texts.count("cal") == 1 and g_patches == 1 and "0" not in g_texts
    g_measured = [r["geometric_error_deg"] for r in rows if not r["geometric_calibration"]]
    assert g_norm.vmin == pytest.approx(min(g_measured)) and min(g_measured) > 0  # 0 not on it
    assert f"mean {np.mean(g_measured):.2f}° over 8 gazes, 1 calibration gaze left out" in g_title
    assert any(t.startswith("cal: a calibration gaze") for t in seen["legend"])


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
            caption=caption, plane_mm=(40.0, 30.0), picture_mm=(46.0, 34.3),
        )  # fmt: skip

    assert len(_check(write, ("paper2005", 2)).names) == 2


def test_delta_gallery_draws_the_eye_plane_in_mm_and_the_eye_image_on_the_sensor(tmp_path):
    """deltas.png: the eye-plane row spans the receiver's ±20 × ±15 mm (not its 21 × 15 bins),
    the eye-image row the picture's ±23 × ±17.15 mm on the sensor with the pixel size said; the
    eye plane in inferno, the eye image grey as the camera shows it."""
    rng = np.random.default_rng(1)
    patterns = [rng.uniform(0, 1e-4, (15, 21)) for _ in range(2)]
    images = [rng.uniform(0, 1e-8, (65, 87)) for _ in range(2)]
    seen = {}

    ylabels = []

    def keep(fig, name):
        ylabels.extend(ax.get_ylabel() for ax in fig.axes)
        for ax in fig.axes:
            if ax.images:
                seen.setdefault(ax.get_xlabel(), []).append(
                    (tuple(ax.images[0].get_extent()), ax.images[0].cmap.name)
                )

    with observe_figures(keep):
        save_delta_gallery([0.1, 0.5], patterns, images, ["a", "b"], tmp_path / "d.png",
                           plane_mm=(40.0, 30.0), picture_mm=(46.0, 34.3))  # fmt: skip
    plane = seen.pop("eye plane x (mm)")
    assert [e for e, _ in plane] == [(-20.0, 20.0, -15.0, 15.0)] * 2
    assert {c for _, c in plane} == {"inferno"}
    ((label, picture),) = seen.items()
    assert label == "image x on the sensor (mm)"
    assert [y for y in ylabels if y.startswith("eye image")] == [
        "eye image, 1 px = 0.529 mm\ny on the sensor (mm)"
    ]
    assert [e for e, _ in picture] == [pytest.approx((-23.0, 23.0, -17.15, 17.15))] * 2
    assert {c for _, c in picture} == {"gray"}


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
        "eye_image_digital_plot.png", "eye_image_plot.png", "eye_plane_plot.png", "layout.png",
        "layout_xz.png",
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


def test_the_checks_find_offset_texts_exponents_and_colour_maps_off_the_rule():
    """An irradiance map in W/mm² drawn as is (values ~1e-6): its colour bar shows an offset
    or e-notation; a sensor picture in inferno and an eye-plane map in grey break the rule;
    scaled to µW/mm² in the rule's maps, the same figure passes."""
    from eyelume.report.plots import agg_figure, si_scale

    data = 1e-6 * (1.0 + np.arange(12.0).reshape(3, 4) / 1000.0)
    fig = agg_figure(8, 3)
    a, b = fig.subplots(1, 2)
    fig.colorbar(a.imshow(data, cmap="inferno"), ax=a, label="image-plane irradiance (W/mm²)")
    fig.colorbar(b.imshow(data * 2, cmap="gray"), ax=b, label="eye-plane irradiance (W/mm²)")
    assert exponent_texts(fig), "an offset or exponent went unnoticed"
    bad = colormaps_off_rule(fig)
    assert len(bad) == 2 and "picture on the sensor" in bad[0] + bad[1]

    factor, label = si_scale("image-plane irradiance (W/mm²)", float(data.max()))
    assert label == "image-plane irradiance (µW/mm²)"
    fig = agg_figure(8, 3)
    a, b = fig.subplots(1, 2)
    fig.colorbar(a.imshow(data / factor, cmap="gray"), ax=a, label=label)
    fig.colorbar(b.imshow(2 * data / factor, cmap="inferno"), ax=b,
                 label=label.replace("image-plane", "eye-plane"))  # fmt: skip
    assert exponent_texts(fig) == [] and colormaps_off_rule(fig) == []


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


def _tiny_render(name: str):
    from eyelume.compile import compile_scene
    from eyelume.render import RenderOptions, render, render_extras
    from eyelume.scene.io import load_scene

    scene = load_scene(
        "paper2005",
        {"run.estimator": "forward", "sensor.cols": "24", "sensor.rows": "18", "name": name},
    )
    result = render(scene, RenderOptions(rays=5_000, seed=1))
    return result, render_extras(compile_scene(scene), result.seed)


def test_a_scene_name_with_dollars_and_backslashes_is_shown_literally(tmp_path):
    """User text is not matplotlib mathtext: a name with ``$…$`` pairs and a backslash command
    (``$\\badcmd$`` made matplotlib raise ParseFatalException after the render, so nothing was
    written) reaches every render figure's title as typed, and every file is written."""
    from eyelume.report.outputs import write_render_outputs

    name = "Rig A: $1.5k vs $2k budget, rig $\\badcmd$"
    result, extras = _tiny_render(name)
    titles = []

    def keep(fig, _name):
        fig.canvas.draw()  # mathtext would raise (or garble) here
        titles.extend(t.get_text() for t in fig.findobj(Text) if name in t.get_text())
        rendered = [t for t in fig.findobj(Text) if name in t.get_text()]
        assert rendered and all(not t.get_parse_math() for t in rendered)

    with observe_figures(keep):
        written = write_render_outputs(result, extras, tmp_path)
    assert len(titles) >= 5
    for f in ("summary.json", "truth.json", "layout.png", "eye_image_plot.png"):
        assert (tmp_path / f).is_file() and tmp_path / f in written


def test_a_failing_figure_loses_no_json_result(tmp_path, monkeypatch):
    """summary.json and truth.json are written before any figure: a figure that fails cannot
    lose the run's numbers."""
    import eyelume.report.outputs as outputs

    result, extras = _tiny_render("paper2005")

    def broken(*_a, **_k):
        raise RuntimeError("figure failed")

    monkeypatch.setattr(outputs, "save_irradiance_plot", broken)
    with pytest.raises(RuntimeError, match="figure failed"):
        outputs.write_render_outputs(result, extras, tmp_path)
    assert (tmp_path / "summary.json").is_file() and (tmp_path / "truth.json").is_file()


def test_error_map_cells_write_degrees_with_one_decimal(tmp_path):
    """A gaze error of 1.96° is written "2.0" (two significant figures wrote "2", read as a
    count), glint counts whole, pupil errors in px to two figures."""
    rows = _rows([(-10.0, 0.0), (10.0, 0.0)], pccr=False)
    rows[0]["geometric_error_deg"], rows[1]["geometric_error_deg"] = 1.96, 12.34
    seen = {}

    def keep(fig, name):
        for ax in fig.axes:
            seen[ax.get_title().split("\n")[0]] = [t.get_text() for t in ax.texts]

    with observe_figures(keep):
        save_error_maps(rows, tmp_path / "e.png", "scene paper2005, seed 0")
    assert seen["geometric gaze error (°)"] == ["2.0", "12.3"]
    assert seen["glints found and matched (count)"] == ["4", "4"]
    assert seen["pupil-centre error (px)"] == ["0.12", "0.25"]


def test_the_render_layouts_legend_names_the_scenes_led_bodies(tmp_path):
    """paper2005's LEDs made flat cylinders: both layouts' legends call them cylinders (their
    section a rectangle), not the sphere's circle."""
    from eyelume.compile import compile_scene
    from eyelume.render import RenderOptions, render, render_extras
    from eyelume.report.outputs import write_render_outputs
    from eyelume.scene.io import load_scene

    scene = load_scene(
        "paper2005",
        {
            "run.estimator": "forward",
            "sensor.cols": "24",
            "sensor.rows": "18",
            "leds.body_shape": "cylinder",
            "leds.body_length_mm": "2.0",
        },
    )
    result = render(scene, RenderOptions(rays=5_000, seed=1))
    legends = {}

    def keep(fig, name):
        legend = fig.axes[0].get_legend()
        if name.startswith("layout") and legend is not None:
            legends[name] = [t.get_text() for t in legend.texts if t.get_text().startswith("LED")]

    with observe_figures(keep):
        write_render_outputs(result, render_extras(compile_scene(scene), result.seed), tmp_path)
    assert legends == {
        "layout.png": ["LED: cylinder body ▭, axis —, its id"],
        "layout_xz.png": ["LED: cylinder body ▭, axis —, its id"],
    }
