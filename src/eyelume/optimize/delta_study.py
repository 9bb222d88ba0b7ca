"""The paper's Section 4.3 δ study (``eyelume reproduce``): for each target falloff δ, the
generator's best LED placement, its simulated eye image (glints off), and the evaluator's merit;
the best δ.

For every δ the 385-configuration sweep of :mod:`eyelume.optimize.sweep` picks the placement whose
eye-plane pattern best matches the δ target (and a bounded refinement is reported beside it); the
grid's best is then rendered by the fast estimator with the paper's glint removal
(:func:`eyelume.analysis.masks.glints_off`) and scored against the ideal eye-image mask. Every δ is
rendered with the same seed (common random numbers), so differences between δ are not blurred
by independent noise; each merit carries its standard error and the upward bias noise gives it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from eyelume.analysis.evaluator import evaluator_merit, skin_score
from eyelume.analysis.masks import IdealMask, glints_off, ideal_mask
from eyelume.analysis.safety import eye_safety
from eyelume.analysis.targets import gaussian_target
from eyelume.compile import compile_scene
from eyelume.estimators.interrupt import PartialRun, run_unit
from eyelume.optimize.sweep import refine, sweep_leds
from eyelume.render import RenderOptions, RenderResult, render
from eyelume.scene.io import apply_overrides
from eyelume.scene.model import Scene

__all__ = [
    "PAPER_MERITS",
    "PAPER_CHOICE",
    "DeltaRow",
    "evaluate_paper_placement",
    "evaluate_placement",
    "merit_noise",
    "run_delta_study",
    "with_placement",
]

#: The paper's published LightTools evaluator merits (Section 4.3), by δ.
PAPER_MERITS = {0.0: 380.5, 0.3: 341.8, 0.5: 342.3, 0.8: 459.1}
#: The paper's conclusions: best δ, recommended δ ± tolerance, the δ = 0.3 placement (mm, °).
PAPER_CHOICE = {
    "best_deltas": (0.3, 0.5),
    "recommended_delta": 0.4,
    "recommended_tolerance": 0.2,
    "placement_delta": 0.3,
    "height_mm": 40.0,
    "distance_mm": 70.0,
    "pitch_deg": 20.0,
}


@dataclass
class DeltaRow:
    """One δ of the study: the generator's choice and the evaluator's verdict."""

    delta: float
    height_mm: float
    distance_mm: float
    pitch_deg: float
    generator_merit: float
    refined: tuple[float, float, float, float]  # Y, Z, θ, merit of the continuous refinement
    evaluator_merit: float
    evaluator_merit_se: float
    evaluator_noise_bias: float
    skin_mean_w_mm2: float
    skin_std_w_mm2: float
    skin_cv: float
    pattern: np.ndarray
    image: np.ndarray
    corneal_margin: float = float("nan")
    retinal_margin: float = float("nan")


def with_placement(scene: Scene, height_mm: float, distance_mm: float, pitch_deg: float) -> Scene:
    """``scene`` with its LEDs at height Y, distance Z and pitch θ."""
    return apply_overrides(
        scene,
        {
            "leds.height_mm": float(height_mm),
            "leds.distance_mm": float(distance_mm),
            "leds.pitch_deg": float(pitch_deg),
        },
    )


def merit_noise(result: RenderResult, mask: IdealMask) -> tuple[float, float]:
    """Standard error of the evaluator merit of a render, and the merit's upward bias from the
    image noise, from the render's per-pixel variance.

    With s the exposure factor and r = s I − M, merit = Σ w r² / Σ w. At the optimal s the
    merit's derivative in s vanishes, so to first order ∂merit/∂I_p = 2 w_p s r_p / Σ w, and
    Var(merit) ≈ Σ_p (2 w_p s r_p / Σ w)² Var(I_p); noise adds E[Σ w s² δI²] / Σ w =
    Σ w s² Var(I) / Σ w to the expected merit.
    """
    img, var = result.eye_image, result.eye_image_variance
    w, m = mask.weights, mask.image
    ii = float(np.sum(w * img * img))
    s = float(np.sum(w * img * m)) / ii if ii > 0 else 0.0
    r = s * img - m
    sw = float(w.sum())
    se = math.sqrt(float(np.sum((2 * w * s * r / sw) ** 2 * var)))
    bias = float(np.sum(w * s * s * var)) / sw
    return se, bias


def evaluate_placement(
    scene: Scene, mask: IdealMask, samples_per_pixel: int, seed: int
) -> tuple[RenderResult, float, float, float]:
    """Render ``scene`` with its glints removed; (result, merit, merit SE, noise bias)."""
    result = render(
        compile_scene(glints_off(scene)),
        RenderOptions(estimator="fast", samples_per_pixel=samples_per_pixel, seed=seed),
    )
    merit = evaluator_merit(result.eye_image, mask.image, mask.weights)
    se, bias = merit_noise(result, mask)
    return result, merit, se, bias


def run_delta_study(
    scene: Scene,
    deltas: Sequence[float],
    samples_per_pixel: int = 32,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> list[DeltaRow]:
    """Run the Section 4.3 iteration over ``deltas`` (see the module docstring).

    ``progress(message)`` once per δ (a progress bar counts them). Ctrl-C or SIGTERM stops the
    study after the δ values finished: :class:`~eyelume.estimators.interrupt.PartialRun` with
    their rows (the δ in flight is dropped whole)."""
    mask = ideal_mask(compile_scene(scene))
    rows: list[DeltaRow] = []
    try:
        for delta in deltas:
            rows.append(run_unit(_delta_row, scene, mask, float(delta), samples_per_pixel, seed))
            r = rows[-1]
            if progress:
                progress(
                    f"δ = {delta:.2f}: Y {r.height_mm:g} Z {r.distance_mm:g} θ {r.pitch_deg:g}, "
                    f"evaluator merit {r.evaluator_merit:.5f} ± {r.evaluator_merit_se:.5f}"
                )
    except KeyboardInterrupt:
        raise PartialRun(rows, len(rows), len(deltas), "δ values") from None
    return rows


def _delta_row(scene: Scene, mask, delta: float, samples_per_pixel: int, seed: int) -> DeltaRow:
    """One δ of the study: the generator's best placement, refined, and its evaluation."""
    target = gaussian_target(float(delta), scene.eye_plane)
    sweep = sweep_leds(scene, target)
    b = sweep.best
    y, z, th = b["height_mm"], b["distance_mm"], b["pitch_deg"]
    refined = refine(scene, target, start=(y, z, th))
    placed = with_placement(scene, y, z, th)
    result, merit, se, bias = evaluate_placement(placed, mask, samples_per_pixel, seed)
    mean, std, cv = skin_score(result.eye_image, result.regions["skin"])
    safety = eye_safety(placed)
    return DeltaRow(
        delta=float(delta),
        height_mm=y,
        distance_mm=z,
        pitch_deg=th,
        generator_merit=b["merit"],
        refined=tuple(float(v) for v in refined),
        evaluator_merit=merit,
        evaluator_merit_se=se,
        evaluator_noise_bias=bias,
        skin_mean_w_mm2=mean,
        skin_std_w_mm2=std,
        skin_cv=cv,
        pattern=sweep.patterns[sweep.best_index],
        image=result.eye_image,
        corneal_margin=safety["corneal_margin"],
        retinal_margin=safety["retinal_margin"],
    )


def evaluate_paper_placement(scene: Scene, samples_per_pixel: int, seed: int) -> dict:
    """The paper's δ = 0.3 answer (Y 40, Z 70, θ 20) scored by our generator (its merit and rank
    among the 385 grid placements for the same target) and our evaluator."""
    pc = PAPER_CHOICE
    target = gaussian_target(pc["placement_delta"], scene.eye_plane)
    sweep = sweep_leds(scene, target)
    y, z, th = pc["height_mm"], pc["distance_mm"], pc["pitch_deg"]
    k = int(
        np.nonzero((sweep.height_mm == y) & (sweep.distance_mm == z) & (sweep.pitch_deg == th))[0][
            0
        ]
    )
    finite = np.isfinite(sweep.merit)
    rank = int(np.sum(sweep.merit[finite] < sweep.merit[k])) + 1
    mask = ideal_mask(compile_scene(scene))
    result, merit, se, _ = evaluate_placement(
        with_placement(scene, y, z, th), mask, samples_per_pixel, seed
    )
    mean, std, cv = skin_score(result.eye_image, result.regions["skin"])
    return {
        "delta": pc["placement_delta"],
        "height_mm": y,
        "distance_mm": z,
        "pitch_deg": th,
        "generator_merit": float(sweep.merit[k]),
        "generator_rank": rank,
        "configurations": int(finite.sum()),
        "evaluator_merit": merit,
        "evaluator_merit_se": se,
        "skin_cv": cv,
    }
