"""The render budget of a picture that a tracker or a labelled dataset reads: render to the
noise the sensor itself has, not below it.

A camera's picture carries shot noise of relative size 1/sqrt(N) for N photo-electrons in a
pixel; a render whose own Monte Carlo noise is well below that is wasted work, since the
digitised picture (:func:`eyelume.detectors.sensor.digitize`) adds the sensor's noise anyway.
``render_noise = "sensor"`` keeps the render's own noise — the median skin pixel's relative
standard error, as :func:`eyelume.render.render` measures it with ``rel_error`` — below the
sensor's shot noise there, 1/sqrt(N̄) for the N̄ mean photo-electrons of the median skin pixel
(:func:`eyelume.detectors.sensor.electrons_per_w_mm2`). N̄ is not known before the picture is
rendered, so a pilot render finds it (:func:`sensor_noise_target`): the same scene sampled by a
coarse grid of :data:`PILOT_COLS` columns over the same field (irradiance is per unit area, so
a coarse pixel reads the mean of the fine ones under it; the median over the skin's few hundred
coarse pixels is within a per cent or so), :data:`PILOT_SAMPLES` samples per pixel, its own
seed; the target is :data:`SENSOR_NOISE_MARGIN` / sqrt(N̄) (the margin absorbs the pilot's
estimate). A number instead is a fixed ``rel_error`` target.

With sunlight (``ambient.sun``) the sensor counts two independent sources, the LEDs' N̄_L and
the sun's N̄_S electrons, whose shot noises add in variance: sqrt(N̄_L + N̄_S). The LEDs' and
the sunlight's renders are separate (:func:`eyelume.render.render`) with independent noises,
which add in variance too, so each is rendered to the shot noise of its own electrons —
``rel_error`` = m / sqrt(N̄_L), ``ambient_rel_error`` = m / sqrt(N̄_S) (m =
:data:`SENSOR_NOISE_MARGIN`, each N̄ the median skin pixel of that source's pilot picture) —
and their sum's noise, m sqrt(N̄_L + N̄_S), stays within the margin of the whole picture's shot
noise. (One target m / sqrt(N̄_L + N̄_S) for both, the rule before, asks the weaker source for
(N̄_L + N̄_S) / N̄ times the samples it needs: ~4.4× for the LEDs of ``vr-offaxis`` at 850 nm
in the sun of ``benchmarks/design_850_940.py``.)

Used by the labelled datasets (:mod:`eyelume.optimize.dataset`, one pilot per picture) and by
tracking evaluation (:mod:`eyelume.optimize.tracking`, one pilot per scene: the skin's
electrons do not follow the gaze, ``tests/optimize/test_render_budget.py``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from eyelume.errors import GeometryError, OptionError
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "MAX_SAMPLES_PER_PIXEL",
    "NO_EYE_PLANE",
    "PILOT_COLS",
    "PILOT_SAMPLES",
    "SENSOR_NOISE_MARGIN",
    "SensorTarget",
    "noise_options",
    "parse_render_noise",
    "sensor_noise_target",
]

#: render_noise = "sensor": the pilot's columns (its rows in proportion), samples per pixel,
#: and the share of the shot noise aimed at (module docstring).
PILOT_COLS = 48
PILOT_SAMPLES = 8
SENSOR_NOISE_MARGIN = 0.9
#: The cap on camera samples per pixel of a ``rel_error`` render (a dark scene stops there).
MAX_SAMPLES_PER_PIXEL = 4096
#: The overrides that shrink a scene's eye-plane receiver to one bin, for a render whose eye
#: plane nobody reads (a tracking frame, its pilot, a dataset's picture): the fast render
#: computes the eye plane's direct irradiance apart from the picture — 16² points a bin with a
#: shadow ray to each LED, ~0.1 CPU-s a vr-offaxis frame on 21 × 15 bins (0.3–0.7 s a dataset
#: picture) — and the picture is the same bit for bit without it
#: (tests/optimize/test_dataset.py, tests/optimize/test_frame_eye_plane.py).
NO_EYE_PLANE = {"eye_plane.cols": 1, "eye_plane.rows": 1}
#: Mixed into the pilot's seed, so its samples are not the picture's.
_PILOT_TAG = 0x9170


class SensorTarget(NamedTuple):
    """The render targets of ``render_noise = "sensor"`` (:func:`sensor_noise_target`).

    ``rel_error``: the LEDs' render's, m / sqrt(``electrons``); ``electrons``: the pilot's
    median skin pixel's photo-electrons from the LEDs, N̄_L; ``ambient_rel_error`` and
    ``ambient_electrons``: the same for the sunlight's render (None without ``ambient.sun``)."""

    rel_error: float
    electrons: float
    ambient_rel_error: float | None = None
    ambient_electrons: float | None = None


def _median_skin_electrons(image: np.ndarray, skin: np.ndarray, per_w_mm2: float) -> float | None:
    lit = image[skin]
    lit = lit[lit > 0]
    return float(np.median(lit)) * per_w_mm2 if lit.size else None


def sensor_noise_target(scene: Scene, seed: int) -> SensorTarget:
    """The targets of ``render_noise = "sensor"``: :data:`SENSOR_NOISE_MARGIN` / sqrt(N̄) for
    the LEDs' render and, with ``ambient.sun``, for the sunlight's (module docstring), N̄ the
    median skin pixel's photo-electrons from each source in a pilot render of ``scene``
    sampled by :data:`PILOT_COLS` columns over the same field of the sensor,
    :data:`PILOT_SAMPLES` samples per pixel, seed derived from ``seed``. A sun that lights no
    skin pixel gets no target of its own (``ambient_rel_error`` None: the LEDs').

    Raises
    ------
    GeometryError
        The pilot's picture shows no skin with the LEDs' light on it.
    KeyboardInterrupt
        Ctrl-C or SIGTERM cut the pilot short.
    """
    from eyelume.detectors.sensor import electrons_per_w_mm2
    from eyelume.render import RenderOptions, render

    s = scene.sensor
    width, height = s.field_mm
    cols = min(s.cols, PILOT_COLS)
    rows = max(1, round(s.rows * cols / s.cols))
    pilot = apply_overrides(
        scene,
        {"sensor.width_mm": width, "sensor.height_mm": height, "sensor.cols": cols,
         "sensor.rows": rows, **NO_EYE_PLANE},
    )  # fmt: skip
    pilot_seed = int(np.random.SeedSequence([seed, _PILOT_TAG]).generate_state(1)[0] >> 1)
    opts = RenderOptions(estimator="fast", samples_per_pixel=PILOT_SAMPLES, seed=pilot_seed)
    result = render(pilot, opts)
    if result.interrupted:
        raise KeyboardInterrupt
    per = electrons_per_w_mm2(s, float(scene.wavelength_nm))
    skin = result.regions["skin"]
    electrons = _median_skin_electrons(result.led_image_at_scene_wavelength, skin, per)
    if electrons is None:
        raise GeometryError("the pilot picture shows no lit skin: give samples_per_pixel")
    target = SensorTarget(SENSOR_NOISE_MARGIN / math.sqrt(electrons), electrons)
    sun = None if result.ambient is None else result.ambient.eye_image
    ambient = None if sun is None else _median_skin_electrons(sun, skin, per)
    if ambient is None:
        return target
    return target._replace(
        ambient_rel_error=SENSOR_NOISE_MARGIN / math.sqrt(ambient), ambient_electrons=ambient
    )


def parse_render_noise(text: str, option: str = "--render-noise") -> str | float:
    """``"sensor"`` or a relative error in (0, 1) from a command-line value.

    Raises
    ------
    OptionError
        Anything else, naming ``option`` and the value.
    """
    if text.strip().lower() == "sensor":
        return "sensor"
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 < value < 1.0):
        raise OptionError(f"{option} {text}: 'sensor' or a relative error in (0, 1), e.g. 0.05")
    return value


def noise_options(
    scene: Scene, noise: str | float, seed: int, max_samples: int = MAX_SAMPLES_PER_PIXEL
) -> tuple[float, dict]:
    """(rel_error target, the budget's facts) of ``noise`` ("sensor": the pilot's targets for
    ``scene`` and ``seed``, :func:`sensor_noise_target`; a number: that target, for the
    sunlight's render too). The facts: ``budget`` ("sensor" or "render_noise"),
    ``target_rel_error``, ``pilot_skin_electrons`` (sensor only: the LEDs'),
    ``ambient_target_rel_error`` and ``pilot_ambient_skin_electrons`` (sensor, with a sun that
    lights the skin), ``max_samples_per_pixel``."""
    facts: dict = {"budget": "render_noise"}
    if noise == "sensor":
        t = sensor_noise_target(scene, seed)
        target = t.rel_error
        facts.update(budget="sensor", pilot_skin_electrons=t.electrons)
        if t.ambient_rel_error is not None:
            facts.update(
                ambient_target_rel_error=t.ambient_rel_error,
                pilot_ambient_skin_electrons=t.ambient_electrons,
            )
    else:
        target = float(noise)
    facts["target_rel_error"] = target
    facts["max_samples_per_pixel"] = max_samples
    return target, facts
