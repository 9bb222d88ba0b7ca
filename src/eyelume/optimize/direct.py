"""Beyond the paper: choose the LED placement for the evaluator's merit itself.

The paper could not afford a 20-minute ray trace per trial, so it optimised a proxy (the
eye-plane pattern against a target) and evaluated only the winners. With the fast estimator an
eye image costs well under a second, so the evaluator merit can be the objective: a bounded
Nelder–Mead search (SciPy; derivative-free, as the merit of a rendered image has no gradient)
over the LED height Y, distance Z, pitch θ and, optionally, the LEDs' half-intensity angle, for
each LED count asked (evenly spaced azimuths from 0°, optionally also rotated by half a step).
Every trial renders with the same seed (common random numbers), so the
objective is a deterministic, piecewise-smooth function of the variables and the simplex is not
chasing noise; the winner is then re-rendered with an independent seed to report an unbiased
merit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from eyelume.analysis.masks import IdealMask
from eyelume.errors import SceneError
from eyelume.estimators.interrupt import run_unit
from eyelume.optimize.delta_study import evaluate_placement
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import PER_LED_NUMBERS, Scene

__all__ = ["DirectResult", "DirectSearch", "optimize_direct"]

#: The paper's ranges (Section 4.1.1): Y 20–40 mm, Z 20–70 mm, θ 0–30°.
PAPER_BOUNDS = ((20.0, 40.0), (20.0, 70.0), (0.0, 30.0))


@dataclass
class DirectResult:
    """The best placement found, its merit (search seed) and an independent re-render's."""

    leds: int
    azimuth_offset_deg: float
    height_mm: float
    distance_mm: float
    pitch_deg: float
    half_angle_deg: float
    azimuth_shifts_deg: tuple[float, ...]
    merit: float
    merit_check: float
    merit_check_se: float
    evaluations: int
    history: list[tuple[float, ...]] = field(default_factory=list)

    def overrides(self) -> dict[str, object]:
        return _overrides(
            self.leds,
            self.azimuth_offset_deg,
            self.height_mm,
            self.distance_mm,
            self.pitch_deg,
            self.half_angle_deg,
            list(self.azimuth_shifts_deg) or None,
        )


def _overrides(n, offset, y, z, th, half, shifts=None) -> dict[str, object]:
    step = 360.0 / n
    shifts = shifts if shifts is not None else [0.0] * n
    return {
        "leds.count": n,
        "leds.azimuths_deg": [offset + k * step + float(shifts[k]) for k in range(n)],
        "leds.height_mm": float(y),
        "leds.distance_mm": float(z),
        "leds.pitch_deg": float(th),
        "leds.profile.half_intensity_angle_deg": float(half),
    }


@dataclass(frozen=True)
class DirectSearch:
    """What the direct search varies and what it may spend.

    ``led_counts``: the LED counts tried (evenly spaced azimuths from 0°); ``vary_spread``: the
    half-intensity angle is a variable too, within ``spread_bounds`` (degrees); ``vary_azimuths``:
    each LED's azimuth is a variable (within ± half the even spacing); ``try_rotated``: also the
    azimuths rotated by half a step (an × instead of a +). Each trial renders
    ``samples_per_pixel`` samples with ``seed``; each search stops after ``max_evaluations``.
    """

    led_counts: Sequence[int] = (4,)
    vary_spread: bool = False
    vary_azimuths: bool = False
    try_rotated: bool = False
    spread_bounds: tuple[float, float] = (10.0, 40.0)
    samples_per_pixel: int = 16
    seed: int = 0
    max_evaluations: int = 40


def optimize_direct(
    scene: Scene,
    mask: IdealMask,
    start: tuple[float, float, float],
    search: DirectSearch | None = None,
    progress: Callable[[str], None] | None = None,
) -> DirectResult:
    """Minimise the evaluator merit of the glints-off eye image over the LED placement.

    ``start`` is (Y, Z, θ), e.g. the paper's two-step answer; the search stays inside the
    paper's ranges. Impossible placements (an LED body crossing the eye plane or the lens, two
    bodies overlapping) score +inf. Returns the best over the LED counts and azimuth offsets of
    ``search`` (:class:`DirectSearch`), its merit re-rendered with the next seed.
    """
    search = search or DirectSearch()
    _check_leds_alike(scene, search.vary_spread)
    best: DirectResult | None = None
    for n in search.led_counts:
        for offset in (0.0, 180.0 / n) if search.try_rotated else (0.0,):
            cand = _search_one(scene, mask, start, search, n, offset)
            if progress:
                progress(
                    f"{n} LEDs from {offset:g}°: merit {cand.merit:.5f} at Y {cand.height_mm:.1f}"
                    f" Z {cand.distance_mm:.1f} θ {cand.pitch_deg:.1f}"
                )
            if best is None or cand.merit < best.merit:
                best = cand
    assert best is not None
    placed = apply_overrides(scene, best.overrides())
    _, merit, se, _ = run_unit(
        evaluate_placement, placed, mask, search.samples_per_pixel, search.seed + 1
    )
    best.merit_check, best.merit_check_se = merit, se
    return best


def _check_leds_alike(scene: Scene, vary_spread: bool) -> None:
    """The search varies the LED count (and with ``vary_spread`` a cosᵐ spread angle): it
    needs one I₀, one profile and one wavelength for every LED. Raises SceneError naming a
    per-LED list (or a table profile whose spread cannot vary)."""
    leds = scene.leds
    for name in (*PER_LED_NUMBERS, "profile", "body_shape"):
        value = getattr(leds, name)
        if isinstance(value, list):
            raise SceneError(
                "the direct search varies the LED count and spread: give one value for every "
                "LED, not one per LED",
                field=f"leds.{name}",
                value=value,
            )
    if vary_spread and leds.profile.kind != "cos_power":  # type: ignore[union-attr]
        raise SceneError(
            "the direct search varies the spread angle of a cos_power profile",
            field="leds.profile.kind",
            value=leds.profile.kind,  # type: ignore[union-attr]
        )


def _search_one(
    scene: Scene,
    mask: IdealMask,
    start: tuple[float, float, float],
    search: DirectSearch,
    n: int,
    offset: float,
) -> DirectResult:
    """One bounded Nelder–Mead search with ``n`` LEDs from azimuth ``offset`` (degrees)."""
    half0 = scene.leds.profiles()[0].half_intensity_angle_deg
    spread, azimuths = search.vary_spread, search.vary_azimuths
    history: list[tuple[float, ...]] = []

    def objective(x: np.ndarray) -> float:
        y, z, th = x[:3]
        half = x[3] if spread else half0
        shifts = x[4 if spread else 3 :] if azimuths else None
        try:
            placed = apply_overrides(scene, _overrides(n, offset, y, z, th, half, shifts))
            _, merit, _, _ = run_unit(
                evaluate_placement, placed, mask, search.samples_per_pixel, search.seed
            )
        except SceneError:
            merit = float("inf")
        history.append((*map(float, x), merit))
        return merit

    x0 = list(start) + ([half0] if spread else [])
    bounds = list(PAPER_BOUNDS) + ([search.spread_bounds] if spread else [])
    if azimuths:  # each LED's azimuth may move ± half the even spacing
        x0 += [0.0] * n
        bounds += [(-90.0 / n, 90.0 / n)] * n
    res = minimize(
        objective,
        np.array(x0, dtype=float),
        method="Nelder-Mead",
        bounds=bounds,
        options={"maxfev": search.max_evaluations, "xatol": 0.25, "fatol": 1e-5},
    )
    x = res.x
    return DirectResult(
        leds=n,
        azimuth_offset_deg=offset,
        height_mm=float(x[0]),
        distance_mm=float(x[1]),
        pitch_deg=float(x[2]),
        half_angle_deg=float(x[3]) if spread else half0,
        azimuth_shifts_deg=tuple(float(v) for v in (x[4 if spread else 3 :] if azimuths else [])),
        merit=float(res.fun),
        merit_check=float("nan"),
        merit_check_se=float("nan"),
        evaluations=int(res.nfev),
        history=history,
    )
