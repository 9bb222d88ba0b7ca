"""The paper's illumination generator (§4.1): the LED placement whose eye-plane pattern best
matches a target.

:func:`sweep_leds` scores every configuration of a grid of LED heights Y, axial distances Z and
pitches θ (the paper's 5 × 11 × 7 = 385: Y 20–40 mm, Z 20–70 mm, θ 0–30°, steps of 5) by the
generator merit (:func:`eyelume.analysis.merit.generator_merit`) of its free-space eye-plane
irradiance (:mod:`eyelume.estimators.closed_form`, no rays: the paper's "simple LED–eye plane
system"). :func:`refine` then moves continuously from a grid point within bounds.

Configurations whose geometry is impossible (an LED body reaching the eye plane, overlapping
bodies: :func:`eyelume.estimators.closed_form.geometry_problems`) get merit NaN, are listed in
``SweepResult.problems`` and are never chosen.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from eyelume.analysis.merit import generator_merit
from eyelume.errors import GeometryError
from eyelume.estimators.closed_form import (
    auto_order,
    bin_irradiance,
    configuration_irradiance,
    geometry_problems,
    led_emitters,
    plane_edges,
    product_grid,
)
from eyelume.scene.model import Scene

__all__ = ["PAPER_BOUNDS", "PAPER_GRID", "SweepResult", "refine", "sweep_leds"]

#: The paper's grid (§4.1.2): heights Y (mm), distances Z (mm), pitches θ (°).
PAPER_GRID = (range(20, 41, 5), range(20, 71, 5), range(0, 31, 5))
#: The paper's ranges (§4.1.1): Y 20–40 mm, Z 20–70 mm, θ 0–30°.
PAPER_BOUNDS = ((20.0, 40.0), (20.0, 70.0), (0.0, 30.0))


#: Columns of :meth:`SweepResult.table_rows`.
@dataclass
class SweepResult:
    """Every configuration of a sweep, in C order of (heights, distances, pitches).

    ``height_mm``, ``distance_mm``, ``pitch_deg``, ``merit`` are (n,) arrays, one entry per
    configuration; ``patterns`` (n, rows, cols) their eye-plane irradiance in W/mm² (NaN where
    the geometry is impossible); ``problems`` maps the index of each impossible configuration to
    the reason; ``heights``, ``distances``, ``pitches`` are the grid's axes.
    """

    heights: np.ndarray
    distances: np.ndarray
    pitches: np.ndarray
    height_mm: np.ndarray
    distance_mm: np.ndarray
    pitch_deg: np.ndarray
    merit: np.ndarray
    patterns: np.ndarray
    target: np.ndarray
    best_index: int
    problems: dict[int, str] = field(default_factory=dict)

    @property
    def best(self) -> dict[str, float | int]:
        """The best configuration: ``index``, ``height_mm``, ``distance_mm``, ``pitch_deg``,
        ``merit`` (the first in C order among equals)."""
        i = self.best_index
        return {
            "index": i,
            "height_mm": float(self.height_mm[i]),
            "distance_mm": float(self.distance_mm[i]),
            "pitch_deg": float(self.pitch_deg[i]),
            "merit": float(self.merit[i]),
        }

    def merit_grid(self) -> np.ndarray:
        """The merit reshaped to (len(heights), len(distances), len(pitches))."""
        return self.merit.reshape(len(self.heights), len(self.distances), len(self.pitches))

    def table_rows(self) -> list[dict[str, object]]:
        """One dict per configuration with the keys ``index``, ``height_mm``, ``distance_mm``,
        ``pitch_deg``, ``merit``, ``best``, ``problem`` (in that order), ready for
        :class:`csv.DictWriter`; ``merit`` is '' and ``problem`` the reason where impossible."""
        rows = []
        for i in range(len(self.merit)):
            ok = i not in self.problems
            rows.append(
                {
                    "index": i,
                    "height_mm": float(self.height_mm[i]),
                    "distance_mm": float(self.distance_mm[i]),
                    "pitch_deg": float(self.pitch_deg[i]),
                    "merit": float(self.merit[i]) if ok else "",
                    "best": int(i == self.best_index),
                    "problem": "" if ok else self.problems[i],
                }
            )
        return rows


def _check_target(scene: Scene, target: np.ndarray) -> np.ndarray:
    t = np.asarray(target, dtype=float)
    p = scene.eye_plane
    if t.shape != (p.rows, p.cols):
        raise ValueError(
            f"target shape {t.shape} does not match the eye plane's (rows, cols) = "
            f"({p.rows}, {p.cols})"
        )
    return t


def _over_limit(scene: Scene, y: float, z: float, th: float) -> str | None:
    """Why a placement exceeds an IEC 62471 exempt-group limit, or None."""
    from eyelume.analysis.safety import eye_safety
    from eyelume.scene.io import apply_overrides

    placed = apply_overrides(
        scene,
        {"leds.height_mm": float(y), "leds.distance_mm": float(z), "leds.pitch_deg": float(th)},
    )
    s = eye_safety(placed)
    if s["within_exempt_group"]:
        return None
    return (
        f"over the IEC 62471 exempt group (corneal margin {s['corneal_margin']:.2f}, "
        f"retinal margin {s['retinal_margin']:.2f})"
    )


def sweep_leds(
    scene: Scene,
    target: np.ndarray,
    heights: Sequence[float] = PAPER_GRID[0],
    distances: Sequence[float] = PAPER_GRID[1],
    pitches: Sequence[float] = PAPER_GRID[2],
    *,
    order: int | None = None,
    eye_safe: bool = False,
) -> SweepResult:
    """Score every LED placement of the grid against ``target`` (paper §4.1.2).

    With ``eye_safe`` a placement over an IEC 62471 exempt-group limit
    (:mod:`eyelume.analysis.safety`) is excluded like an impossible one (merit NaN, listed in
    ``problems``).

    Parameters
    ----------
    scene
        Its LEDs (count, azimuths, body, intensity, profile) and eye plane are used; the placement
        (Y, Z, θ) comes from the grid.
    target
        (rows, cols) target pattern on the eye plane (e.g.
        :func:`eyelume.analysis.targets.gaussian_target`).
    heights, distances, pitches
        Grid axes in mm, mm, degrees (default the paper's 385 configurations).
    order
        Gauss–Legendre order of the closed-form irradiance (None: chosen, see
        :func:`eyelume.estimators.closed_form.auto_order`).

    Returns
    -------
    SweepResult; raises ValueError if no configuration is possible.

    >>> import eyelume
    >>> from eyelume.analysis.targets import gaussian_target
    >>> scene = eyelume.load_scene("paper2005")
    >>> r = sweep_leds(scene, gaussian_target(0.3, scene.eye_plane))
    >>> len(r.merit), sorted(r.best)
    (385, ['distance_mm', 'height_mm', 'index', 'merit', 'pitch_deg'])
    """
    t = _check_target(scene, target)
    axes = [np.asarray(list(v), dtype=float).ravel() for v in (heights, distances, pitches)]
    if any(a.size == 0 for a in axes):
        raise ValueError("heights, distances and pitches must each hold at least one value")
    y, z, th = product_grid(*axes)
    why = geometry_problems(scene.leds, y, z, th)
    if eye_safe:
        why = [w or _over_limit(scene, y[i], z[i], th[i]) for i, w in enumerate(why)]
    problems = {i: w for i, w in enumerate(why) if w is not None}
    ok = np.array([w is None for w in why])
    if not ok.any():
        first = next(iter(problems.items()))
        raise GeometryError(
            f"no configuration of the grid is possible (e.g. #{first[0]}: {first[1]})"
        )
    patterns = np.full((len(y), *t.shape), np.nan)
    patterns[ok] = configuration_irradiance(scene, y[ok], z[ok], th[ok], order=order)
    merit = np.asarray(generator_merit(patterns, t), dtype=float).reshape(len(y))
    merit[~ok] = np.nan
    return SweepResult(
        heights=axes[0],
        distances=axes[1],
        pitches=axes[2],
        height_mm=y,
        distance_mm=z,
        pitch_deg=th,
        merit=merit,
        patterns=patterns,
        target=t,
        best_index=int(np.nanargmin(merit)),
        problems=problems,
    )


def refine(
    scene: Scene,
    target: np.ndarray,
    start: tuple[float, float, float],
    bounds: Sequence[tuple[float, float]] = PAPER_BOUNDS,
    *,
    order: int | None = None,
    maxiter: int = 200,
) -> tuple[float, float, float, float]:
    """Refine an LED placement (Y, Z, θ) continuously within ``bounds``; never worse than ``start``.

    The merit of the closed-form pattern is a smooth function of (Y, Z, θ) (an analytic integrand
    under a fixed quadrature rule, one order for the whole search), so a quasi-Newton method
    converges in a few dozen evaluations where a simplex method would need hundreds: SciPy's
    L-BFGS-B, which keeps to the box bounds itself, on the box scaled to [0, 1]³, with
    finite-difference gradients (each evaluation costs about a millisecond). It is a local
    search: start it from the grid's best (:func:`sweep_leds`). Every point of the box must be a
    possible placement (checked at its corners: the rules only get easier inside).

    Returns
    -------
    (Y, Z, θ, merit): the better of the optimizer's result and ``start``.
    """
    t = _check_target(scene, target)
    lo = np.array([float(b[0]) for b in bounds])
    hi = np.array([float(b[1]) for b in bounds])
    if lo.shape != (3,) or not np.all(hi >= lo):
        raise ValueError(f"bounds = {bounds!r}: need three (low, high) pairs with low ≤ high")
    x0 = np.asarray(start, dtype=float)
    if x0.shape != (3,) or np.any(x0 < lo - 1e-9) or np.any(x0 > hi + 1e-9):
        raise ValueError(f"start = {start!r} is not within bounds {bounds!r}")
    x0 = np.clip(x0, lo, hi)
    corners = np.array(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij")).reshape(3, -1)
    for why in geometry_problems(scene.leds, *corners):
        if why is not None:
            raise GeometryError(f"bounds {bounds!r} include an impossible placement: {why}")

    leds = scene.leds
    xe, ye = plane_edges(scene.eye_plane)
    if order is None:  # one order for the whole search, or the merit would jump between orders
        emit, axes = led_emitters(leds, *corners)
        order = auto_order(xe, ye, emit, axes, leds.profiles())
    span = np.where(hi > lo, hi - lo, 1.0)

    def merit_at(v: np.ndarray) -> float:
        emit, axes = led_emitters(leds, [v[0]], [v[1]], [v[2]])
        e = bin_irradiance(xe, ye, emit, axes, leds.intensities_w_sr(), leds.profiles(), order)
        return float(generator_merit(e[0], t))

    def objective(u: np.ndarray) -> float:
        return merit_at(lo + np.clip(u, 0.0, 1.0) * span)

    m0 = merit_at(x0)
    res = minimize(
        objective,
        (x0 - lo) / span,
        method="L-BFGS-B",
        bounds=[(0.0, 1.0)] * 3,
        options={"maxiter": maxiter},
    )
    v = lo + np.clip(res.x, 0.0, 1.0) * span
    m = merit_at(v)
    if not (math.isfinite(m) and m <= m0):
        v, m = x0, m0
    return float(v[0]), float(v[1]), float(v[2]), m
