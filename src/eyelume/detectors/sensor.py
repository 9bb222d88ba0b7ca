"""The digital camera: image-plane irradiance → photo-electrons → digital numbers (DN).

One photosite of pitch p, exposed for t at quantum efficiency QE to the irradiance E of its
picture sample (see :class:`eyelume.scene.model.Sensor` for why every photosite sees the
image-plane irradiance of the paper's optics), collects on average

    N̄ = E · p² · t · QE / (h c / λ)   photo-electrons,

and reads out as

    DN = clip(round((min(Poisson(N̄), W) + Normal(0, σ)) / g + b), 0, 2^bits − 1)

with W the full well and σ the read noise (e⁻), g the gain (e⁻/DN) and b the black level (DN).

A pixel is *saturated* when its electrons reach the full well or its reading reaches the ADC's
full scale: its value no longer tells how much light it received. The noise draws come from a
NumPy generator keyed by (seed, a fixed tag), so the digital picture depends on the seed alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.constants import c, h

from eyelume.scene.model import Sensor

__all__ = ["DigitalImage", "camera_summary", "digitize", "electrons_per_w_mm2", "photon_energy_j"]

#: Second word of the noise generator's seed, so the camera's stream is not the tracer's.
_SEED_TAG = 0x5E7503


@dataclass(frozen=True)
class DigitalImage:
    """A digitized picture and the facts of its conversion.

    Attributes
    ----------
    counts : (rows, cols) uint16
        The reading of every pixel in DN, black level included.
    mean_electrons : (rows, cols) float64
        Expected photo-electrons per pixel, N̄, before noise and clipping.
    saturated : (rows, cols) bool
        Pixels clipped at the full well or at the ADC's full scale.
    electrons_per_dn : float
        The conversion gain (e⁻/DN).
    full_scale_dn : int
        The largest reading, 2^bits − 1.
    saturated_pixels : int
        How many pixels are saturated.
    photon_energy_j : float
        h c / λ at the scene's wavelength (J).
    """

    counts: np.ndarray
    mean_electrons: np.ndarray
    saturated: np.ndarray
    electrons_per_dn: float
    full_scale_dn: int
    saturated_pixels: int
    photon_energy_j: float


def photon_energy_j(wavelength_nm: float) -> float:
    """Energy of one photon, h c / λ, in joules (λ in nm)."""
    return h * c / (wavelength_nm * 1e-9)


def electrons_per_w_mm2(sensor: Sensor, wavelength_nm: float) -> float:
    """Mean photo-electrons per pixel per W/mm² of irradiance: p² · t · QE / (h c / λ).

    p = ``pixel_pitch_um`` (µm → mm, so p² is in mm²), t = ``exposure_ms`` (ms → s); the result
    times an irradiance in W/mm² is N̄ in electrons.
    """
    pitch_mm = sensor.pixel_pitch_um * 1e-3
    joules_per_w_mm2 = pitch_mm**2 * sensor.exposure_ms * 1e-3
    return joules_per_w_mm2 * sensor.quantum_efficiency / photon_energy_j(wavelength_nm)


def _check_irradiance(irradiance_w_mm2: np.ndarray) -> np.ndarray:
    e = np.asarray(irradiance_w_mm2, dtype=np.float64)
    if e.ndim != 2:
        raise ValueError(f"irradiance must be a 2-D (rows, cols) array, got shape {e.shape}")
    bad = int(np.count_nonzero(~np.isfinite(e)))
    if bad:
        raise ValueError(f"irradiance has {bad} NaN or infinite value(s) out of {e.size}")
    negative = int(np.count_nonzero(e < 0))
    if negative:
        raise ValueError(
            f"irradiance has {negative} negative value(s) (min {e.min():.3g} W/mm²); "
            "an irradiance is ≥ 0"
        )
    return e


def digitize(
    irradiance_w_mm2: np.ndarray, sensor: Sensor, wavelength_nm: float, seed: int
) -> DigitalImage:
    """Turn an image-plane irradiance map (W/mm², (rows, cols)) into the camera's reading (DN).

    Steps: N̄ = E · :func:`electrons_per_w_mm2` → Poisson shot noise → clip at the full well →
    + Gaussian read noise (σ = ``read_noise_e`` e⁻) → ÷ gain + black level → round → clip to
    [0, 2^bits − 1]. The same (irradiance, sensor, wavelength, seed) gives the same counts.

    Raises
    ------
    ValueError
        If the irradiance is not 2-D, holds NaN or inf, or is negative anywhere.
    """
    e = _check_irradiance(irradiance_w_mm2)
    mean_e = e * electrons_per_w_mm2(sensor, wavelength_nm)
    well = float(sensor.full_well_e)
    # Far above the well the draw is clipped anyway: capping the mean 50σ above the well changes
    # no outcome (P < 1e-500) and keeps Poisson's mean within NumPy's range for any input.
    cap = well + 50.0 * math.sqrt(well) + 50.0
    rng = np.random.default_rng([int(seed), _SEED_TAG])
    electrons = rng.poisson(np.minimum(mean_e, cap)).astype(np.float64)
    full = electrons >= well
    electrons = np.minimum(electrons, well)
    electrons += rng.normal(0.0, sensor.read_noise_e, size=e.shape)
    dn = np.rint(electrons / sensor.gain_e_per_dn + sensor.black_level_dn)
    full_scale = 2**sensor.adc_bits - 1
    saturated = full | (dn >= full_scale)
    counts = np.clip(dn, 0, full_scale).astype(np.uint16)
    return DigitalImage(
        counts=counts,
        mean_electrons=mean_e,
        saturated=saturated,
        electrons_per_dn=float(sensor.gain_e_per_dn),
        full_scale_dn=full_scale,
        saturated_pixels=int(np.count_nonzero(saturated)),
        photon_energy_j=photon_energy_j(wavelength_nm),
    )


def camera_summary(sensor: Sensor, wavelength_nm: float, digital: DigitalImage) -> dict:
    """The camera's settings and the digital picture's facts as JSON-ready data (summary.json)."""
    return {
        "pixel_pitch_um": sensor.pixel_pitch_um,
        "exposure_ms": sensor.exposure_ms,
        "quantum_efficiency": sensor.quantum_efficiency,
        "full_well_e": sensor.full_well_e,
        "read_noise_e": sensor.read_noise_e,
        "gain_e_per_dn": sensor.gain_e_per_dn,
        "adc_bits": sensor.adc_bits,
        "black_level_dn": sensor.black_level_dn,
        "full_scale_dn": digital.full_scale_dn,
        "wavelength_nm": wavelength_nm,
        "photon_energy_j": digital.photon_energy_j,
        "electrons_per_w_mm2": electrons_per_w_mm2(sensor, wavelength_nm),
        "saturated_pixels": digital.saturated_pixels,
        "saturated_share": digital.saturated_pixels / max(digital.counts.size, 1),
        "median_dn": float(np.median(digital.counts)) if digital.counts.size else 0.0,
        "units": {"counts": "DN", "electrons_per_w_mm2": "e-/(W/mm^2)", "exposure": "ms"},
    }
