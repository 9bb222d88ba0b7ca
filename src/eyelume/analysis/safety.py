"""Eye safety of the LEDs against the IEC 62471 exempt group (photobiological safety of lamps).

Two hazards apply to 850 nm light (IEC 62471:2006, Table 6, exempt group, continuous wave,
exposure 1000 s; the same values as ANSI/IESNA RP-27.3):

* **infrared radiation hazard for the eye** (cornea and lens, 780–3000 nm): the irradiance at the
  eye E_IR ≤ 100 W/m²;
* **retinal thermal hazard, weak visual stimulus** (780–1400 nm): the source's burn-hazard
  weighted radiance L_IR = Σ L_λ R(λ) Δλ ≤ 6000 / α W/(m²·sr), α the source's angular subtense
  in rad, taken within [0.011, 0.1] rad as the standard prescribes.

Here E_IR is the irradiance at the corneal vertex from all LEDs together, each on a surface
facing it (the standard's worst case: the sum of the LEDs' normal irradiances
I₀ₖ fₖ(α_k) / d_k², each LED with its own on-axis intensity and profile, d_k the distance from
LED k's emission point). L_IR is each LED's mean radiance over its apparent emitting disc,
I₀ₖ / (π (Dₖ/2)²), Dₖ = ``leds.emitter_diameter_mm`` of LED k (the on-axis value: the worst
direction, as the eye may look into any LED), weighted by the burn-hazard function R(λₖ) at that
LED's own wavelength λₖ (``leds.wavelength_nm``; :func:`burn_hazard_weight`; 0.501 at 850 nm),
against the limit at αₖ = Dₖ / dₖ at that LED's distance; the retinal margin is the smallest
over the LEDs (each LED is its own source on the retina). The corneal irradiance E_IR sums every
LED whatever its wavelength (the infrared hazard's band is 780–3000 nm: a visible LED's share
is counted too, on the safe side). Each LED is taken as monochromatic at its wavelength:
for a real LED's spectrum of σ nm about it (Gaussian), the exponential R(λ)
averages to R(λ₀) · exp((σ ln 10 / 500)² / 2), +0.3 % for a 40 nm wide (FWHM) 850 nm LED.
A margin is limit / value (> 1: within the exempt group; ∞ where the value is 0, written as
``null`` in JSON files).
"""

from __future__ import annotations

import math

import numpy as np

from eyelume.scene.model import Scene
from eyelume.scene.pose import as_world, led_world_poses
from eyelume.scene.sources import relative_intensity

__all__ = [
    "E_IR_LIMIT_W_M2",
    "EXPOSURE_S",
    "R_UPPER_BOUND_BELOW_700",
    "burn_hazard_weight",
    "eye_safety",
    "retinal_thermal_limit",
]

E_IR_LIMIT_W_M2 = 100.0
EXPOSURE_S = 1000.0
SOURCE = (
    "IEC 62471:2006 Table 6, exempt group (continuous wave, 1000 s); retinal radiance weighted "
    "by the burn-hazard function R(λ) of Table 4.2"
)


#: R(λ) used below 700 nm: the maximum of IEC 62471:2006 Table 4.2's R(λ) (10.0, at 435–440 nm),
#: an upper bound (the table's visible values are not included here), so a visible source's
#: retinal margin is understated, never overstated.
R_UPPER_BOUND_BELOW_700 = 10.0


def burn_hazard_weight(wavelength_nm: float) -> float:
    """The burn-hazard weighting function R(λ) of IEC 62471:2006, Table 4.2 (dimensionless).

    For 700–1400 nm, the range of the standard's infrared retinal thermal hazard:

    * 700 < λ ≤ 1050 nm: R(λ) = 10^((700 − λ)/500)  (0.501 at 850 nm; 1 at 700 nm);
    * 1050 < λ ≤ 1150 nm: R(λ) = 0.2;
    * 1150 < λ ≤ 1200 nm: R(λ) = 0.2 · 10^(0.02 (1150 − λ));
    * 1200 < λ ≤ 1400 nm: R(λ) = 0.02.

    Beyond 1400 nm the ocular media absorb before the retina and the standard defines no
    retinal thermal hazard: 0. Below 700 nm: :data:`R_UPPER_BOUND_BELOW_700`, an upper bound.

    Examples
    --------
    >>> round(burn_hazard_weight(850.0), 4)
    0.5012
    """
    lam = float(wavelength_nm)
    if not (math.isfinite(lam) and lam > 0):
        raise ValueError(f"wavelength_nm = {wavelength_nm!r} must be a positive number")
    if lam < 700.0:
        return R_UPPER_BOUND_BELOW_700
    if lam <= 1050.0:
        return 10.0 ** ((700.0 - lam) / 500.0)
    if lam <= 1150.0:
        return 0.2
    if lam <= 1200.0:
        return 0.2 * 10.0 ** (0.02 * (1150.0 - lam))
    if lam <= 1400.0:
        return 0.02
    return 0.0


def retinal_thermal_limit(alpha_rad: float) -> float:
    """Exempt-group limit of L_IR, W/(m²·sr), for a source of angular subtense α (rad)."""
    return 6000.0 / min(max(alpha_rad, 0.011), 0.1)


def eye_safety(scene: Scene) -> dict:
    """Corneal IR irradiance and retinal thermal radiance of the scene's LEDs against the
    exempt-group limits (module docstring), JSON-ready. Positions in world mm: the corneal
    vertex of primary gaze sits at the eye's pose (``eye_pose``), moved by ``head_offset_mm``.

    Every LED counts with its own I₀ₖ and profile fₖ: E_IR = Σₖ I₀ₖ fₖ(αₖ) / dₖ² (LEDs whose
    axis looks away from the vertex, αₖ ≥ 90°, add 0). The retinal hazard is per source (each
    LED images to its own spot): Lₖ = I₀ₖ / (π (D/2)²) R(λ) against the limit at αₖ = D / dₖ;
    the reported retinal figures are those of the LED with the smallest margin
    (``retinal_worst_led``). ``per_led`` lists each LED's share, wavelength and weight R(λₖ);
    ``burn_hazard_weight`` at the top is the worst LED's."""
    leds = scene.leds
    centres, axes = led_world_poses(scene)
    emit = centres + axes * np.asarray(leds.emission_offsets_mm())[:, None]
    # the corneal vertex of primary gaze: the eye's pose and the head offset (world)
    eye = as_world(
        scene, np.add(scene.eye_pose.vertex_mm, np.asarray(scene.head_offset_mm, dtype=float))
    )
    profiles = leds.profiles()
    shapes = {p: relative_intensity(p) for p in set(profiles)}
    diameters = leds.emitter_diameters_mm()
    lams = leds.wavelengths_nm(scene.wavelength_nm)
    irr = 0.0
    per_led = []
    for p, a, i0, prof, dia, lam in zip(
        emit, axes, leds.intensities_w_sr(), profiles, diameters, lams, strict=True
    ):
        v = eye - p
        d = float(np.linalg.norm(v))  # mm
        cos_a = float(v @ a) / d
        e = 0.0
        if cos_a > 0:
            e = i0 * float(shapes[prof](math.acos(min(cos_a, 1.0)))) / (d * 1e-3) ** 2
            irr += e
        r_m = dia / 2 * 1e-3
        weight = burn_hazard_weight(lam)
        radiance = i0 / (math.pi * r_m * r_m) * weight
        limit = retinal_thermal_limit(dia / d)
        per_led.append(
            {
                "distance_mm": d,
                "wavelength_nm": lam,
                "burn_hazard_weight": weight,
                "emitter_diameter_mm": dia,
                "corneal_irradiance_w_m2": e,
                "retinal_radiance_w_m2_sr": radiance,
                "retinal_margin": limit / radiance if radiance > 0 else math.inf,
            }
        )
    worst = min(range(len(per_led)), key=lambda k: per_led[k]["retinal_margin"])
    r_m = diameters[worst] / 2 * 1e-3
    source_radiance = leds.intensities_w_sr()[worst] / (math.pi * r_m * r_m)
    weight = per_led[worst]["burn_hazard_weight"]
    radiance = source_radiance * weight
    alpha = diameters[worst] / per_led[worst]["distance_mm"]
    l_limit = retinal_thermal_limit(alpha)
    return {
        "source": SOURCE,
        "exposure_s": EXPOSURE_S,
        "corneal_irradiance_w_m2": irr,
        "corneal_limit_w_m2": E_IR_LIMIT_W_M2,
        "corneal_margin": E_IR_LIMIT_W_M2 / irr if irr > 0 else math.inf,
        "source_radiance_w_m2_sr": source_radiance,
        "burn_hazard_weight": weight,
        "retinal_radiance_w_m2_sr": radiance,
        "angular_subtense_rad": alpha,
        "retinal_limit_w_m2_sr": l_limit,
        "retinal_margin": l_limit / radiance if radiance > 0 else math.inf,
        "retinal_worst_led": worst,
        "within_exempt_group": irr <= E_IR_LIMIT_W_M2 and radiance <= l_limit,
        "per_led": per_led,
    }
