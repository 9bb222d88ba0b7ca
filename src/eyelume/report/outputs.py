"""Files a render writes: arrays, pictures, figures, the layout drawing and the summary."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from eyelume.detectors.sensor import camera_summary, digitize
from eyelume.json_files import write_json
from eyelume.report.plots import (
    CMAP_SENSOR,
    SectionCurve,
    save_grey_png,
    save_irradiance_plot,
    save_layout,
)

if TYPE_CHECKING:  # annotations only: report/ never imports what traces rays
    from eyelume.render import RenderExtras, RenderResult

__all__ = ["write_render_outputs"]

#: Colours of the traced rays in the layout by kind (:data:`eyelume.render.RAY_KINDS`),
#: distinct from the LEDs' red (:data:`eyelume.report.plots.CATEGORY_COLORS`), and their
#: legend entries.
RAY_COLORS = {"sensor": "tab:pink", "sensor, off the section": "tab:olive", "other": "tab:orange"}
RAY_LABELS = {
    "sensor": "ray to the sensor",
    "sensor, off the section": "ray to the sensor, born off\nthe section (projected)",
    "other": "other ray",
}


def _led_id(name: str) -> str:
    """An LED axis's id, as ``truth.json`` numbers the LEDs ("LED 2 axis" → "2"), else ""."""
    parts = name.split()
    return parts[1] if len(parts) == 3 and parts[0] == "LED" and parts[2] == "axis" else ""


def write_render_outputs(result: RenderResult, extras: RenderExtras, out: str | Path) -> list[Path]:
    """Write every output of ``eyelume render`` into folder ``out``; returns the paths written.

    ``extras`` (:func:`eyelume.render.render_extras`) holds the layout section, the traced ray
    paths and the truth, computed by the caller: report/ traces no ray.

    ``eye_image.npy``/``eye_plane.npy`` (W/mm², float64), ``eye_image_std.npy`` (each pixel's
    estimated standard error, W/mm²), their grey PNGs (glints saturate at the
    99.5th percentile), ``eye_image_digital.npy`` (the camera's reading in DN, uint16, from
    :func:`eyelume.detectors.sensor.digitize` with the render's seed) and
    ``eye_image_digital.png`` (0 DN
    black … full scale white, no autoscaling; the camera's picture, each pixel drawn as a block
    of 8 × 8 or so, the factor in its PNG comment) and its labelled enlargement
    ``eye_image_digital_plot.png`` (DN colour bar, mm and sensor-px axes), colour-bar figures
    ``*_plot.png`` in physical units (grey for the pictures on the sensor, inferno for the eye
    plane: :mod:`eyelume.report.plots`), ``layout.png`` and ``layout_xz.png`` (the y–z and
    x–z sections, each with a few dozen rays traced from near its plane) and ``summary.json``
    (run facts, power ledger and, under ``"camera"``, the sensor settings and saturated pixels) and
    ``truth.json`` (the true gaze, apparent pupil and glint positions on the picture:
    :func:`eyelume.analysis.truth.eye_truth`). With ``ambient.sun``: ``ambient_image.npy``,
    ``ambient_image_std.npy`` and ``ambient_image.png`` (the sunlight's picture, W/mm² at the
    scene's wavelength), the digital picture counting LEDs and sunlight, and the signal to
    ambient under ``"ambient"`` in summary.json and truth.json.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []

    def path(name: str) -> Path:
        p = out / name
        written.append(p)
        return p

    np.save(path("eye_image.npy"), result.eye_image)
    np.save(path("eye_image_std.npy"), np.sqrt(result.eye_image_variance))
    np.save(path("eye_plane.npy"), result.eye_plane)
    # a cut first round's missing pixels (NaN in the .npy files) are drawn black
    missing = ~np.isfinite(result.eye_image)
    shown = np.where(missing, 0.0, result.eye_image)
    save_grey_png(shown, path("eye_image.png"))
    save_grey_png(result.eye_plane, path("eye_plane.png"), clip_percentile=100.0)
    sc = result.scene
    # LEDs of several wavelengths: the photo-electrons are the wavelength groups' sum
    counted = (
        shown
        if result.groups is None and result.ambient is None
        else np.where(missing, 0.0, result.eye_image_at_scene_wavelength)
    )
    if result.ambient is not None:  # the sunlight's picture apart (counted in the digital one)
        np.save(path("ambient_image.npy"), result.ambient.eye_image)
        np.save(path("ambient_image_std.npy"), np.sqrt(result.ambient.eye_image_variance))
        save_grey_png(result.ambient.eye_image, path("ambient_image.png"))
    digital = digitize(counted, sc.sensor, sc.wavelength_nm, result.seed)
    digital.counts[missing] = 0
    # the run's numbers first: a figure that fails below cannot lose them
    summary = result.summary()
    # the estimate's standard error of the counted picture: the rendered picture's relative
    # one (the same picture but for the wavelength groups' weights; sunlight's own noise left
    # out, which can only make a pixel look saturated beyond noise sooner)
    std = np.sqrt(result.eye_image_variance)
    with np.errstate(divide="ignore", invalid="ignore"):
        relative = np.where(shown > 0, std / shown, 0.0)
    summary["camera"] = camera_summary(
        sc.sensor, sc.wavelength_nm, digital, estimate_std_w_mm2=counted * relative
    )
    write_json(path("summary.json"), summary)
    truth = extras.truth
    if "ambient" in summary:  # where the sun's brightest pixel is, and the ratios
        truth = {**truth, "ambient": summary["ambient"]}
    write_json(path("truth.json"), truth)
    np.save(path("eye_image_digital.npy"), digital.counts)
    save_grey_png(digital.counts, path("eye_image_digital.png"), white=digital.full_scale_dn)
    name = sc.name
    budget = (
        f"fast estimator, {result.samples_per_pixel} samples per pixel"
        if result.estimator == "fast" and result.samples_per_pixel
        else f"{result.estimator} estimator, {result.rays:,} rays"
    )
    save_irradiance_plot(
        shown,
        path("eye_image_plot.png"),
        extent_mm=result.picture_extent_mm,
        title=f"{name}: eye image on the sensor (glints clipped at 99.5 %)\n"
        f"{budget}, seed {result.seed}",
        label="image-plane irradiance (W/mm²)",
        xlabel="image x on the sensor (mm, picture upright)",
        ylabel="image y on the sensor (mm)",
        clip_percentile=99.5,
        pixel_axes=True,
        cmap=CMAP_SENSOR,
    )
    # the camera's picture at its own size is eye_image_digital.png; this is its labelled
    # enlargement: the same numbers on the camera's own scale (0 DN black, full scale white)
    save_irradiance_plot(
        digital.counts,
        path("eye_image_digital_plot.png"),
        extent_mm=result.picture_extent_mm,
        title=f"{name}: the camera's digital picture (eye_image_digital.png enlarged), "
        f"{sc.sensor.exposure_ms:g} ms exposure, 0 DN black, full scale "
        f"{digital.full_scale_dn:g} DN white\n{budget}, seed {result.seed}",
        label="camera signal (DN)",
        xlabel="image x on the sensor (mm, picture upright)",
        ylabel="image y on the sensor (mm)",
        pixel_axes=True,
        cmap=CMAP_SENSOR,
        vmax=float(digital.full_scale_dn),
    )
    save_irradiance_plot(
        result.eye_plane,
        path("eye_plane_plot.png"),
        extent_mm=result.plane_extent_mm,
        title=f"{name}: eye-plane irradiance toward the eye\n{budget}, seed {result.seed}",
        label="eye-plane irradiance (W/mm²)",
        xlabel="eye plane x (mm)",
        ylabel="eye plane y (mm)",
    )
    for view, file, vertical in (("yz", "layout.png", "y"), ("xz", "layout_xz.png", "x")):
        curves = [
            SectionCurve(s.name, s.category, s.z, s.y, tag=_led_id(s.name))
            for s in extras.sections[view]
        ]
        rays = extras.ray_paths[view]
        count = {k: sum(kind == k for _, kind in rays) for k in RAY_COLORS}
        save_layout(
            curves,
            [p for p, _ in rays],
            path(file),
            title=f"{name}: {vertical}–z section (world; camera projected); rays of seed "
            f"{result.seed} born ≤ 1 mm from the section unless marked",
            ray_colors=[RAY_COLORS[kind] for _, kind in rays],
            vertical=vertical,
            ray_legend=[
                (RAY_COLORS[k], f"{RAY_LABELS[k]} ({count[k]})") for k in RAY_COLORS if count[k]
            ],  # fmt: skip
            led_bodies=sc.leds.body_shapes(),
        )
    return written
