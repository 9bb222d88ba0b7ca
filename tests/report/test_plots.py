"""Tests for eyelume.report.plots: read every PNG back and check what a person would see."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from eyelume.report.plots import (
    SectionCurve,
    save_grey_png,
    save_irradiance_plot,
    save_layout,
)


def _read(path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im)


# --------------------------------------------------------------------------------------------------
# save_grey_png
# --------------------------------------------------------------------------------------------------


def test_grey_png_size_is_integer_upscaled(tmp_path):
    path = tmp_path / "eye.png"
    save_grey_png(np.ones((65, 87)), path)  # 87 wide: factor ceil(640 / 87) = 8
    with Image.open(path) as im:
        assert im.mode == "L"
        assert im.size == (87 * 8, 65 * 8)


def test_grey_png_no_upscale_when_wide_enough(tmp_path):
    path = tmp_path / "wide.png"
    save_grey_png(np.ones((3, 700)), path)
    assert _read(path).shape == (3, 700)


def test_grey_png_levels_are_linear_to_clip(tmp_path):
    # Clip at the maximum (percentile 100) so the expected levels are exact.
    arr = np.array([[0.0, 0.5, 1.0, 2.0, 0.25]])
    path = tmp_path / "levels.png"
    save_grey_png(arr, path, clip_percentile=100.0, min_width_px=1)
    grey = _read(path)
    assert grey.dtype == np.uint8
    assert grey[0, 0] == 0
    assert grey[0, 1] in (63, 64)  # 0.25 of the clip value
    assert grey[0, 2] in (127, 128)  # half the clip value
    assert grey[0, 3] == 255
    assert grey[0, 4] in (31, 32)


def test_grey_png_glint_saturates_and_face_stays_visible(tmp_path):
    # A dim face of 1000 pixels at 1.0 and a glint 1000 times brighter: with the default 99.5th
    # percentile clip the face is white-ish, not black, and the glint saturates.
    arr = np.ones((25, 40))
    arr[0, 0] = 1000.0
    arr[10, 10:20] = 0.5
    path = tmp_path / "glint.png"
    save_grey_png(arr, path, min_width_px=1)
    grey = _read(path)
    assert grey[0, 0] == 255
    assert grey[5, 5] == 255  # the face is at the clip value
    assert grey[10, 15] in (127, 128)


def test_grey_png_negative_values_are_black(tmp_path):
    arr = np.array([[-3.0, 1.0]])
    path = tmp_path / "neg.png"
    save_grey_png(arr, path, clip_percentile=100.0, min_width_px=1)
    assert _read(path).tolist() == [[0, 255]]


def test_grey_png_orientation_row0_col0_is_top_left(tmp_path):
    arr = np.zeros((4, 6))
    arr[0, 0] = 1.0
    path = tmp_path / "orient.png"
    save_grey_png(arr, path, clip_percentile=100.0, min_width_px=60)  # factor 10
    grey = _read(path)
    assert grey.shape == (40, 60)
    assert np.all(grey[:10, :10] == 255)
    assert np.all(grey[10:, :] == 0)
    assert np.all(grey[:, 10:] == 0)


def test_grey_png_all_zero_is_black(tmp_path):
    path = tmp_path / "zero.png"
    save_grey_png(np.zeros((15, 21)), path)
    grey = _read(path)
    assert grey.shape[1] >= 640
    assert grey.max() == 0


def test_grey_png_empty_is_black(tmp_path):
    path = tmp_path / "empty.png"
    save_grey_png(np.zeros((0, 5)), path, min_width_px=8)
    grey = _read(path)
    assert grey.shape == (8, 8)
    assert grey.max() == 0


def test_grey_png_nan_raises_with_count(tmp_path):
    arr = np.ones((4, 4))
    arr[1, 1] = np.nan
    arr[2, 2] = np.inf
    arr[3, 3] = np.nan
    with pytest.raises(ValueError, match="3 non-finite"):
        save_grey_png(arr, tmp_path / "nan.png")
    assert not (tmp_path / "nan.png").exists()


@pytest.mark.parametrize(
    ("arr", "kwargs"),
    [
        (np.ones(5), {}),
        (np.ones((2, 2)), {"clip_percentile": 0.0}),
        (np.ones((2, 2)), {"clip_percentile": 101.0}),
        (np.ones((2, 2)), {"min_width_px": 0}),
    ],
)
def test_grey_png_bad_input_raises(tmp_path, arr, kwargs):
    with pytest.raises(ValueError):
        save_grey_png(arr, tmp_path / "bad.png", **kwargs)


def test_grey_png_creates_parent_directory(tmp_path):
    path = tmp_path / "a" / "b" / "eye.png"
    save_grey_png(np.ones((2, 2)), path)
    assert path.is_file()


# --------------------------------------------------------------------------------------------------
# save_irradiance_plot
# --------------------------------------------------------------------------------------------------


def _gaussian_spot(rows: int = 30, cols: int = 40) -> np.ndarray:
    yy, xx = np.mgrid[0:rows, 0:cols]
    return 1e-3 * np.exp(-((xx - cols / 2) ** 2 + (yy - rows / 2) ** 2) / 50.0)


_INFERNO_TOP = np.array([252, 255, 164])  # inferno's colour at the top of the scale


def _image_area_top_colour(path) -> np.ndarray:
    """Mask of pixels of inferno's top colour left of the colour bar (the left 70 %)."""
    rgb = _read(path)[..., :3].astype(int)
    mask = np.abs(rgb - _INFERNO_TOP).sum(axis=-1) < 30
    mask[:, int(0.7 * rgb.shape[1]) :] = False
    return mask


def test_irradiance_plot_writes_figure_with_content(tmp_path):
    path = tmp_path / "irr.png"
    save_irradiance_plot(
        _gaussian_spot(), path, extent_mm=(-20.0, 20.0, -15.0, 15.0), title="Eye plane"
    )
    img = _read(path)
    # 7 x 5 in at 150 dpi, tight bbox: several hundred pixels each way.
    assert img.shape[0] > 300 and img.shape[1] > 400
    assert img[..., :3].astype(int).std() > 10  # not a uniform image
    assert _image_area_top_colour(path).sum() > 10  # the spot's peak is drawn in the image area


def test_irradiance_plot_clip_percentile_changes_picture(tmp_path):
    arr = _gaussian_spot()
    arr[0, 0] = 1.0  # a glint 1000 times the spot
    a, b = tmp_path / "noclip.png", tmp_path / "clip.png"
    extent = (-20.0, 20.0, -15.0, 15.0)
    save_irradiance_plot(arr, a, extent_mm=extent, title="t")
    save_irradiance_plot(arr, b, extent_mm=extent, title="t", clip_percentile=99.0)
    # Unclipped, only the glint reaches the top colour; clipped, the spot's core does too.
    n_a = _image_area_top_colour(a).sum()
    n_b = _image_area_top_colour(b).sum()
    assert n_b > n_a + 100


def test_irradiance_plot_orientation_row0_at_top(tmp_path):
    arr = np.zeros((10, 10))
    arr[0, :] = 1.0  # row 0 bright: must be drawn at the top of the axes
    path = tmp_path / "orient.png"
    save_irradiance_plot(arr, path, extent_mm=(0.0, 10.0, 0.0, 10.0), title="")
    rgb = _read(path)[..., :3].astype(int)
    left = rgb[:, : int(0.7 * rgb.shape[1])]
    dark_rows = np.nonzero(((left.sum(axis=-1) < 40).sum(axis=1)) > 50)[0]  # rows 1..9: black
    bright_rows = np.nonzero(_image_area_top_colour(path).any(axis=1))[0]
    assert bright_rows.size > 0 and dark_rows.size > 0
    assert bright_rows.max() < dark_rows.min() + 3
    image_height = dark_rows.max() - bright_rows.min()
    assert bright_rows.max() - bright_rows.min() < 0.2 * image_height


@pytest.mark.parametrize(
    ("arr", "extent"),
    [
        (np.full((3, 3), np.nan), (0.0, 1.0, 0.0, 1.0)),
        (np.ones(3), (0.0, 1.0, 0.0, 1.0)),
        (np.ones((0, 3)), (0.0, 1.0, 0.0, 1.0)),
        (np.ones((3, 3)), (0.0, 0.0, 0.0, 1.0)),
        (np.ones((3, 3)), (0.0, 1.0, 0.0)),
        (np.ones((3, 3)), (0.0, 1.0, 0.0, np.inf)),
    ],
)
def test_irradiance_plot_bad_input_raises(tmp_path, arr, extent):
    with pytest.raises(ValueError):
        save_irradiance_plot(arr, tmp_path / "bad.png", extent_mm=extent, title="t")


def test_irradiance_plot_all_zero_works(tmp_path):
    path = tmp_path / "zero.png"
    save_irradiance_plot(np.zeros((5, 5)), path, extent_mm=(0, 1, 0, 1), title="zero")
    assert path.stat().st_size > 1000


# --------------------------------------------------------------------------------------------------
# save_layout
# --------------------------------------------------------------------------------------------------


def _system() -> tuple[list[SectionCurve], list[np.ndarray]]:
    t = np.linspace(-1.0, 1.0, 41)
    cornea = SectionCurve("anterior cornea", "eye", -((t * 6) ** 2) / (2 * 7.8), t * 6)
    lens = SectionCurve("lens S1", "lens", 100.0 - (t * 12) ** 2 / 80.0, t * 12)
    stop = SectionCurve("stop", "stop", np.array([150.0, 150.0]), np.array([5.0, 15.0]))
    sensor = SectionCurve("sensor", "sensor", np.array([450.0, 450.0]), np.array([-3.0, 3.0]))
    led = SectionCurve(
        "LED 1 body",
        "led",
        np.array([60.0, 62.0, 62.0, 60.0, 60.0]),
        np.array([30.0, 30.0, 33.0, 33.0, 30.0]),
    )
    rays = []
    for y_eye in np.linspace(-4.0, 4.0, 9):
        rays.append(
            np.array(
                [[0.0, 31.5, 61.0], [0.0, y_eye, 0.0], [0.0, y_eye * 0.5, 100.0], [0.0, 0.0, 450.0]]
            )
        )
    return [cornea, lens, stop, sensor, led], rays


def test_layout_writes_wide_figure_with_content(tmp_path):
    curves, rays = _system()
    path = tmp_path / "layout.png"
    save_layout(curves, rays, path, title="Paper 2005 system")
    img = _read(path)
    h, w = img.shape[:2]
    assert w > 1500 and h > 400  # 16 x 5 in at 150 dpi
    assert w > 2 * h
    rgb = img[..., :3].astype(int)
    assert rgb.std() > 5
    # Category colours are drawn: tab:blue (31, 119, 180) for the eye, tab:green for the lens.
    for colour in [(31, 119, 180), (44, 160, 44), (148, 103, 189)]:
        close = np.abs(rgb - np.array(colour)).sum(axis=-1) < 30
        assert close.sum() > 20, colour


def test_layout_ray_colors(tmp_path):
    curves, rays = _system()
    path = tmp_path / "layout_colors.png"
    save_layout(curves, rays, path, title="t", ray_colors=["tab:cyan"] * len(rays))
    rgb = _read(path)[..., :3].astype(int)
    # Semi-transparent cyan (23, 190, 207) over white: blue channel high, red clearly lower.
    cyanish = (rgb[..., 2] > 200) & (rgb[..., 0] < 200) & (rgb[..., 1] > rgb[..., 0] + 20)
    assert cyanish.sum() > 50
    with pytest.raises(ValueError, match="ray_colors"):
        save_layout(curves, rays, tmp_path / "x.png", title="t", ray_colors=["red"])


def test_layout_no_rays_and_no_curves(tmp_path):
    path = tmp_path / "empty.png"
    save_layout([], [], path, title="empty")
    assert path.stat().st_size > 1000


def test_section_curve_mismatched_lengths_raise_naming_curve():
    with pytest.raises(ValueError, match="lens S3"):
        SectionCurve("lens S3", "lens", np.zeros(5), np.zeros(4))


def test_section_curve_nan_raises_naming_curve():
    with pytest.raises(ValueError, match="posterior cornea"):
        SectionCurve("posterior cornea", "eye", np.array([0.0, np.nan]), np.zeros(2))


def test_section_curve_unknown_category_raises():
    with pytest.raises(ValueError, match="housing"):  # "camera" is a category now
        SectionCurve("strap", "housing", np.zeros(2), np.zeros(2))


def test_section_curve_arrays_are_read_only_copies():
    z = np.array([1.0, 2.0])
    curve = SectionCurve("sensor", "sensor", z, np.zeros(2))
    z[0] = 99.0
    assert curve.z[0] == 1.0
    with pytest.raises(ValueError):
        curve.z[0] = 5.0


@pytest.mark.parametrize(
    "ray",
    [
        np.zeros((3, 2)),
        np.zeros(3),
        np.array([[0.0, 0.0, 0.0], [0.0, np.nan, 10.0]]),
        np.array([[0.0, 0.0, 0.0], [0.0, 0.0, np.inf]]),
    ],
)
def test_layout_bad_ray_raises_naming_index(tmp_path, ray):
    curves, rays = _system()
    with pytest.raises(ValueError, match="ray 9"):
        save_layout(curves, [*rays, ray], tmp_path / "bad.png", title="t")


def test_grey_png_says_its_enlargement(tmp_path):
    path = tmp_path / "eye.png"
    save_grey_png(np.ones((65, 87)), path)
    with Image.open(path) as im:
        assert im.size == (87 * 8, 65 * 8)
        assert "87 x 65 array, each element drawn as a 8 x 8 pixel block" in im.info["Comment"]


def test_irradiance_plot_pixel_axes_count_the_array(tmp_path):
    from eyelume.report.plots import observe_figures

    seen = []

    def grab(fig, name):
        ax = fig.axes[0]
        sec = [c for c in ax.child_axes if type(c).__name__ == "SecondaryAxis"]
        seen.append({c.get_xlabel() or c.get_ylabel() for c in sec})

    with observe_figures(grab):
        save_irradiance_plot(
            np.ones((30, 40)), tmp_path / "p.png", extent_mm=(-2, 2, -1.5, 1.5), title="t",
            pixel_axes=True,
        )  # fmt: skip
    assert seen == [{"column (sensor px of 40)", "row (sensor px of 30)"}]


def test_a_long_scene_name_wraps_instead_of_widening_the_eye_image_plot(tmp_path):
    """The title (scene name, budget, seed) wraps to the figure's width: a 90-character scene
    name leaves the PNG as wide as a short one's."""
    widths = []
    for name in ("s", "a-very-long-scene-file-name-that-someone-gave-their-headset-" * 2):
        path = tmp_path / f"{len(name)}.png"
        save_irradiance_plot(
            np.ones((30, 40)), path, extent_mm=(-2, 2, -1.5, 1.5), pixel_axes=True,
            title=f"{name}: eye image on the sensor (glints clipped at 99.5 %)\nseed 1",
        )  # fmt: skip
        widths.append(_read(path).shape[1])
    assert widths[1] <= widths[0] + 5, widths


def test_a_narrow_layout_is_drawn_on_limits_near_its_content(tmp_path):
    """A system taller than long (vr-offaxis: z −25 … 55 mm across ±60 mm) is drawn at equal
    scale on axis limits near its content, not on a z range widened to fill the axes (it was
    drawn on z −90 … 125 mm, in a third of each axis)."""
    from eyelume.report.plots import observe_figures

    skin = SectionCurve("skin", "tissue", np.array([-5.0, -5.0]), np.array([-60.0, 60.0]))
    lens = SectionCurve("lens", "lens", np.array([20.0, 25.0]), np.array([20.0, 25.0]))
    ray = np.array([[0.0, 0.0, -25.0], [0.0, 10.0, 55.0]])
    seen = {}

    def keep(fig, _name):
        ax = fig.axes[0]
        seen["x"], seen["y"] = ax.get_xlim(), ax.get_ylim()

    with observe_figures(keep):
        save_layout([skin, lens], [ray], tmp_path / "l.png", title="narrow")
    assert seen["x"][1] - seen["x"][0] < 1.2 * 80  # content spans 80 mm in z
    assert seen["y"][1] - seen["y"][0] < 1.2 * 120
