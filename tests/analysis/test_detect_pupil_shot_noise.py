"""A pupil under a dark iris at shot noise (issue 13), on an eyelume render kept as a fixture.

Found in the 850/940 nm design run's population frames (session 25): a person with a dark
iris at 1 ms exposure, pupil 16 DN and iris 26–30 DN over a 14 DN black level, was answered
``ok`` with the whole iris as the pupil (207 × 144 px against the pupil's 54 × 40, centre
4.7 px off). The darker-core test judged the pupil's 11 DN step against the interior's noise,
the iris's (σ 1.7 DN with its texture: 6 σ, under the 8 σ it asks), while the pupil's own
noise, a few electrons' shot noise over the read noise, is σ 0.5: 20 σ deep. (Drawn pictures of
a pupil in a dark iris at shot noise — iris flat or shaded, textured up to σ 7 DN — were found
right before the fix too: the ladder told the pupil from the iris; in the render the iris meets
the lid's and lashes' shadows.)

``tests/reference/population_dark_iris_940nm.npz``: the digital picture (``counts``, 400 × 400
uint16 DN) of ``python benchmarks/design_850_940.py --people 50 --workers 1 --set
sensor.exposure_ms=1 --set run.indirect=cache --keep DIR`` at commit 0b498a2: person 2 of
population seed 1 on ``vr-offaxis`` at 940 nm, calibration frame (0°, −10°), the sun on; with
the truth's pupil outline (``pupil_edge_px``, 72 points of ``truth.json``'s ``pupil.edge_px``)
and the LEDs' azimuths and predicted glint layout that ``evaluate-tracking`` passes.

Tolerances: the issue's 1 px for the centre and the axes (the ellipse fitted to the truth's
outline; its rms 0.02 px).
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from eyelume.analysis.labels import fit_ellipse
from eyelume.analysis.tracking import detect

FIXTURE = Path(__file__).parents[1] / "reference" / "population_dark_iris_940nm.npz"


def detect_kept_frame(path: Path):
    """(the detection, the truth's pupil ellipse) of a kept render ``path`` (.npz: ``counts``,
    ``led_azimuths_deg``, ``led_pattern_px``, ``pupil_edge_px``), detected as
    ``evaluate-tracking`` does (the LEDs' azimuths and predicted glint layout passed)."""
    f = np.load(path)
    d = detect(
        f["counts"],
        led_azimuths_deg=list(f["led_azimuths_deg"]),
        led_pattern_px=f["led_pattern_px"],
    )
    return d, fit_ellipse(f["pupil_edge_px"])


def assert_pupil_is_the_truths(d, truth) -> None:
    """``d`` is ``ok`` with its pupil's centre and both axes within the issue's 1 px of the
    truth's ellipse (``fit_ellipse`` of ``truth.json``'s outline)."""
    assert d.pupil is not None, d.failures
    assert math.dist(d.pupil.centre_px, truth["center_px"]) < 1.0, (d.pupil, d.failures)
    got, want = sorted(d.pupil.axes_px), sorted(2 * np.asarray(truth["semi_axes_px"]))
    assert abs(got[0] - want[0]) < 1.0 and abs(got[1] - want[1]) < 1.0, (d.pupil, want)
    assert d.ok, d.failures


def test_pupil_in_a_dark_iris_of_a_population_render_is_not_the_iris():
    assert_pupil_is_the_truths(*detect_kept_frame(FIXTURE))


#: The same design run's person 1 at 940 nm (dark iris, 2.3 mm pupil), rendered again at
#: commit 4d274f9 (session 31's keep folder, the same command): its first calibration frame
#: (−15°, −10°), kept with the same keys as :data:`FIXTURE`.
SMALL = Path(__file__).parents[1] / "reference" / "population_dark_iris_small_pupil_940nm.npz"


def test_small_pupil_7_dn_under_a_dark_iris_is_found_not_the_iris():
    """Pupil 16 DN, iris 20–26 DN over a 14 DN black level, a 2.3 mm pupil (46 × 28 px) in a
    203 × 107 px dark iris fitted whole by the ladder. The iris's interior has its 5th
    percentile in the pupil, 7 DN under its median; the pupil's noise (Immerkær over its
    pixels, quantised) is 0.74 DN, so the core is 9.4 σ deep. The darker-core test had raised
    the noise of any integer picture to ≥ 1 DN (its percentiles move in whole steps), which
    asked 8 DN: the iris was answered ``ok``, its centre 3.3 px off (session 31's design run).
    Now the floor applies only under ½ DN of noise (479db5c). Fails before: the pupil's axes
    come out 203 × 107 px."""
    assert_pupil_is_the_truths(*detect_kept_frame(SMALL))


def _low_count_eye(seed: int, shade: float = 0.0, halo: tuple[float, float] | None = None):
    """An 8-bit low-count eye (320 × 240): pupil ellipse 52 × 47 px at 10 DN over black (iris
    disc 70 DN, skin 160) drawn 4× finer and area-reduced, blurred σ 1.5 px; a linear shading
    of ``shade`` DN across the pupil's diameter (direction 35°); four glints (σ 1.5 px,
    saturated) on a ring of 0.3 × the diameter inside it, each with a flare ``halo`` (σ px, DN)
    or none; Gaussian noise σ 0.3 DN, rounded. Returns (picture, centre)."""
    c, d, s = (158.97, 121.37), 52.0, 4
    rows, cols = 240, 320
    canvas = np.full((rows * s, cols * s), 160.0, np.float32)

    def fine(v: float) -> int:
        return int(round((s * v + (s - 1) / 2) * 256))

    cv2.circle(canvas, (fine(c[0]), fine(c[1])), int(s * (1.3 * d + 20) * 256), 70.0, -1, 8, 8)
    axes = (int(s * d / 2 * 256), int(s * 0.9 * d / 2 * 256))
    cv2.ellipse(canvas, (fine(c[0]), fine(c[1])), axes, 30, 0, 360, 10.0, -1, 8, 8)
    img = cv2.GaussianBlur(
        cv2.resize(canvas, (cols, rows), interpolation=cv2.INTER_AREA).astype(np.float64),
        (0, 0),
        1.5,
    )
    yy, xx = np.mgrid[:rows, :cols]
    u = (xx - c[0]) * math.cos(math.radians(35.0)) - (yy - c[1]) * math.sin(math.radians(35.0))
    img = np.maximum(img + shade * u / d, 0.0)
    for az in (0.0, 90.0, 180.0, 270.0):
        gx = c[0] + 0.3 * d * math.cos(math.radians(az))
        gy = c[1] - 0.3 * d * math.sin(math.radians(az))
        r2 = (xx - gx) ** 2 + (yy - gy) ** 2
        img += 3.0 * 255 * np.exp(-r2 / (2 * 1.5**2))
        if halo is not None:
            img += halo[1] * np.exp(-r2 / (2 * halo[0] ** 2))
    img = img + np.random.default_rng(seed).normal(0.0, 0.3, img.shape)
    return np.rint(np.clip(img, 0.0, 255.0)).astype(np.uint8), c


@pytest.mark.parametrize(
    ("seed", "shade", "halo"),
    [
        (1, 14.0, None),
        (1, 16.0, None),
        (1, 20.0, None),
        (0, 0.0, (6.0, 20.0)),
        (1, 0.0, (6.0, 20.0)),
    ],
)
def test_a_uniform_pupil_at_sub_step_noise_has_no_core(seed, shade, halo):
    """The darker-core test at an integer picture's noise under half a step: the noise counts
    as 1 step, as before session 32. At a ½-step floor (3431219), a uniform pupil 10 DN over
    black, at σ 0.3 DN, read as holding a core: session 32's new user's pictures with 14–20 DN
    of shading across it were refused ("pupil merged with iris"), those with four glints'
    flare halos inside it (σ 6 px, +20 DN) refused or answered ``ok`` with a crescent between
    the halos, 22 px off. Of these five, the 20 DN shading and the first halo fail there. The
    pupil must be found within 1 px (the shading biases the centre ~0.04 px a DN)."""
    img, centre = _low_count_eye(seed, shade, halo)
    d = detect(img, led_azimuths_deg=[0.0, 90.0, 180.0, 270.0])
    assert d.ok, d.failures
    assert math.dist(d.pupil.centre_px, centre) < 1.0, d.pupil
