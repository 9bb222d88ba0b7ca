"""The pupil on the off-axis presets' renders (issue 11 item 6, issue 13): found, and within
0.5 px of the renderer's truth.

The pictures are small renders (the presets' optics with a coarser chip, so the eye fills the
same field): ``vr-offaxis`` at 100 × 100 (12 µm pixels) and 200 × 200 (6 µm, the setting of
``eyelume evaluate-tracking --scene vr-offaxis --samples 4 --set sensor.cols=200 --set
sensor.rows=200 --set sensor.pixel_pitch_um=6 --set sensor.exposure_ms=1``), and
``glasses-frame`` at 160 × 120 (12 µm). The eye is seen 40–50° off its axis: the pupil is an
ellipse of axis ratio ~0.7, at the sensor's black level, in a near-black iris, while the
lit skin around the eye fills most of the picture and sets the noise and the grey scale.
Before, the detector answered none of the 200 × 200 frames ("pupil merged with iris": the picture's
noise σ, set by the skin's shot noise and the sparse Monte Carlo samples there, was ~10× that
between pupil and iris; and the ladder's levels, spaced by the skin, crossed the pupil–iris
step in one or two levels).

Tolerance: 0.5 px between the detected ellipse's centre and the centre of the ellipse fitted
to the truth's apparent pupil outline (the same definition, :mod:`.evaluate`) — issue 13's
bound for eyelume's renders ("still within 0.5 px of the truth"). The pupils are 16–40 px
across, so 0.5 px is 1–3 % of the diameter; the detector's errors on these frames are
0.02–0.2 px.

Glints are not asserted: at these sizes a corneal glint of the presets' LEDs is one pixel or
less and a 4-sample render draws some of them and not others (see the README's tracking
section); ``ok`` is then False for "glint lost" when fewer than two are matched.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import eyelume
from eyelume.analysis.tracking import detect
from eyelume.analysis.tracking.evaluate import _truth_ellipse_centre, led_picture_azimuths
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.detectors.sensor import digitize
from eyelume.render import RenderOptions, render

TOL_PX = 0.5

VR_100 = {
    "sensor.cols": 100,
    "sensor.rows": 100,
    "sensor.pixel_pitch_um": 12.0,
    "sensor.exposure_ms": 1.0,
}
VR_200 = {**VR_100, "sensor.cols": 200, "sensor.rows": 200, "sensor.pixel_pitch_um": 6.0}
GLASSES = {"sensor.cols": 160, "sensor.rows": 120, "sensor.pixel_pitch_um": 12.0}


def _pupil_detect(preset: str, sets: dict, h: float, v: float, seed: int = 0, samples: int = 4):
    """Render, digitize and detect one frame: (the detection, its refusals other than the
    glints', the truth)."""
    sc = eyelume.load_scene(
        preset, {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v, **sets}
    )
    cs = compile_scene(sc)
    r = render(cs, RenderOptions(estimator="fast", samples_per_pixel=samples, seed=seed))
    counts = digitize(r.eye_image, sc.sensor, sc.wavelength_nm, seed=seed).counts
    d = detect(counts, led_azimuths_deg=led_picture_azimuths(cs))
    pupil_errors = [
        f for f in d.failures if not f.startswith("warning") and not f.startswith("glint")
    ]
    return d, pupil_errors, eye_truth(cs)


def _assert_pupil_right(d, truth) -> None:
    """The detected pupil within TOL_PX of the truth's centre, and the pupil, not the iris."""
    cx, cy = _truth_ellipse_centre(truth)
    err = math.hypot(d.pupil.centre_px[0] - cx, d.pupil.centre_px[1] - cy)
    assert err <= TOL_PX, (d.pupil, (cx, cy), err)
    # The pupil, not the iris (2.5× its size): the major axis within 15 % of the truth's.
    edge = np.asarray(truth["pupil"]["edge_px"], np.float32)
    major = max(cv2.fitEllipse(edge)[1])
    assert abs(d.pupil.axes_px[0] / major - 1.0) < 0.15, (d.pupil.axes_px, major)


def _pupil_check(preset: str, sets: dict, h: float, v: float, seed: int = 0, samples: int = 4):
    d, pupil_errors, truth = _pupil_detect(preset, sets, h, v, seed, samples)
    assert d.pupil is not None and not pupil_errors, d.failures
    _assert_pupil_right(d, truth)


def test_vr_offaxis_pupil_at_the_evaluation_size():
    """Failed before (the frames evaluate-tracking renders for vr-offaxis)."""
    _pupil_check("vr-offaxis", VR_200, 0.0, 0.0)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("h", "v"),
    [
        (20.0, -20.0),
        (30.0, 20.0),
        (-20.0, -20.0),
        (-30.0, 10.0),
    ],
)
def test_vr_offaxis_pupil_over_gazes(h, v):
    """Failed before, each; at (−30°, 10°) the upper lid hides a quarter of the pupil (refused
    from the diffraction PSF (issue 11) until this session's detector and scene changes, when
    its strict xfail mark turned into a failure: answered within the check's tolerance again).

    Over ten noise draws of the sensor (digitize seeds 0–9) of one render: every answer
    right, and at least 8 answered. The detector refuses some draws of these frames: at
    (20°, −20°) it took a dark strip by the lid fold for the pupil's blob (then refused it) in
    1 of 20 draws, before and after session 15's renderer change moved the glints within
    their pixels (which, through the sensor's Poisson draws, re-drew every pixel's noise:
    seed 0, answered before, was that one draw after). With p = 0.05 a draw, 3 or more
    refusals in 10 has probability 1.2 %."""
    sc = eyelume.load_scene(
        "vr-offaxis", {"eye.gaze_horizontal_deg": h, "eye.gaze_vertical_deg": v, **VR_200}
    )
    cs = compile_scene(sc)
    r = render(cs, RenderOptions(estimator="fast", samples_per_pixel=4, seed=0))
    truth, azimuths = eye_truth(cs), led_picture_azimuths(cs)
    answered = 0
    for seed in range(10):
        counts = digitize(r.eye_image, sc.sensor, sc.wavelength_nm, seed=seed).counts
        d = detect(counts, led_azimuths_deg=azimuths)
        if d.pupil is not None:
            _assert_pupil_right(d, truth)
            answered += 1
    assert answered >= 8, answered


@pytest.mark.slow
@pytest.mark.parametrize(
    ("h", "v", "seed"),
    [
        (0.0, 0.0, 0),
        (20.0, -20.0, 1),
        (-20.0, 10.0, 2),
    ],
)
def test_vr_offaxis_pupil_small(h, v, seed):
    """At 100 × 100 (a pupil of 16–20 px). Since each LED's light paths aim at its glint
    (``CameraTables.glint_aim``) a 4-sample render at this size has its glints, and at (0°, 0°)
    and (−20°, 10°) 1–3 px glints 2–4 px outside the pupil's edge, filled with the pupil's
    dark by the working picture, grew bumps on its blob: refused as "not compact (solidity
    0.77 / 0.71 < 0.80)" (strict xfails until the glints' pixels were left out of the blob's
    compactness, ``pupil._glint_forgiven``; the synthetic cases below pin it without a
    render)."""
    _pupil_check("vr-offaxis", VR_100, h, v, seed)


@pytest.mark.slow
@pytest.mark.parametrize(("h", "v"), [(0.0, 0.0), (30.0, 20.0)])
def test_glasses_frame_pupil(h, v):
    """The skin saturates (full scale over most of the picture); the pupil and iris do not."""
    _pupil_check("glasses-frame", GLASSES, h, v)


#: The refusals a glasses-frame picture at (20°, −20°) may honestly end in (see below).
_MARGINAL_REFUSALS = ("pupil cut or hidden", "no pupil: the darkest blob")


@pytest.mark.slow
def test_glasses_frame_pupil_marginal_gaze_never_wrong():
    """At (20°, −20°) saturated patches of skin beside the iris pass as glints; each glint is
    filled with the darkest value within its own radius (with the largest one's, they turned the
    pupil's neighbourhood dark and the pupil was refused as not compact), and the outline points
    under them are left out. The frame is at the edge of the detector's reach: over seeds 0–3 it
    was answered at 2 of 4 before 88db55a and at 1 of 4 after it (that commit moved the fast
    estimator's samples at rounding level — the picture's sum by 3e-8 — which flips which
    skin patches saturate into glints: at seed 0, 110 outline points fall under them and the
    support drops to 43 % against the 45 % needed). So no one seed is pinned: the detector must
    never answer wrongly (every answer within 0.5 px of the truth and the pupil's size), refuse
    only for the pupil's named causes, and answer at least one of the four."""
    answered = 0
    for seed in range(4):
        d, pupil_errors, truth = _pupil_detect("glasses-frame", GLASSES, 20.0, -20.0, seed)
        if d.pupil is not None and not pupil_errors:
            _assert_pupil_right(d, truth)
            answered += 1
        else:
            assert pupil_errors, d.failures
            assert all(f.startswith(_MARGINAL_REFUSALS) for f in pupil_errors), (seed, d.failures)
    assert answered >= 1


def test_paper_lid_cut_pupil_is_not_answered_off_by_a_pixel():
    """paper2005 at (−30°, −20°) (87 × 65, seed 0, 16 samples, as ``evaluate-tracking``): the
    upper lid hides 18 % of the pupil. The finer ladder's blob is the pupil's darkest core,
    whose fitted outline passes the usual support (0.59) 1.6–2.3 px off the truth; the finer
    pass must then refuse (stricter support), as the first pass does — ``ok`` only within 1 px
    (issue 13)."""
    sc = eyelume.load_scene(
        "paper2005", {"eye.gaze_horizontal_deg": -30.0, "eye.gaze_vertical_deg": -20.0}
    )
    cs = compile_scene(sc)
    r = render(cs, RenderOptions(estimator="fast", samples_per_pixel=16, seed=0))
    counts = digitize(r.eye_image, sc.sensor, sc.wavelength_nm, seed=0).counts
    d = detect(counts, led_azimuths_deg=led_picture_azimuths(cs))
    cx, cy = _truth_ellipse_centre(eye_truth(cs))
    if d.ok:
        assert math.hypot(d.pupil.centre_px[0] - cx, d.pupil.centre_px[1] - cy) <= 1.0, d.pupil


@pytest.mark.parametrize("n_glints", [2, 3])
@pytest.mark.parametrize("outside_px", [0.0, 4.5])
@pytest.mark.parametrize(
    ("axes", "angle"), [((19.0, 15.0), 30.0), ((17.0, 13.0), -20.0)], ids=["19x15", "17x13"]
)
def test_small_pupil_with_glints_on_its_edge(axes, angle, outside_px, n_glints):
    """A 100 × 100 picture the test draws (``test_detect.draw_eye``: pupil 30, iris 170, skin
    500 DN, 10-bit, blur σ 0.8 px, noise σ 8 DN) with a 17–19 px pupil — vr-offaxis's at 100 ×
    100 — and 2–3 saturated Gaussian glints (σ 0.8 px, ~3 px across) evenly
    around it, their centres on the drawn edge or 4.5 px outside it, where their skirts lie on
    the edge. The pupil's centre is answered within 0.5 px of the drawn one (the tolerance of
    the renders above). Before the glints' pixels were left out of the blob's compactness the
    three-glint pictures with the glints 4.5 px out were refused as not compact (solidity
    0.74 and 0.78): the working picture fills each glint with the darkest value within its reach,
    which for a glint just outside the edge is the pupil's, and the fill grew bumps on the
    blob — the vr-offaxis failure above, without a render."""
    from tests.analysis.test_detect import EyePicture, draw_eye

    centre = (49.3, 50.6)
    a, b = axes[0] / 2 + outside_px, axes[1] / 2 + outside_px
    t = math.radians(angle)
    glints = []
    for phi in np.linspace(0.3, 0.3 + 2 * math.pi, n_glints, endpoint=False):
        s, q = a * math.cos(phi), b * math.sin(phi)
        glints.append(
            (
                centre[0] + s * math.cos(t) - q * math.sin(t),
                centre[1] + s * math.sin(t) + q * math.cos(t),
            )
        )
    picture = EyePicture(
        shape=(100, 100),
        centre=centre,
        axes=axes,
        angle=angle,
        glints=glints,
        glint_sigma=0.8,
        iris_radius=1.1 * axes[0],
        blur=0.8,
    )
    d = detect(draw_eye(picture))
    assert d.ok and d.pupil is not None, d.failures
    err = math.hypot(d.pupil.centre_px[0] - centre[0], d.pupil.centre_px[1] - centre[1])
    assert err <= TOL_PX, (d.pupil, err)
