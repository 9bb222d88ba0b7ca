"""The digital camera: image-plane irradiance → photo-electrons → digital numbers (DN).

One photosite of pitch p, exposed for t at quantum efficiency QE to the irradiance E of its
picture sample (see :class:`eyelume.scene.model.Sensor` for why every photosite sees the
image-plane irradiance of the paper's optics), collects on average

    N̄ = E · p² · t · QE / (h c / λ)   photo-electrons,

and reads out as

    DN = clip(round((min(Poisson(N̄), W) + Normal(0, σ)) / g + b), 0, 2^bits − 1)

with W the full well and σ the read noise (e⁻), g the gain (e⁻/DN) and b the black level (DN).

The quantum efficiency is one number or a QE(λ) curve (``sensor.quantum_efficiency``: a
built-in curve's name or a CSV table; :func:`quantum_efficiency_curve`). LEDs of spectral width
(FWHM) w > 0 (``leds.spectral_width_nm``) emit a Gaussian spectrum S(λ) of that width, unit
area, centred on their wavelength λ₀; a watt of it gives

    ∫ QE(λ) λ/(h c) S(λ) dλ   photo-electrons per second   (:func:`spectral_response_nm`)

instead of QE(λ₀) λ₀/(h c). A filter in front of the sensor (``sensor.filter``,
:func:`filter_transmittance`) multiplies QE(λ) by its transmittance T(λ) for every light.

Sunlight (``ambient.sun``, :func:`sunlight_band`) is counted the same way over its whole
spectrum: E_sun(λ) T(λ) QE(λ) λ/(h c) integrated over the wavelengths the sensor sees.

A pixel is *saturated* when its electrons reach the full well or its reading reaches the ADC's
full scale: its value no longer tells how much light it received. The noise draws come from a
NumPy generator keyed by (seed, a fixed tag), so the digital picture depends on the seed alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
from scipy.constants import c, h

from eyelume.errors import InputFileError, SceneError
from eyelume.scene.model import QE_CURVES, Sensor, Sun
from eyelume.scene.solar import solar_spectrum
from eyelume.scene.textfile import read_csv_table

__all__ = [
    "DigitalImage",
    "SunlightBand",
    "SATURATION_SIGMAS",
    "SPECTRUM_HALF_WIDTH_SIGMA",
    "camera_summary",
    "count_weights",
    "digitize",
    "electrons_per_w_mm2",
    "filter_transmittance",
    "filter_table",
    "gaussian_spectrum_sigma_nm",
    "photon_energy_j",
    "quantum_efficiency_at",
    "quantum_efficiency_curve",
    "spectral_response_nm",
    "sunlight_band",
]

_QE_FIELD = "sensor.quantum_efficiency"
_FILTER_FIELD = "sensor.filter.table_csv"
#: An LED's Gaussian spectrum is taken over λ₀ ± this many standard deviations (renormalised
#: to unit area there; the tails beyond hold 5.7e-7 of it), which the QE table must cover.
SPECTRUM_HALF_WIDTH_SIGMA = 5.0
#: Points of the uniform grid the spectrum is integrated on (trapezoid rule).
_SPECTRUM_POINTS = 4001

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


def _spectral_table(
    where: Path, field: str, column: str, words: tuple[str, str, str]
) -> tuple[np.ndarray, np.ndarray]:
    """A two-column CSV table ``wavelength_nm, <column>`` (a QE curve or a filter's T(λ)):
    (wavelengths nm (n,), values (n,)), each value a fraction in [0, 1]. ``words``: what the
    table is, what its values are, their symbol — for the messages.

    Raises
    ------
    InputFileError
        One line naming ``where`` and ``field``: unreadable, fewer than two rows, a wavelength
        not finite and > 0 or not strictly increasing (not a function of λ), a value outside
        [0, 1].
    """
    name, quantity, symbol = words
    table = read_csv_table(where, field, ("wavelength_nm", column))
    lam, v = table[:, 0], table[:, 1]
    if len(lam) < 2:
        raise InputFileError(
            f"{len(lam)} row(s): a {name} needs at least two wavelengths", file=where, field=field
        )
    for n, (x, y) in enumerate(table, 1):
        if not (math.isfinite(x) and x > 0):
            raise InputFileError(
                f"row {n}: wavelength {x!r} nm must be finite and > 0", file=where, field=field
            )
        if not (math.isfinite(y) and 0 <= y <= 1):
            raise InputFileError(
                f"row {n} ({x:g} nm): {quantity} {y!r} lies outside [0, 1]",
                file=where,
                field=field,
            )
    steps = np.diff(lam)
    if np.any(steps <= 0):
        n = int(np.argmax(steps <= 0)) + 2
        raise InputFileError(
            f"row {n}: wavelength {lam[n - 1]:g} nm after {lam[n - 2]:g} nm: the wavelengths "
            f"must increase strictly ({symbol} must be a function of wavelength)",
            file=where,
            field=field,
        )
    return lam, v


def quantum_efficiency_curve(sensor: Sensor) -> tuple[np.ndarray, np.ndarray] | None:
    """The sensor's QE(λ) table, (wavelengths nm (n,), QE (n,)), or None for one number.

    ``sensor.quantum_efficiency`` names a built-in curve (:data:`eyelume.scene.model.QE_CURVES`,
    files in ``eyelume/scene/presets/sensors/`` stating their source) or a CSV file of two
    columns ``wavelength_nm, quantum_efficiency`` read by
    :func:`eyelume.scene.textfile.read_csv_table` (``#`` comment lines, an optional header).

    Raises
    ------
    InputFileError
        One line naming the file and ``sensor.quantum_efficiency``: unreadable, fewer than two
        rows, a wavelength that is not finite and > 0, wavelengths not strictly increasing (QE
        not a function of λ), a QE outside [0, 1].
    """
    qe = sensor.quantum_efficiency
    if not isinstance(qe, str):
        return None
    if qe in QE_CURVES:
        where = Path(str(resources.files("eyelume.scene.presets") / "sensors" / QE_CURVES[qe]))
    else:
        where = Path(qe)
    return _spectral_table(
        where, _QE_FIELD, "quantum_efficiency", ("QE curve", "quantum efficiency", "QE")
    )


def _outside(sensor: Sensor, lam: np.ndarray, what: str) -> SceneError:
    return SceneError(
        f"{what} lies outside the QE curve's {lam[0]:g}-{lam[-1]:g} nm (it is not extrapolated)",
        field=_QE_FIELD,
        value=sensor.quantum_efficiency,
    )


def quantum_efficiency_at(sensor: Sensor, wavelength_nm: float) -> float:
    """QE at ``wavelength_nm``: the one number, or the curve linearly interpolated.

    Raises
    ------
    InputFileError
        A bad QE table (:func:`quantum_efficiency_curve`).
    SceneError
        ``wavelength_nm`` outside the table's range (one line naming
        ``sensor.quantum_efficiency`` and the wavelength).
    """
    curve = quantum_efficiency_curve(sensor)
    if curve is None:
        return float(sensor.quantum_efficiency)
    lam, q = curve
    if not lam[0] <= wavelength_nm <= lam[-1]:
        raise _outside(sensor, lam, f"{wavelength_nm:g} nm")
    return float(np.interp(wavelength_nm, lam, q))


def filter_table(sensor: Sensor) -> tuple[np.ndarray, np.ndarray] | None:
    """A ``kind = "table"`` filter's rows, (wavelengths nm (n,), T (n,)); None otherwise.

    Raises
    ------
    InputFileError
        One line naming the file and ``sensor.filter.table_csv``: unreadable, fewer than two
        rows, a wavelength not finite and > 0 or not strictly increasing (T not a function of
        λ), a transmittance outside [0, 1].
    """
    f = sensor.filter
    if f is None or f.kind != "table":
        return None
    where = Path(f.table_csv)  # type: ignore[arg-type]
    return _spectral_table(
        where, _FILTER_FIELD, "transmittance", ("filter table", "transmittance", "T")
    )


def filter_transmittance(sensor: Sensor, wavelength_nm) -> np.ndarray:
    """The sensor filter's transmittance T(λ) at ``wavelength_nm`` (a number or an array, nm):
    1 without a filter; a long- or band-pass filter's ``transmittance`` inside its band (edges
    included) and 0 outside; a table's rows linearly interpolated, 0 outside them.

    >>> from eyelume.scene.model import Sensor
    >>> s = Sensor(filter={"kind": "band_pass", "cut_on_nm": 900, "cut_off_nm": 980,
    ...                    "transmittance": 0.9})
    >>> filter_transmittance(s, [850.0, 940.0]).tolist()
    [0.0, 0.9]
    """
    lam = np.asarray(wavelength_nm, dtype=float)
    f = sensor.filter
    if f is None:
        return np.ones_like(lam)
    if f.kind == "table":
        t_lam, t = filter_table(sensor)  # type: ignore[misc]
        return np.interp(lam, t_lam, t, left=0.0, right=0.0)
    inside = lam >= f.cut_on_nm
    if f.kind == "band_pass":
        inside &= lam <= f.cut_off_nm
    return np.where(inside, f.transmittance, 0.0)


def _check_filter_covers(sensor: Sensor, lo: float, hi: float, what: str) -> None:
    """A table filter must cover an LED's wavelength (spectrum): SceneError otherwise."""
    table = filter_table(sensor)
    if table is not None and (lo < table[0][0] or hi > table[0][-1]):
        raise SceneError(
            f"{what} lies outside the filter table's {table[0][0]:g}-{table[0][-1]:g} nm "
            "(it is not extrapolated)",
            field=_FILTER_FIELD,
            value=sensor.filter.table_csv,  # type: ignore[union-attr]
        )


def gaussian_spectrum_sigma_nm(fwhm_nm: float) -> float:
    """Standard deviation of a Gaussian of full width at half maximum ``fwhm_nm``:
    σ = FWHM / (2 √(2 ln 2))."""
    return fwhm_nm / (2.0 * math.sqrt(2.0 * math.log(2.0)))


def spectral_response_nm(sensor: Sensor, wavelength_nm: float, fwhm_nm: float = 0.0) -> float:
    """∫ QE(λ) T(λ) λ S(λ) dλ (nm): the photo-electrons per joule times h c (λ in nm); T the
    sensor filter's transmittance (:func:`filter_transmittance`, 1 without a filter).

    S is a Gaussian spectrum of full width at half maximum ``fwhm_nm`` centred on
    λ₀ = ``wavelength_nm``, taken over λ₀ ± :data:`SPECTRUM_HALF_WIDTH_SIGMA` σ and normalised to
    unit area there; the integral is the trapezoid rule on a uniform grid of 4001 points
    (QE linearly interpolated between the table's rows). ``fwhm_nm`` = 0: QE(λ₀) λ₀. For a QE
    that is constant over the spectrum the result is QE λ₀ (S is symmetric); for a QE linear
    in λ, QE(λ₀) λ₀ + b σ_t², b its slope and σ_t² the truncated Gaussian's variance.

    Raises
    ------
    InputFileError, SceneError
        As :func:`quantum_efficiency_at`; SceneError when the table does not cover the
        spectrum λ₀ ± 5σ.
    """
    if fwhm_nm == 0:
        if sensor.filter is None:
            return quantum_efficiency_at(sensor, wavelength_nm) * wavelength_nm
        _check_filter_covers(sensor, wavelength_nm, wavelength_nm, f"{wavelength_nm:g} nm")
        t = float(filter_transmittance(sensor, wavelength_nm))
        return quantum_efficiency_at(sensor, wavelength_nm) * t * wavelength_nm
    sigma = gaussian_spectrum_sigma_nm(fwhm_nm)
    half = SPECTRUM_HALF_WIDTH_SIGMA * sigma
    lo, hi = wavelength_nm - half, wavelength_nm + half
    x = np.linspace(-SPECTRUM_HALF_WIDTH_SIGMA, SPECTRUM_HALF_WIDTH_SIGMA, _SPECTRUM_POINTS)
    lam = wavelength_nm + sigma * x
    weight = np.exp(-0.5 * x * x)
    curve = quantum_efficiency_curve(sensor)
    if curve is None:
        qe = np.full_like(lam, float(sensor.quantum_efficiency))
    else:
        table_lam, table_q = curve
        if lo < table_lam[0] or hi > table_lam[-1]:
            raise _outside(
                sensor,
                table_lam,
                f"the LED spectrum {lo:.4g}-{hi:.4g} nm (centre {wavelength_nm:g} nm, FWHM "
                f"{fwhm_nm:g} nm, ±{SPECTRUM_HALF_WIDTH_SIGMA:g} sigma)",
            )
        qe = np.interp(lam, table_lam, table_q)
    if sensor.filter is not None:
        _check_filter_covers(
            sensor, lo, hi, f"the LED spectrum {lo:.4g}-{hi:.4g} nm (centre {wavelength_nm:g} nm)"
        )
        qe = qe * filter_transmittance(sensor, lam)
    return float(np.trapezoid(qe * lam * weight, x) / np.trapezoid(weight, x))


def electrons_per_w_mm2(sensor: Sensor, wavelength_nm: float, fwhm_nm: float = 0.0) -> float:
    """Mean photo-electrons per pixel per W/mm² of irradiance: p² · t · QE / (h c / λ).

    p = ``pixel_pitch_um`` (µm → mm, so p² is in mm²), t = ``exposure_ms`` (ms → s); the result
    times an irradiance in W/mm² is N̄ in electrons. With a QE curve, QE at ``wavelength_nm``;
    with an LED spectrum of FWHM ``fwhm_nm`` > 0, p² t ∫ QE(λ) λ/(h c) S(λ) dλ
    (:func:`spectral_response_nm`). A single-number QE and ``fwhm_nm`` = 0 give exactly the
    plain formula.

    Raises
    ------
    InputFileError, SceneError
        A bad QE table or a wavelength (spectrum) outside it (:func:`spectral_response_nm`).
    """
    pitch_mm = sensor.pixel_pitch_um * 1e-3
    joules_per_w_mm2 = pitch_mm**2 * sensor.exposure_ms * 1e-3
    if isinstance(sensor.quantum_efficiency, float) and fwhm_nm == 0 and sensor.filter is None:
        return joules_per_w_mm2 * sensor.quantum_efficiency / photon_energy_j(wavelength_nm)
    response_nm = spectral_response_nm(sensor, wavelength_nm, fwhm_nm)
    return joules_per_w_mm2 * response_nm * 1e-9 / (h * c)


def count_weights(
    sensor: Sensor,
    wavelengths_nm: list[float],
    fwhm_nm: float | list[float],
    scene_wavelength_nm: float,
) -> list[float]:
    """For light of each wavelength (an LED spectrum of FWHM ``fwhm_nm`` centred on it: one
    width for all, or one per wavelength), the factor w_g that turns its irradiance into the
    irradiance at ``scene_wavelength_nm`` giving the same mean photo-electrons:
    w_g = :func:`electrons_per_w_mm2` (λ_g, FWHM) / :func:`electrons_per_w_mm2` (λ_scene).
    A single-number QE and no width: λ_g / λ_scene.

    Raises
    ------
    InputFileError, SceneError
        A bad QE table, a wavelength or spectrum outside it, or QE = 0 at the scene's
        wavelength (whose digital picture could then count nothing).
    """
    widths = list(fwhm_nm) if isinstance(fwhm_nm, list | tuple) else [fwhm_nm] * len(wavelengths_nm)
    if len(widths) != len(wavelengths_nm):
        raise ValueError(f"{len(widths)} widths for {len(wavelengths_nm)} wavelengths")
    if isinstance(sensor.quantum_efficiency, float) and not any(widths) and sensor.filter is None:
        return [lam / scene_wavelength_nm for lam in wavelengths_nm]
    if sensor.filter is not None and spectral_response_nm(sensor, scene_wavelength_nm) <= 0:
        raise SceneError(
            f"the filter blocks the scene's wavelength_nm = {scene_wavelength_nm:g}, at which "
            "the digital picture is counted: choose a wavelength the filter passes",
            field="sensor.filter",
            value=sensor.filter.kind,
        )
    if quantum_efficiency_at(sensor, scene_wavelength_nm) <= 0:
        raise SceneError(
            f"the QE curve is 0 at the scene's wavelength_nm = {scene_wavelength_nm:g}, at "
            "which the digital picture is counted: choose a wavelength the sensor sees",
            field=_QE_FIELD,
            value=sensor.quantum_efficiency,
        )
    ref = electrons_per_w_mm2(sensor, scene_wavelength_nm)
    return [
        electrons_per_w_mm2(sensor, lam, w) / ref
        for lam, w in zip(wavelengths_nm, widths, strict=True)
    ]


@dataclass(frozen=True)
class SunlightBand:
    """How the sensor counts the sunlight of ``ambient.sun`` (:func:`sunlight_band`).

    Attributes
    ----------
    irradiance_w_mm2 : float
        E_eq: the irradiance (W/mm², normal to the sun's direction, at the eye) of light at the
        scene's wavelength that would give the sensor as many photo-electrons as the sunlight.
    band_nm : (float, float)
        The wavelengths integrated (nm).
    seen_w_m2 : float
        s ∫ E_λ T dλ over the band: the sunlight the filter passes where the sensor sees (W/m²).
    trace_wavelength_nm : float
        λ̄, the electron-weighted mean wavelength of the counted sunlight (0.1 nm), at which its
        light is traced (the eye's indices, the cornea's reflection).
    spectrum : str
        The spectrum's name (``ambient.sun.spectrum``).
    """

    irradiance_w_mm2: float
    band_nm: tuple[float, float]
    seen_w_m2: float
    trace_wavelength_nm: float
    spectrum: str

    def summary(self) -> dict:
        return {
            "spectrum": self.spectrum,
            "band_nm": list(self.band_nm),
            "seen_w_m2": self.seen_w_m2,
            "equivalent_irradiance_w_m2": self.irradiance_w_mm2 * 1e6,
            "trace_wavelength_nm": self.trace_wavelength_nm,
        }


def _sun_band(sensor: Sensor) -> tuple[float, float]:
    """Where the sensor sees sunlight: the QE curve's range, narrowed to the filter's band."""
    lo, hi = 0.0, math.inf
    curve = quantum_efficiency_curve(sensor)
    if curve is not None:
        lo, hi = float(curve[0][0]), float(curve[0][-1])
    f = sensor.filter
    if f is not None and f.kind != "table":
        lo = max(lo, float(f.cut_on_nm))  # type: ignore[arg-type]
        if f.kind == "band_pass":
            hi = min(hi, float(f.cut_off_nm))  # type: ignore[arg-type]
    elif f is not None:
        t_lam = filter_table(sensor)[0]  # type: ignore[index]
        lo, hi = max(lo, float(t_lam[0])), min(hi, float(t_lam[-1]))
    if curve is None and math.isinf(hi):
        raise SceneError(
            "a single-number QE says nothing about where the sensor stops seeing: for sunlight "
            "give a QE curve (e.g. 'nir-global-shutter') or a band_pass or table sensor.filter",
            field=_QE_FIELD,
            value=sensor.quantum_efficiency,
        )
    return lo, hi


def sunlight_band(sensor: Sensor, sun: Sun, scene_wavelength_nm: float) -> SunlightBand:
    """The sunlight's count by the sensor, as an equivalent irradiance at the scene's wavelength.

    A surface patch that sends a fraction G of the light arriving on it from the sun's direction
    to a pixel (the same G at every wavelength of the band: the geometry, and reflectances taken
    at one wavelength λ̄) gives that pixel

        N̄ = G p² t s ∫ E_λ(λ) T(λ) QE(λ) λ/(h c) dλ   photo-electrons,

    E_λ the spectrum (``ambient.sun.spectrum``, :func:`eyelume.scene.solar.solar_spectrum`), s
    its ``scale``, T the filter (:func:`filter_transmittance`). Light of the scene's wavelength
    λ_s and irradiance E_eq gives G p² t E_eq R(λ_s)/(h c), R = :func:`spectral_response_nm`
    (λ_s) = QE(λ_s) T(λ_s) λ_s; so the sun is traced as a source of irradiance

        E_eq = s ∫ E_λ T QE λ dλ / R(λ_s)

    and its picture counted like light at λ_s (weight 1). The integral runs over where the
    sensor sees (the QE curve's range, narrowed to a long- or band-pass filter's band or a
    filter table's rows: :func:`_sun_band`), by the trapezoid rule on the union of the solar
    table's, the QE curve's and the filter table's rows there (E_λ, QE and T linear between
    them), exact at the filter's step edges.

    Raises
    ------
    SceneError
        A single-number QE without a band-pass or table filter (no band); a band the solar
        table does not reach, or through which no sunlight is counted; the QE or filter at the
        scene's wavelength 0 (:func:`count_weights`).
    InputFileError
        A bad QE or filter table.
    """
    lo, hi = _sun_band(sensor)
    lam_sun, e_sun = solar_spectrum(sun.spectrum)
    lo, hi = max(lo, float(lam_sun[0])), min(hi, float(lam_sun[-1]))
    if not lo < hi:
        raise SceneError(
            f"the sensor's band {lo:g}-{hi:g} nm holds no sunlight of the ASTM G173 table "
            f"({lam_sun[0]:g}-{lam_sun[-1]:g} nm)",
            field="ambient.sun",
            value=sun.spectrum,
        )
    nodes = [lam_sun, np.array([lo, hi])]
    curve = quantum_efficiency_curve(sensor)
    if curve is not None:
        nodes.append(curve[0])
    table = filter_table(sensor)
    if table is not None:
        nodes.append(table[0])
    lam = np.unique(np.concatenate(nodes))
    lam = lam[(lam >= lo) & (lam <= hi)]
    e = np.interp(lam, lam_sun, e_sun)
    qe = (
        np.full_like(lam, float(sensor.quantum_efficiency))
        if curve is None
        else np.interp(lam, curve[0], curve[1])
    )
    t = filter_transmittance(sensor, lam)
    w = e * t * qe * lam
    counted = float(np.trapezoid(w, lam))
    if counted <= 0:
        raise SceneError(
            f"no sunlight is counted in the sensor's band {lo:g}-{hi:g} nm (QE or filter 0 there)",
            field="ambient.sun",
            value=sun.spectrum,
        )
    count_weights(sensor, [scene_wavelength_nm], 0.0, scene_wavelength_nm)  # λ_s counts
    response = spectral_response_nm(sensor, scene_wavelength_nm)
    mean_nm = float(np.trapezoid(w * lam, lam)) / counted
    return SunlightBand(
        irradiance_w_mm2=sun.scale * counted / response * 1e-6,
        band_nm=(lo, hi),
        seen_w_m2=sun.scale * float(np.trapezoid(e * t, lam)),
        trace_wavelength_nm=round(mean_nm, 1),
        spectrum=sun.spectrum,
    )


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


#: Standard errors of the estimate by which a pixel's expected electrons must pass the clipping
#: level to count as saturated beyond the estimate's noise (:func:`camera_summary`).
SATURATION_SIGMAS = 2.0


def camera_summary(
    sensor: Sensor,
    wavelength_nm: float,
    digital: DigitalImage,
    estimate_std_w_mm2: np.ndarray | None = None,
) -> dict:
    """The camera's settings and the digital picture's facts as JSON-ready data (summary.json).

    ``saturated_share``: the share of the picture's pixels clipped (:func:`digitize`). With
    ``estimate_std_w_mm2`` (the standard error of each pixel's rendered irradiance, W/mm²,
    (rows, cols), the Monte Carlo estimate's — not the sensor's shot noise), also
    ``saturated_share_beyond_noise``: the share whose expected electrons N̄ pass the clipping
    level N_c = min(full well, (2^bits − 1 − black level + ½) · gain) by more than
    :data:`SATURATION_SIGMAS` standard errors, N̄ − 2 σ ≥ N_c. A pixel of the forward estimator
    reached by n rays of w electrons each has N̄ = n w and σ = √n w; with w a large part of the
    well (few rays per pixel) a pixel may saturate by noise alone: the render cannot tell, and
    the exposure is not yet to blame.
    """
    extra = {}
    if estimate_std_w_mm2 is not None:
        per = electrons_per_w_mm2(sensor, wavelength_nm)
        # a pixel's unknown error (inf: one sample) stays inf, not the largest float, whose
        # product overflowed with a RuntimeWarning; a missing one (NaN) counts as none
        std = np.asarray(estimate_std_w_mm2, dtype=np.float64)
        sigma = np.nan_to_num(std, nan=0.0, posinf=np.inf) * per
        clip = min(
            float(sensor.full_well_e),
            (digital.full_scale_dn - sensor.black_level_dn + 0.5) * sensor.gain_e_per_dn,
        )
        beyond = digital.mean_electrons - SATURATION_SIGMAS * sigma >= clip
        extra["saturated_share_beyond_noise"] = int(np.count_nonzero(beyond)) / max(
            digital.counts.size, 1
        )
    return {
        "pixel_pitch_um": sensor.pixel_pitch_um,
        "exposure_ms": sensor.exposure_ms,
        "quantum_efficiency": sensor.quantum_efficiency,
        "quantum_efficiency_at_wavelength": quantum_efficiency_at(sensor, wavelength_nm),
        **(
            {}
            if sensor.filter is None
            else {
                "filter": sensor.filter.model_dump(exclude_none=True),
                "filter_transmittance_at_wavelength": float(
                    filter_transmittance(sensor, wavelength_nm)
                ),
            }
        ),
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
        **extra,
        "median_dn": float(np.median(digital.counts)) if digital.counts.size else 0.0,
        "units": {"counts": "DN", "electrons_per_w_mm2": "e-/(W/mm^2)", "exposure": "ms"},
    }
