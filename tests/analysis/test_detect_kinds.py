"""The kinds of eye picture issue 13 found the histogram front end failing on, made up here.

:func:`closeup` draws a near-eye infrared close-up like the real ones (160 × 160, 8-bit): skin,
an iris disc, an elliptical pupil, a Gaussian optical blur and Gaussian pixel noise, drawn at
4× and averaged down so edges are anti-aliased and the truth is the drawn geometry. Each test
changes one thing and asserts the right answer (the pupil within a tolerance derived from the
picture's noise) or the refusal that names the cause.

Tolerance: an edge step ΔI blurred by σ_b has slope ≈ ΔI · 0.8 / (√(2π) σ_b) where the detector
reads it (¼ of the way up); with pixel noise σ_n each edge point is off by σ_e ≈ σ_n / slope
and the centre of N points by σ_e √(2/N). For the default picture (ΔI = 60, σ_b = 1.2, σ_n =
2, N ≈ 120) that is σ_e ≈ 0.13 px and ≈ 0.02 px on the centre; the darkest case here (ΔI = 18)
gives ≈ 0.06 px. The 0.25 px asserted is > 4 σ of the worst case, and far below the 5 px by
which the iris or a border taken for the pupil would miss.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from eyelume.analysis.tracking import detect

SIZE = 160
CENTRE = (80.4, 78.7)


DEFAULTS = {
    "skin": 150.0,
    "iris": 70.0,
    "pupil": 10.0,
    "pupil_axes": (36.0, 33.0),
    "angle": 25.0,
    "centre": CENTRE,
    "iris_radius": 45.0,
    "glints": (),
    "glint_sigma": 2.0,
    "glint_peak": 800.0,
    "blur": 1.2,
    "noise": 2.0,
    "seed": 0,
}


def closeup(**kw) -> np.ndarray:
    """A float close-up (grey levels of an 8-bit camera before clipping and rounding); keyword
    arguments change :data:`DEFAULTS` (levels, pupil full axes px and angle °, glints (x, y)
    with σ and peak, blur σ px, noise σ, seed)."""
    unknown = set(kw) - set(DEFAULTS)
    assert not unknown, unknown
    p = {**DEFAULTS, **kw}
    skin, iris, pupil, centre = p["skin"], p["iris"], p["pupil"], p["centre"]
    pupil_axes, angle, blur, noise = p["pupil_axes"], p["angle"], p["blur"], p["noise"]
    glint_sigma, glint_peak = p["glint_sigma"], p["glint_peak"]
    s, shift = 4, 8
    canvas = np.full((SIZE * s, SIZE * s), skin, np.float32)

    def fine(v):
        return int(round((s * v + (s - 1) / 2) * 2**shift))

    def size(v):
        return int(round(s * v * 2**shift))

    c = (fine(centre[0]), fine(centre[1]))
    cv2.circle(canvas, c, size(p["iris_radius"]), iris, -1, cv2.LINE_8, shift)
    axes = (size(pupil_axes[0] / 2), size(pupil_axes[1] / 2))
    cv2.ellipse(canvas, c, axes, angle, 0, 360, pupil, -1, cv2.LINE_8, shift)
    img = cv2.resize(canvas, (SIZE, SIZE), interpolation=cv2.INTER_AREA).astype(np.float64)
    img = cv2.GaussianBlur(img, (0, 0), blur) if blur else img
    yy, xx = np.mgrid[:SIZE, :SIZE]
    for gx, gy in p["glints"]:
        img += glint_peak * np.exp(-((xx - gx) ** 2 + (yy - gy) ** 2) / (2 * glint_sigma**2))
    if noise:
        img += np.random.default_rng(p["seed"]).normal(0.0, noise, img.shape)
    return img


def u8(img: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def err(d, centre=CENTRE) -> float:
    return math.hypot(d.pupil.centre_px[0] - centre[0], d.pupil.centre_px[1] - centre[1])


def assert_pupil(d, tol=0.25, centre=CENTRE):
    assert d.ok, d.failures
    assert err(d, centre) < tol, (d.pupil, centre)


@pytest.mark.parametrize("seed", [0, 1])
def test_dark_iris_close_to_the_pupil(seed):
    """Pupil 12, iris 30 (18 levels apart), skin 150: pupil and iris make one histogram mode;
    the old valley threshold landed between iris and skin and answered nothing or the iris."""
    d = detect(u8(closeup(iris=30.0, pupil=12.0, seed=seed)))
    assert_pupil(d)
    assert d.pupil.axes_px[0] < 40  # the pupil, not the 90 px iris


def test_saturated_glints_do_not_set_the_scale():
    """Three glints far above full scale, one over the pupil's edge: clipped at 255 they make
    the image's range; the pupil is judged against its own surround and still found."""
    glints = [(76.0, 76.0), (104.0, 59.0), (80.4 + 17.0, 78.7)]  # in the pupil, iris, on its edge
    img = u8(closeup(glints=glints, glint_peak=2000.0, glint_sigma=2.5))
    d = detect(img)
    assert_pupil(d)
    found = [g.centre_px for g in d.glints]
    # The glint on the edge has its skirt half over the pupil, half over the iris: its
    # background-subtracted centroid leans to the brighter side (and is flagged).
    for (gx, gy), tol in zip(glints, (0.5, 0.5, 1.0), strict=True):
        assert min(math.hypot(gx - x, gy - y) for x, y in found) < tol
    assert any("on the pupil edge" in f for f in d.failures)


def test_glints_found_when_most_of_the_picture_saturates():
    """Light skin over-exposed: skin at 600 and the iris at 240 clip to 255 and 240, so most of
    the picture (the skin, ~70 %) is at full scale and the 99th percentile sits on it. The four
    saturated glints (two over the pupil, two over the iris-pupil surround) are still found
    against their own darker surround, centred within 0.5 px (a symmetric spot: its
    background-weighted centroid is its centre), and matched to their LEDs; noise specks
    (2 × 2 px, 3 σ) in the pupil and iris and saturated skin are not glints."""
    c = CENTRE
    glints = [(c[0] + 9.0, c[1]), (c[0], c[1] - 9.0), (c[0] - 9.0, c[1]), (c[0], c[1] + 9.0)]
    img = closeup(skin=600.0, iris=200.0, glints=glints, glint_peak=3000.0, glint_sigma=1.5)
    for x, y in [(70, 70), (92, 88), (110, 60), (50, 95)]:
        img[y : y + 2, x : x + 2] += 6.0  # 3 σ of the noise
    img = u8(img)
    assert (img == 255).mean() > 0.5
    d = detect(img, led_azimuths_deg=[0.0, 90.0, 180.0, 270.0])
    assert_pupil(d)
    assert [g.led for g in d.glints] == [0, 1, 2, 3], d.glints
    for g, (gx, gy) in zip(d.glints, glints, strict=True):
        assert math.hypot(g.centre_px[0] - gx, g.centre_px[1] - gy) < 0.5, (g, (gx, gy))


def test_black_border_is_not_the_pupil():
    """A crop that runs off the sensor (black rows below) and black corners (outside a
    headset's lens): darker than the pupil and far larger; never taken for it."""
    img = u8(closeup(pupil=25.0))
    img[135:, :] = 0
    yy, xx = np.mgrid[:SIZE, :SIZE]
    img[np.hypot(xx - 80, yy - 80) > 105] = 0
    d = detect(img)
    assert_pupil(d)


@pytest.mark.parametrize("cut", [62, 70])
def test_black_border_cutting_the_pupil_is_missing_pixels(cut):
    """A crop that ran off the sensor: black rows (exactly 0) over the top 15–25 % of the
    pupil. Darker than the pupil and joined to it, they once made pupil and border one
    border-connected region, and a dark speck elsewhere was refused as "pupil too small" (a
    real close-up did so). As missing pixels they cut the pupil; the rest gives its centre."""
    img = u8(closeup(pupil=25.0))
    img[:cut, :] = 0
    d = detect(img)
    assert_pupil(d)
    assert any(f.startswith("warning: a black border") for f in d.failures), d.failures


@pytest.mark.parametrize("speck_radius", [1.5, 2.5])
def test_pupil_cut_by_the_frame_is_not_called_too_small(speck_radius):
    """The pupil's centre on the picture's top edge (half of it outside) and a small dark speck
    below: the speck is not answered as the pupil, and the refusal says the pupil-sized dark
    region is on the border rather than that the pupil is too small."""
    img = closeup(centre=(80.4, 0.0))
    r = int(round(speck_radius * 16))
    cv2.circle(img, (40 * 16, 120 * 16), r, 10.0, -1, cv2.LINE_AA, 4)
    d = detect(u8(img))
    assert not d.ok and d.pupil is None
    assert d.failures[0].startswith("no pupil off the picture's border: "), d.failures


def test_small_pupil_is_measured_not_the_iris():
    """A 2 mm pupil (12 px across at this framing, ~110 px of area) in a 90 px iris."""
    d = detect(u8(closeup(pupil_axes=(12.5, 11.5), iris=60.0)))
    assert_pupil(d, tol=0.3)
    assert d.pupil.axes_px[0] < 15


def test_pupil_too_small_is_refused_by_name():
    """A 2.5 px pupil: under the 30 px of area a pupil needs (``pupil_min_area_px``)."""
    d = detect(u8(closeup(pupil_axes=(2.5, 2.5), blur=0.8)))
    assert not d.ok and d.pupil is None
    assert d.failures[0].startswith("pupil too small: "), d.failures


def test_bright_pupil_is_refused_by_name():
    """On-axis illumination: the retina lights the pupil, brighter than the iris and skin."""
    d = detect(u8(closeup(pupil=230.0, iris=60.0, skin=120.0)))
    assert not d.ok and d.pupil is None
    assert d.failures[0].startswith("no dark pupil: bright-pupil image?"), d.failures


def test_stuck_pixels_do_not_set_the_scale():
    """A hot pixel 64 × full scale (a 16-bit stuck pixel in a 10-bit picture) and a dead one:
    the pupil and the glints are still found; a single hot pixel is not a glint."""
    glints = [(72.0, 74.0), (90.0, 84.0)]
    img = closeup(glints=glints, glint_peak=400.0) * 4.0  # 10-bit levels
    img = np.clip(img, 0, 1023)
    img[20, 140] = 65535.0
    img[30, 25] = 0.0
    d = detect(np.rint(img).astype(np.uint16))
    assert_pupil(d)
    assert len(d.glints) == 2
    for g in d.glints:
        assert min(math.hypot(g.centre_px[0] - x, g.centre_px[1] - y) for x, y in glints) < 0.5


def test_lashes_are_neither_pupil_nor_glints():
    """Dark lashes over a bright sclera above the iris: thin and dark (not a compact blob), and
    the bright gaps between them stand out of their neighbourhood but are no glints."""
    img = closeup(skin=200.0, glints=[(86.0, 84.0)], glint_peak=600.0)
    for k in range(14):
        x0 = 35 + 7 * k
        cv2.line(img, (x0, 8), (x0 + 6, 34), 5.0, 2)
    d = detect(u8(img))
    assert_pupil(d)
    assert len(d.glints) == 1
    assert math.hypot(d.glints[0].centre_px[0] - 86.0, d.glints[0].centre_px[1] - 84.0) < 0.5


def test_nan_pixels_through_the_pupil():
    """A float picture with a NaN column through the pupil and a NaN patch: missing pixels;
    the outline next to them is left out and the rest gives the centre."""
    img = closeup(seed=3)
    img[:, 60] = np.nan
    img[70:74, 90:94] = np.nan
    d = detect(img)
    assert_pupil(d)


@pytest.mark.parametrize("pad", [160, 480])
def test_missing_pixels_do_not_move_the_threshold_ladder(monkeypatch, pad):
    """Missing pixels (NaN, outside a lens) are 255 in the pupil's working picture; the
    ladder's levels (P0.5 to P60, issue 13) must come from the valid pixels only. The same
    close-up with 50 % and 75 % of the frame NaN beside it gets the ladder it gets alone (it
    had P60 = 255 and a coarser step), and the same pupil."""
    from eyelume.analysis.tracking import pupil as pupil_mod

    seen = []
    levels = pupil_mod._levels

    def spy(small, params, fine):
        seen.append(levels(small, params, fine))
        return seen[-1]

    monkeypatch.setattr(pupil_mod, "_levels", spy)
    img = closeup(skin=200.0, iris=100.0, pupil=20.0)
    alone = detect(img)
    ladder_alone = seen[0]
    padded = np.full((SIZE, SIZE + pad), np.nan)
    padded[:, :SIZE] = img
    seen.clear()
    d = detect(padded)
    assert seen[0] == ladder_alone
    assert_pupil(d)
    assert err(d, alone.pupil.centre_px) < 0.01


def test_a_noise_speck_is_never_a_glint():
    """Specks of 2–4 px a few σ of the noise above their background (Gaussian noise σ 2 and a
    few 3 σ clusters): no glint is reported; a real glint beside them is."""
    img = closeup(glints=[(88.0, 70.0)], glint_peak=300.0)
    for x, y in [(40, 40), (120, 130), (100, 30), (30, 120)]:
        img[y : y + 2, x : x + 2] += 6.0  # 3 σ of the noise
    d = detect(u8(img), led_azimuths_deg=[0.0])
    assert d.ok, d.failures
    assert [g.led for g in d.glints] == [0]
    assert math.hypot(d.glints[0].centre_px[0] - 88.0, d.glints[0].centre_px[1] - 70.0) < 0.5


# --- eyelume track: any grey picture a camera writes; bad input is one line and exit 2 -------


def _track(*args):
    from typer.testing import CliRunner

    from eyelume.cli import app

    return CliRunner().invoke(app, ["track", *map(str, args)])


def _ok_centre(res):
    import json

    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["ok"], data["failures"]
    return data["pupil"]["centre_px"]


def test_track_reads_8_and_16_bit_png_tiff_float_npy_and_colour(tmp_path):
    img = closeup(seed=4)
    files = {
        "a.png": u8(img),
        "b.png": np.clip(np.rint(img * 256), 0, 65535).astype(np.uint16),
        "c.tif": np.clip(np.rint(img * 16), 0, 65535).astype(np.uint16),
        "e.png": np.dstack([u8(img)] * 3),  # colour: B = G = R
    }
    for name, arr in files.items():
        assert cv2.imwrite(str(tmp_path / name), arr)
    np.save(tmp_path / "d.npy", img.astype(np.float32))
    for name in [*files, "d.npy"]:
        res = _track(tmp_path / name)
        x, y = _ok_centre(res)
        assert math.hypot(x - CENTRE[0], y - CENTRE[1]) < 0.25, name
    assert "luminance" in _track(tmp_path / "e.png").stderr


def test_track_nan_pixels_are_missing_and_bad_inputs_are_one_line(tmp_path):
    img = closeup(seed=5)
    img[10:20, :] = np.nan
    np.save(tmp_path / "nan.npy", img)
    x, y = _ok_centre(_track(tmp_path / "nan.npy"))
    assert math.hypot(x - CENTRE[0], y - CENTRE[1]) < 0.25
    np.save(tmp_path / "allnan.npy", np.full((20, 20), np.nan))
    np.save(tmp_path / "empty.npy", np.zeros((0,)))
    np.save(tmp_path / "text.npy", np.array(["a", "b"]))
    (tmp_path / "junk.png").write_bytes(b"not a picture")
    # finite but beyond float32's squares (a new user's picture × 1e303: RuntimeWarnings, then
    # "cannot convert float NaN to integer" before session 27)
    np.save(tmp_path / "huge.npy", closeup(seed=5).astype(np.float64) * 1e303)
    cases = [
        (["huge.npy"], "rescale"),
        (["allnan.npy"], "no valid pixel"),
        (["empty.npy"], "empty"),
        (["text.npy"], "numeric"),
        (["junk.png"], "junk.png"),
        (["nan.npy", "--leds", "nan,90"], "--leds"),
        (["nan.npy", "--leds", ","], "--leds"),
    ]
    for args, word in cases:
        res = _track(*(tmp_path / args[0], *args[1:]))
        assert res.exit_code == 2, (args, res.output)
        lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
        assert len(lines) == 1 and word in lines[0], (args, res.stderr)
        assert "Traceback" not in res.output


def test_enlargement_factor_finds_nearest_neighbour_blocks_only():
    """k × k blocks of one value (a nearest-neighbour enlargement) give k; a camera's noisy
    picture, a uniform one and a picture whose blocks break in one pixel give 1."""
    from eyelume.analysis.tracking import enlargement_factor

    base = u8(closeup())
    for k in (2, 3, 8):
        assert enlargement_factor(np.kron(base, np.ones((k, k), np.uint8))) == k
    assert enlargement_factor(base) == 1
    assert enlargement_factor(np.zeros((64, 64))) == 1
    big = np.kron(base, np.ones((4, 4), np.uint8))
    big[100, 101] ^= 1
    assert enlargement_factor(big) == 1
    f = np.kron(closeup(), np.ones((2, 2)))
    f[10:12, 20:22] = np.nan  # NaN pixels, enlarged with the rest
    assert enlargement_factor(f) == 2


def test_black_sliver_of_skin_is_refused_not_the_pupil():
    """A black strip 4 px wide and 22 px long in the skin (drawn at 75°), the only dark thing
    in a picture without a pupil — like the strip no light reaches beside a lid in vr-offaxis
    at (30°, 20°): its fitted outline is ~40 × 3.7 px (axis ratio ~0.09), thinner than any
    pupil an eye camera sees (``pupil_min_axis_ratio``, 0.25 = cos 75.5°). It was answered
    ``ok`` as the pupil, 63 px from where the pupil would be; now the named refusal. With the
    pupil there too, the pupil is answered."""
    canvas = np.zeros((SIZE * 4, SIZE * 4), np.uint8)
    end = (30 + 22 * math.cos(math.radians(75)), 130 - 22 * math.sin(math.radians(75)))
    cv2.line(canvas, (120, 520), (int(4 * end[0]), int(4 * end[1])), 255, 16)
    strip = cv2.resize(canvas.astype(np.float32) / 255, (SIZE, SIZE), interpolation=cv2.INTER_AREA)
    no_pupil = closeup(pupil=150.0, iris=150.0, iris_radius=1.0) * (1.0 - strip)
    d = detect(u8(no_pupil))
    assert not d.ok and d.pupil is None, d
    assert d.failures[0].startswith("no pupil: the dark blob is a sliver"), d.failures
    assert_pupil(detect(u8(closeup() * (1.0 - strip))))


def test_a_blob_dark_on_one_side_only_is_refused():
    """The surround check (``surround_sector_min``) on a made-up ellipse: a dark ellipse in
    brighter surround all round passes (a pupil in its iris); with the picture black beyond
    one side of it (the strip no light reaches beside a lid, vr-offaxis (20°, 0°) before the
    PSF, answered 77 px off), that sector is at the blob's own level and it is refused."""
    from eyelume.analysis.tracking.detect import DetectParams
    from eyelume.analysis.tracking.pupil import Ellipse, _one_sided, work_picture

    img = np.full((100, 100), 150.0)
    cv2.ellipse(img, ((50.0, 50.0), (30.0, 15.0), 20.0), 40.0, -1)
    e = Ellipse(50.0, 50.0, 15.0, 7.5, math.radians(20.0))
    none = np.zeros((100, 100), np.uint8)
    params = DetectParams()
    wp = work_picture(img, None, none, params)
    assert _one_sided(img, wp, e, 40.0, none, params) is None
    img[:, 62:] = 40.0  # the picture as dark as the blob beyond its right-hand end
    wp = work_picture(img, None, none, params)
    assert "dark on one side only" in _one_sided(img, wp, e, 40.0, none, params)


def test_an_iris_in_a_shadow_on_one_side_is_still_a_surround():
    """A sunlit face (vr-offaxis at 850 nm, 1 ms, the sun 40° up: the pupil 16 DN over a
    black of 14, the iris in the lid's shadow 30-32, lit ~70-90, the sclera ~570): the shadowed
    sector holds only 0.27 of the ring's step over the pupil, and the pupil was refused as
    "dark on one side only". The shadowed iris has 8x the pupil's signal above the black: it
    is a surround, not the dark side of a strip, which is as dark as the strip itself (the test
    above)."""
    from eyelume.analysis.tracking.detect import DetectParams
    from eyelume.analysis.tracking.pupil import Ellipse, _one_sided, work_picture

    def picture(shadow: float) -> np.ndarray:
        img = np.full((100, 100), 570.0)
        cv2.circle(img, (50, 50), 35, 90.0, -1)  # the lit iris
        quadrant = img[:50, :50]  # the iris's upper-left quarter in the lid's shadow
        quadrant[quadrant < 100.0] = shadow
        img[99, 99] = 14.0  # the black level
        cv2.ellipse(img, ((50.0, 50.0), (26.0, 24.0), 0.0), 16.0, -1)
        return img

    e = Ellipse(50.0, 50.0, 13.0, 12.0, 0.0)
    none = np.zeros((100, 100), np.uint8)
    params = DetectParams()
    img = picture(31.0)  # the shadowed sector is (31 - 16) / (90 - 16) = 0.2 of the step
    wp = work_picture(img, None, none, params)
    assert _one_sided(img, wp, e, 16.0, none, params) is None
    img = picture(17.0)  # a dark side: 3 DN over the black against the blob's 2
    wp = work_picture(img, None, none, params)
    assert "dark on one side only" in _one_sided(img, wp, e, 16.0, none, params)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_unlit_surround_filling_most_of_the_picture(seed):
    """A wide-angle headset camera (eyetrackvr): only a disc around the eye is lit, the rest
    (~70 % of the picture) is at the black level, as dark as the pupil. The ladder's top, the
    60th percentile, then sat on the black level and the ladder never reached the iris ("no
    compact dark blob", or the unlit surround called a pupil cut by the frame); it now runs at
    least a quarter of the range up (``ladder_min_span``) and the pupil is found."""
    img = closeup(
        skin=200.0, iris=30.0, pupil=6.0, iris_radius=30.0, pupil_axes=(22.0, 20.0), seed=seed
    )
    yy, xx = np.mgrid[:SIZE, :SIZE]
    r = np.hypot(xx - CENTRE[0], yy - CENTRE[1])
    dark = 6.0 + np.random.default_rng(seed + 10).normal(0.0, 2.0, img.shape)
    w = np.clip((r - 44.0) / 4.0, 0.0, 1.0)  # a lit disc of ~46 px radius
    img = u8((1.0 - w) * img + w * dark)
    assert (img < 12).mean() > 0.65
    d = detect(img)
    assert_pupil(d)
    assert d.pupil.axes_px[0] < 25  # the pupil, not the 60 px iris


def _ellipse_fit(cx, cy, a, b):
    from eyelume.analysis.tracking.pupil import Ellipse

    return Ellipse(cx, cy, a, b, 0.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_darker_core_inside_a_fit_names_the_iris(seed):
    """An ellipse fitted to the iris with the pupil inside it (vr-offaxis at (−10°, −20°) at
    400 × 400: bright skin sets the ladder's spacing, the pupil–iris step was crossed in one
    level and the iris answered 4.8 px off the pupil's centre): its interior's 5th percentile
    is at the black level, its median the iris's, many σ apart — refused by name. The same
    ellipse over a uniform noisy pupil (its 5th percentile 1.6 σ under its median) is not."""
    from eyelume.analysis.tracking.detect import DetectParams
    from eyelume.analysis.tracking.pupil import darker_core, work_picture

    params = DetectParams()
    img = np.round(
        closeup(skin=900.0, iris=45.0, pupil=16.0, noise=3.0, iris_radius=40.0, seed=seed)
    ).astype(np.uint16)
    bright = np.zeros(img.shape, np.uint8)
    wp = work_picture(img, None, bright, params)
    iris = _ellipse_fit(CENTRE[0], CENTRE[1], 40.0, 40.0)
    why = darker_core(img, wp, iris, bright, params)
    assert why.startswith("pupil merged with iris: ") and "darker core" in why, why
    pupil = _ellipse_fit(CENTRE[0], CENTRE[1], 15.0, 14.0)
    assert darker_core(img, wp, pupil, bright, params) == ""


@pytest.mark.parametrize("where", ["centre", "edge"])
def test_a_dead_pixel_inside_a_small_pupil_is_filled_not_a_cut(where):
    """One NaN pixel (a dead pixel) inside a 16 px pupil, at its centre or a pixel inside its
    edge, made the pupil "touch missing pixels" and refused it as cut by the frame (a fresh
    user's finding on a paper2005 render). A small enclosed hole is filled from its surround
    (``cv2.inpaint``): the pupil is found where it is without the hole, within 0.05 px, with a
    warning naming the filled pixels. A NaN run touching the picture's edge stays missing."""
    img = closeup(pupil_axes=(16.0, 15.0))
    alone = detect(img)
    assert_pupil(alone)
    x, y = int(CENTRE[0]), int(CENTRE[1])
    holed = img.copy()
    holed[(y, x) if where == "centre" else (y, x + 6)] = np.nan
    d = detect(holed)
    assert d.ok, d.failures
    assert err(d, alone.pupil.centre_px) < 0.05
    assert any("1 missing pixel(s) in small enclosed holes" in m for m in d.failures)
    edge = img.copy()
    edge[0, 10:14] = np.nan  # at the edge: not a hole, missing as before, no filling noted
    d = detect(edge)
    assert_pupil(d)
    assert not any("enclosed holes" in m for m in d.failures)


def _too_few_valid():
    """Pictures whose valid pixels all fall within one pixel of a missing one on the ladder's
    reduced picture (its missing pixels are grown by one): they crashed ``detect`` with NumPy's
    "zero-size array to reduction operation minimum" (issue 13, seen on mostly-NaN or mostly
    black renders)."""
    tiny = np.zeros((4, 4), np.uint8)  # the smallest: 2 × 2 valid pixels in a black border
    tiny[1:3, 1:3] = [[1, 2], [3, 4]]
    holey = np.full((768, 1024), np.nan, np.float32)  # reduced 10×: a 20 px patch is 2 px
    holey[300:320, 400:420] = closeup()[70:90, 70:90]
    strip = np.zeros((65, 87), np.float32)  # a 87 × 65 render's size, black but 2 columns
    strip[:, 40:42] = np.arange(1.0, 66.0)[:, None]
    return {"4x4": (tiny, None), "nan": (holey, None), "strip": (strip, None)} | {
        "mask": (closeup(), np.pad(np.ones((SIZE, 2), bool), ((0, 0), (79, 79))))
    }


@pytest.mark.parametrize("kind", ["4x4", "nan", "strip", "mask"])
def test_too_few_valid_pixels_is_a_named_refusal(kind):
    img, valid = _too_few_valid()[kind]
    d = detect(img, valid=valid, led_azimuths_deg=[0, 90, 180, 270])
    assert not d.ok and d.pupil is None, d
    assert d.failures[0].startswith("no pupil: too few valid pixels"), d.failures


def test_track_too_few_valid_pixels_is_a_refusal_not_a_traceback(tmp_path):
    """Through the CLI a refused picture is its JSON (``ok`` false) and the refusal on stderr,
    exit 0 (README: a frame where the pupil is not found "is reported as such"); it was exit 2
    with NumPy's message."""
    import json

    np.save(tmp_path / "nan.npy", _too_few_valid()["nan"][0])
    res = _track(tmp_path / "nan.npy")
    assert res.exit_code == 0, res.output
    assert "Traceback" not in res.output
    assert json.loads(res.stdout)["failures"][0].startswith("no pupil: too few valid pixels")
    first = res.stderr.splitlines()[0]
    assert first.startswith("no pupil: too few valid pixels") and first.endswith("grown by one")


def headset_frame(iris: float, pupil: float, seed: int) -> np.ndarray:
    """A 640 × 400 8-bit frame as a new user drew it (session 19): skin 170, the eye's opening
    an ellipse of sclera 200 (400 × 220 px), an iris of radius 85 px, a pupil of radius 30 px
    (edges antialiased over 1 px), four saturated glints 25 px from its centre, noise σ 3."""
    yy, xx = np.mgrid[0:400, 0:640].astype(float)
    cx, cy = 320.3, 200.7
    img = np.full((400, 640), 170.0)
    opening = ((xx - 320) / 200) ** 2 + ((yy - 200) / 110) ** 2 < 1
    img[opening] = 200.0
    r = np.hypot(xx - cx, yy - cy)
    img[(r < 85) & opening] = iris
    a = np.clip(30.5 - r, 0, 1)
    img = img * (1 - a) + pupil * a
    for dx, dy in ((25, 0), (0, -25), (-25, 0), (0, 25)):
        img += 400 * np.exp(-((xx - cx - dx) ** 2 + (yy - cy - dy) ** 2) / (2 * 1.5**2))
    img += np.random.default_rng(seed).normal(0.0, 3.0, img.shape)
    return u8(img)


@pytest.mark.parametrize("iris", [24.0, 26.0, 28.0])
@pytest.mark.parametrize("seed", [0, 1])
def test_a_pupil_a_few_sigma_darker_than_its_iris_is_never_the_iris(iris, seed):
    """Pupil 18, iris 24–28, noise σ 3 (2–3.3 σ a pixel apart): the ladder cannot part pupil
    from iris and fitted the iris, whose interior's lower tail is within the pixel noise of its
    median — answered `ok` with the 170 px iris as the pupil (a new user's pictures, session
    19: 24 of 24). Averaged over 5 × 5 px the pupil is a core many σ under the iris: the
    answer is the pupil or a refusal naming the merge, never the iris."""
    d = detect(headset_frame(iris, 18.0, seed), led_azimuths_deg=[0, 90, 180, 270])
    if d.ok:
        assert_pupil(d, tol=0.5, centre=(320.3, 200.7))
        assert d.pupil.axes_px[0] < 70  # the 60 px pupil, not the 170 px iris
    else:
        assert d.failures[0].startswith("pupil merged with iris: "), d.failures


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_shaded_uniform_pupil_has_no_averaged_core(seed):
    """The averaged-core test judges the lower tail against the spread of the interior's
    brighter half, so a real pupil shaded across (8 DN from side to side, noise σ 3) is no
    core, as a uniform one is not."""
    from eyelume.analysis.tracking.detect import DetectParams
    from eyelume.analysis.tracking.pupil import darker_core, work_picture

    params = DetectParams()
    img = closeup(skin=200.0, iris=90.0, pupil=20.0, noise=3.0, blur=0.0, seed=seed)
    img += np.linspace(-4.0, 4.0, SIZE)[None, :]  # shading across the picture
    img = u8(img)
    bright = np.zeros(img.shape, np.uint8)
    wp = work_picture(img, None, bright, params)
    pupil = _ellipse_fit(CENTRE[0], CENTRE[1], 17.0, 15.5)
    assert darker_core(img, wp, pupil, bright, params) == ""
    d = detect(img)
    assert_pupil(d, tol=0.5)


def test_a_uniform_picture_but_for_hot_pixels_says_they_were_mended():
    """A black picture with one saturated pixel is uniform once the hot pixel is mended (its
    neighbours' median): the refusal says so, not that every pixel of the input is 0."""
    img = np.zeros((100, 100), np.uint8)
    assert detect(img).failures == ["no pupil: the picture is uniform (every pixel 0)"]
    img[50, 50] = 255
    d = detect(img)
    assert not d.ok
    assert d.failures == [
        "no pupil: the picture is uniform (every pixel 0 once its 1 hot pixel(s) are mended)"
    ]
