"""People: anatomy and condition distributions with their sources, and seeded sampling.

An illumination designed for one schematic eye can fail for a real user; this module draws N
people from measured (or, where marked, assumed) distributions and makes each one a scene
(issue 15, part 2). Data, each distribution with its source in the file:
``scene/presets/eyes/population.toml`` — anterior corneal radius and asphericity Q, corneal
astigmatism (the power vector J0, J45: :func:`corneal_split`), pupil
diameter by ambient level (its mean from Watson & Yellott's 2012 unified formula), angle kappa,
centre of rotation, iris, sclera and skin NIR reflectance (skin by wavelength, Cooksey, Allen &
Tsai 2017), lid aperture, eyelashes (count and length on the upper lid: they switch
``face.lashes`` on) and headset slip (x, y, z).

Sampling: person ``i`` of seed ``s`` draws one uniform number per parameter (in the file's
order, whichever parameters are used) from ``numpy.random.SeedSequence(s).spawn(i + 1)[i]``,
and maps it through the distribution's inverse CDF (a normal truncated to its bounds, or a
uniform). A cornea that does not reach its limbus in front of the iris (steep and oblate:
R ≈ 6.8 mm with Q ≈ +0.25; 2.4·10⁻⁵ of draws at the library's spreads, measured over 10⁷ on
the Arizona eye) is redrawn, radius and asphericity together, from the same person's stream.
So person ``i`` is the same whatever the number of people, the chunk (``start``) or the
worker that draws them, and a parameter's value does not change when another parameter is
switched off.

A study file may hold a ``[population]`` table (:class:`Population`)::

    [population]
    size = 50                      # people
    seed = 1
    ambient = "display"            # a named level of population.toml's [ambient] or cd/m²
    field_diameter_deg = 100.0     # the adapting field (Watson & Yellott)
    age_years = 28.58              # Watson & Yellott's reference age: no age correction
    parameters = ["corneal_radius_mm", "pupil_diameter_mm"]   # default: all
    [population.distributions.corneal_radius_mm]               # change a distribution
    sd = 0.3
    bounds = [6.9, 8.7]

Layer: scene (imports only the scene layer and :mod:`eyelume.errors`).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationError, model_validator
from scipy.special import ndtr, ndtri

from eyelume.errors import EyelumeError, SceneError
from eyelume.scene.eye import LIMBUS_MISMATCH_MM
from eyelume.scene.io import apply_overrides, validation_error
from eyelume.scene.model import Scene
from eyelume.scene.model import _Model as _Table

__all__ = [
    "AMBIENT_LEVELS",
    "PARAMETERS",
    "Distribution",
    "DistributionOverride",
    "Person",
    "Population",
    "corneal_split",
    "load_population_file",
    "parameter_source",
    "parse_population",
    "resolved_distributions",
    "sample_people",
    "sample_population",
    "watson_yellott_pupil_mm",
]

_EYES = "eyelume.scene.presets.eyes"


@cache
def _data() -> dict[str, Any]:
    with resources.as_file(resources.files(_EYES) / "population.toml") as path:
        return tomllib.loads(path.read_text(encoding="utf-8"))


#: The sampled parameters, in the order their uniform numbers are drawn (population.toml).
PARAMETERS: tuple[str, ...] = tuple(k for k in _data() if k != "ambient")

#: Named ambient levels (adapting luminance, cd/m²) for the pupil (population.toml [ambient]).
AMBIENT_LEVELS: dict[str, float] = {k: float(v) for k, v in _data()["ambient"].items()}

#: Watson & Yellott's (2012) reference age (years): their age term vanishes there.
WY_REFERENCE_AGE = 28.58


def parameter_source(name: str) -> str:
    """The literature source (and ASSUMPTION marks) of parameter ``name``'s distribution."""
    return _data()[name]["source"]


def watson_yellott_pupil_mm(
    luminance_cd_m2: float | np.ndarray,
    field_diameter_deg: float = 100.0,
    age_years: float = WY_REFERENCE_AGE,
    eyes: int = 2,
) -> float | np.ndarray:
    """Mean light-adapted pupil diameter (mm), Watson & Yellott's unified formula.

    A. B. Watson and J. I. Yellott, "A unified formula for light-adapted pupil size", J. Vision
    12(10):12 (2012): the corneal flux density F = L·a·M(e) (L in cd/m², a = π(d/2)² the
    adapting field's area in deg², M = 1 for two eyes adapted, 0.1 for one) in Stanley &
    Davies's formula D_SD(F) = 7.75 − 5.75·(F/846)^0.41 / ((F/846)^0.41 + 2), then their age
    term D_U = D_SD + (y − 28.58)·(0.02132 − 0.009562·D_SD) (y the age in years).

    Raises
    ------
    ValueError
        A negative luminance, a field diameter outside (0, 180] deg, ``eyes`` not 1 or 2.
    """
    lum = np.asarray(luminance_cd_m2, dtype=float)
    if np.any(~np.isfinite(lum)) or np.any(lum < 0):
        raise ValueError(f"luminance {luminance_cd_m2!r} cd/m² must be a finite number ≥ 0")
    if not (0 < field_diameter_deg <= 180):
        raise ValueError(f"field_diameter_deg = {field_diameter_deg!r} must lie in (0, 180]")
    if eyes not in (1, 2):
        raise ValueError(f"eyes = {eyes!r} must be 1 or 2")
    area = math.pi * (field_diameter_deg / 2.0) ** 2
    flux = lum * area * (1.0 if eyes == 2 else 0.1)
    p = (flux / 846.0) ** 0.41
    d_sd = 7.75 - 5.75 * p / (p + 2.0)
    d_u = d_sd + (age_years - WY_REFERENCE_AGE) * (0.02132 - 0.009562 * d_sd)
    return float(d_u) if np.ndim(d_u) == 0 else d_u


class DistributionOverride(_Table):
    """A study's change to one parameter's distribution (unset fields keep the library's)."""

    distribution: Literal["normal", "uniform"] | None = None
    mean: float | None = None
    sd: float | None = None
    bounds: tuple[float, float] | None = None

    @model_validator(mode="after")
    def _spread(self) -> DistributionOverride:
        if self.sd is not None and self.sd < 0:
            raise ValueError(f"sd = {self.sd!r}: a spread must be ≥ 0")
        if self.bounds is not None and not self.bounds[0] < self.bounds[1]:
            raise ValueError(f"bounds = {list(self.bounds)!r}: the lower must be below the upper")
        return self


class Population(_Table):
    """A study file's ``[population]`` table (module docstring): how many people, their seed,
    the conditions (ambient level, adapting field, age), which parameters vary and any change
    to their distributions. Refused: an unknown parameter, an unknown ambient level, a negative
    spread, bounds or a mean outside the parameter's physical range (each naming the field)."""

    size: int = Field(50, ge=1, le=100_000)
    seed: int = Field(0, ge=0, lt=2**63)
    ambient: str | float = "display"
    field_diameter_deg: float = Field(100.0, gt=0.0, le=180.0)
    age_years: float = Field(WY_REFERENCE_AGE, ge=1.0, le=100.0)
    eyes_adapted: Literal[1, 2] = 2
    parameters: list[str] | None = None
    distributions: dict[str, DistributionOverride] = {}

    @model_validator(mode="after")
    def _known(self) -> Population:
        for k, name in enumerate(self.parameters or []):
            if name not in PARAMETERS:
                raise ValueError(
                    f"parameters.{k} = {name!r} is not a population parameter "
                    f"({', '.join(PARAMETERS)})"
                )
        if isinstance(self.ambient, str) and self.ambient not in AMBIENT_LEVELS:
            raise ValueError(
                f"ambient = {self.ambient!r} is not a named level "
                f"({', '.join(AMBIENT_LEVELS)}); or give a luminance in cd/m²"
            )
        if not isinstance(self.ambient, str) and not (0 <= self.ambient <= 1e6):
            raise ValueError(f"ambient = {self.ambient!r} cd/m² must lie in 0 … 1e6")
        for name, over in self.distributions.items():
            if name not in PARAMETERS:
                raise ValueError(
                    f"distributions.{name}: {name!r} is not a population parameter "
                    f"({', '.join(PARAMETERS)})"
                )
            lo, hi = _data()[name]["physical"]
            if over.bounds is not None and not (lo <= over.bounds[0] and over.bounds[1] <= hi):
                raise ValueError(
                    f"distributions.{name}.bounds = {list(over.bounds)!r} lies outside the "
                    f"physical range [{lo:g}, {hi:g}]"
                )
            if over.mean is not None and not lo <= over.mean <= hi:
                raise ValueError(
                    f"distributions.{name}.mean = {over.mean!r} lies outside the physical "
                    f"range [{lo:g}, {hi:g}]"
                )
        return self

    @property
    def luminance_cd_m2(self) -> float:
        """The adapting luminance (cd/m²): the named level's or the number given."""
        return AMBIENT_LEVELS[self.ambient] if isinstance(self.ambient, str) else self.ambient

    @property
    def used(self) -> tuple[str, ...]:
        """The parameters sampled (all of :data:`PARAMETERS` unless ``parameters`` is set)."""
        return PARAMETERS if self.parameters is None else tuple(self.parameters)


def parse_population(data: Any, origin: str = "population") -> Population:
    """A :class:`Population` from plain data (a study file's ``[population]`` table); the first
    validation error as one-line SceneError naming the field and value."""
    try:
        return Population.model_validate(data)
    except ValidationError as exc:
        raise validation_error(exc, data, origin) from None


@dataclass(frozen=True)
class Distribution:
    """One parameter's resolved distribution: ``kind`` "normal" (``mean``, ``sd``, truncated
    to [``low``, ``high``]) or "uniform" on [``low``, ``high``]; ``target`` what it sets."""

    name: str
    kind: str
    mean: float
    sd: float
    low: float
    high: float
    target: str

    def moments(self) -> tuple[float, float]:
        """The mean and SD people actually have: the truncated normal's (Johnson, Kotz &
        Balakrishnan, Continuous Univariate Distributions 1, 2nd ed., §10.1: with α, β the
        bounds in SDs from the mean, Z = Φ(β) − Φ(α), mean μ + σ(φ(α) − φ(β))/Z, variance
        σ²[1 + (αφ(α) − βφ(β))/Z − ((φ(α) − φ(β))/Z)²]), or the uniform's ((lo + hi)/2,
        (hi − lo)/√12). They differ from ``mean``, ``sd`` where a bound lies near the mean:
        the pupil at bright ambient levels (population.toml)."""
        if self.kind == "uniform" or self.sd == 0:
            return self.mean, self.sd
        al, be = (self.low - self.mean) / self.sd, (self.high - self.mean) / self.sd
        pa, pb = (
            math.exp(-al * al / 2) / math.sqrt(2 * math.pi),
            math.exp(-be * be / 2) / math.sqrt(2 * math.pi),
        )
        z = float(ndtr(be) - ndtr(al))
        shift = (pa - pb) / z
        var = self.sd**2 * (1 + (al * pa - be * pb) / z - shift * shift)
        return self.mean + self.sd * shift, math.sqrt(var)

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """The value at cumulative probability ``u`` (any shape, in [0, 1)): the inverse CDF of
        the truncated normal, Φ⁻¹(Φ(a) + u·(Φ(b) − Φ(a))) scaled, or of the uniform."""
        u = np.asarray(u, dtype=float)
        if self.kind == "uniform":
            return self.low + u * (self.high - self.low)
        if self.sd == 0:
            return np.full_like(u, self.mean)
        a = ndtr((self.low - self.mean) / self.sd)
        b = ndtr((self.high - self.mean) / self.sd)
        x = self.mean + self.sd * ndtri(a + u * (b - a))
        return np.clip(x, self.low, self.high)


def _skin_bounds(table: dict[str, list[float]], wavelength_nm: float) -> tuple[float, float]:
    """Skin's bounds at ``wavelength_nm``: linear between the measured wavelengths, the
    nearer one's outside them (population.toml)."""
    pts = sorted((float(k), v) for k, v in table.items())
    if wavelength_nm <= pts[0][0]:
        return tuple(pts[0][1])  # type: ignore[return-value]
    if wavelength_nm >= pts[-1][0]:
        return tuple(pts[-1][1])  # type: ignore[return-value]
    for (w0, b0), (w1, b1) in zip(pts, pts[1:], strict=False):
        if w0 <= wavelength_nm <= w1:
            t = (wavelength_nm - w0) / (w1 - w0)
            return (b0[0] + t * (b1[0] - b0[0]), b0[1] + t * (b1[1] - b0[1]))
    raise AssertionError("unreachable")  # pragma: no cover


def resolved_distributions(scene: Scene, population: Population) -> dict[str, Distribution]:
    """Every parameter's distribution for this scene (its wavelength sets the skin's) and
    these conditions (the pupil's mean from :func:`watson_yellott_pupil_mm`), with the study's
    changes applied. SceneError naming ``population.distributions.<name>`` when the result is
    inconsistent (a normal's mean outside its bounds)."""
    out = {}
    for name in PARAMETERS:
        entry = _data()[name]
        over = population.distributions.get(name, DistributionOverride())
        kind = over.distribution or entry["distribution"]
        if "bounds_by_wavelength" in entry:
            low, high = _skin_bounds(entry["bounds_by_wavelength"], scene.wavelength_nm)
        else:
            low, high = entry["bounds"]
        if over.bounds is not None:
            low, high = over.bounds
        mean = entry.get("mean", (low + high) / 2)
        if mean == "watson_yellott_2012":
            mean = watson_yellott_pupil_mm(
                population.luminance_cd_m2,
                population.field_diameter_deg,
                population.age_years,
                population.eyes_adapted,
            )
        if over.mean is not None:
            mean = over.mean
        sd = over.sd if over.sd is not None else entry.get("sd", 0.0)
        if kind == "normal" and not low <= mean <= high:
            raise SceneError(
                f"the mean {mean:.4g} lies outside the bounds [{low:g}, {high:g}]",
                field=f"population.distributions.{name}",
            )
        if kind == "uniform":
            mean, sd = (low + high) / 2, (high - low) / math.sqrt(12)
        out[name] = Distribution(name, kind, float(mean), float(sd), low, high, entry["target"])
    return out


@dataclass
class Person:
    """One sampled person: ``index`` in the population, ``values`` (every parameter's sampled
    value, used or not, by name), ``overrides`` (dotted scene paths → values, for
    :func:`eyelume.scene.io.apply_overrides` on the base scene), ``scene`` (the base scene with
    them applied; None when not built), ``not_applied`` (used parameters the scene has nothing
    for: the lid aperture in a scene without lids)."""

    index: int
    values: dict[str, float]
    overrides: dict[str, Any]
    scene: Scene | None = None
    not_applied: tuple[str, ...] = field(default=())


#: Redraws of a person's cornea (radius, asphericity, astigmatism) before giving up.
_CORNEA_TRIES = 100

#: The corneal parameters redrawn together when a person's cornea cannot exist.
_CORNEA = ("corneal_radius_mm", "corneal_asphericity_q")
_ASTIGMATISM = ("corneal_astigmatism_j0_d", "corneal_astigmatism_j45_d")

#: Keratometric index's power scale (mm·D): K = 337.5 / R, the standard keratometer calibration
#: n = 1.3375 ((n − 1) × 1000), in which corneal astigmatism is reported.
KERATOMETRIC_MM_D = 337.5


def corneal_split(radius_mm: float, j0_d: float, j45_d: float) -> tuple[float, float, float]:
    """(flat radius mm, steep radius mm, TABO axis of the flat meridian deg) of a cornea whose
    mean keratometric power is K = 337.5 / ``radius_mm`` and whose astigmatism is the power
    vector (J0, J45) (D): cylinder C = 2 √(J0² + J45²), flat meridian θ = ½ atan2(J45, J0)
    (so J0 = (C/2) cos 2θ > 0 is with-the-rule, θ near 0°), K_flat,steep = K ∓ C/2.

    Examples
    --------
    >>> [round(x, 4) for x in corneal_split(7.8, 0.5, 0.0)]
    [7.8912, 7.7109, 0.0]
    """
    k = KERATOMETRIC_MM_D / radius_mm
    c = 2.0 * math.hypot(j0_d, j45_d)
    axis = math.degrees(0.5 * math.atan2(j45_d, j0_d)) % 180.0
    return KERATOMETRIC_MM_D / (k - c / 2), KERATOMETRIC_MM_D / (k + c / 2), axis


def _mean_radius(scene: Scene) -> float:
    """The base cornea's mean-power radius 337.5 / ((K_flat + K_steep)/2) (its radius when it is
    rotationally symmetric)."""
    front = scene.eye.surfaces[0]
    steep = scene.eye.cornea.radius_steep_mm
    if steep is None:
        return front.radius_mm
    return 2.0 / (1.0 / front.radius_mm + 1.0 / steep)


def _person_cornea(scene: Scene, values: dict[str, float], used: tuple[str, ...]):
    """(flat radius, steep radius or None, Q of the flat meridian, axis or None) of the person's
    anterior cornea: the sampled radius (a mean-power radius) split by the sampled astigmatism
    (a component not sampled is 0; :func:`corneal_split`), or the base scene's."""
    front = scene.eye.surfaces[0]
    conic = values["corneal_asphericity_q"] if "corneal_asphericity_q" in used else front.conic
    if not set(_ASTIGMATISM) & set(used):
        radius = values["corneal_radius_mm"] if "corneal_radius_mm" in used else front.radius_mm
        return radius, scene.eye.cornea.radius_steep_mm, conic, None
    radius = values["corneal_radius_mm"] if "corneal_radius_mm" in used else _mean_radius(scene)
    j0, j45 = (values[n] if n in used else 0.0 for n in _ASTIGMATISM)
    flat, steep, axis = corneal_split(radius, j0, j45)
    return flat, steep, conic, axis


def _cornea_fits(scene: Scene, values: dict[str, float], used: tuple[str, ...]) -> bool:
    """Whether the person's anterior cornea exists at its semi-diameter h (the limbus) and its
    sag there lies in front of the iris plane (:func:`eyelume.scene.eye.iris_root_radius`'s
    condition): a steep, oblate cornea (R ≈ 6.8 mm, Q ≈ +0.25) does not. An astigmatic one
    also in its steep meridian (the conic of R_steep and Q_steep = (1 + Q) R_steep / R_flat −
    1, Q_steep in −1.5 … 1), that meridian's edge at most 0.8 × the limbus mismatch
    (:data:`eyelume.scene.eye.LIMBUS_MISMATCH_MM`) deeper than the flat one's (the sclera is
    fitted through the flat edge: a margin for the exact check of
    :func:`eyelume.scene.eye.check_eye_geometry`) and in front of the posterior cornea."""
    eye = scene.eye
    h = eye.surfaces[0].semi_diameter_mm
    flat, steep, conic, _ = _person_cornea(scene, values, used)
    s = _conic_sag(flat, conic, h)
    z_iris = sum(x.thickness_mm for x in eye.surfaces[: eye.iris_surface])
    if math.isnan(s) or s >= z_iris:
        return False
    if steep is None or steep == flat:
        return True
    q_steep = (1.0 + conic) * steep / flat - 1.0
    s_steep = _conic_sag(steep, q_steep, h)
    if not (-1.5 <= q_steep <= 1.0) or math.isnan(s_steep) or s_steep >= z_iris:
        return False
    if s_steep - s > 0.8 * LIMBUS_MISMATCH_MM:
        return False
    back = eye.surfaces[1]
    for r in np.linspace(0.0, min(h, back.semi_diameter_mm), 9)[1:]:
        behind = eye.surfaces[0].thickness_mm + _conic_sag(back.radius_mm, back.conic, r)
        if not _conic_sag(steep, q_steep, r) < behind:
            return False
    return True


def _lid_indices(scene: Scene) -> tuple[int, int] | None:
    names = [t.name for t in scene.face.tissues]
    if "upper eyelid" in names and "lower eyelid" in names:
        return names.index("upper eyelid"), names.index("lower eyelid")
    return None


def _lid_overrides(scene: Scene, v: float, over: dict[str, Any]) -> bool:
    """Open the lids to the aperture ``v`` (mm) in ``over``: both margins (their
    ``clip_z_mm[0]``) scaled in proportion; False (nothing set) for a scene without the two."""
    lids = _lid_indices(scene)
    if lids is None:
        return False
    up, lo = (scene.face.tissues[k] for k in lids)
    scale = v / (up.clip_z_mm[0] + lo.clip_z_mm[0])
    for k, t in zip(lids, (up, lo), strict=True):
        over[f"face.tissues.{k}.clip_z_mm"] = [t.clip_z_mm[0] * scale, t.clip_z_mm[1]]
    return True


def _lash_overrides(scene: Scene, target: str, v: float, over: dict[str, Any]) -> bool:
    """Switch the lashes on with a sampled ``lashes.<field>`` (a count rounded) in ``over``;
    False (nothing set) when the scene has not the lid they grow on (``face.lashes.lid``, a
    sphere, on an enabled face)."""
    face = scene.face
    if not face.enabled or not any(
        t.name == face.lashes.lid and t.shape == "sphere" for t in face.tissues
    ):
        return False
    key = target.removeprefix("lashes.")
    over["face.lashes.enabled"] = True
    over[f"face.lashes.{key}"] = round(v) if key == "count" else v
    return True


def _overrides(
    scene: Scene, values: dict[str, float], used: tuple[str, ...], dists: dict[str, Distribution]
) -> tuple[dict[str, Any], tuple[str, ...]]:
    over: dict[str, Any] = {}
    skipped = []
    slip = list(scene.head_offset_mm)
    for name in used:
        target, v = dists[name].target, values[name]
        if target == "none":
            skipped.append(name)
        elif target.startswith("slip."):
            slip["xyz".index(target[-1])] += v
            over["head_offset_mm"] = list(slip)
        elif target.startswith("corneal_astigmatism."):
            flat, steep, _, axis = _person_cornea(scene, values, used)
            over["eye.surfaces.0.radius_mm"] = flat
            over["eye.cornea.radius_steep_mm"] = steep
            over["eye.cornea.axis_deg"] = axis
        elif target == "kappa.horizontal":
            over["eye.kappa_deg"] = [v, scene.eye.kappa_deg[1]]
        elif target == "lid_aperture" or target.startswith("lashes."):
            applied = (
                _lid_overrides(scene, v, over)
                if target == "lid_aperture"
                else _lash_overrides(scene, target, v, over)
            )
            if not applied:
                skipped.append(name)
        else:
            over[target] = v
    if "eye.surfaces.0.radius_mm" in over or "eye.surfaces.0.conic" in over:
        over["eye.sclera_radius_mm"] = _sclera_radius(scene, over)
    return over, tuple(skipped)


def _conic_sag(radius: float, conic: float, r: float) -> float:
    """Sag (mm) of a conic of vertex ``radius`` and conic constant at height ``r``:
    z = c r² / (1 + √(1 − (1 + k) c² r²)), c = 1/radius; NaN where the surface has no point."""
    c = 1.0 / radius
    disc = 1.0 - (1.0 + conic) * c * c * r * r
    return c * r * r / (1.0 + math.sqrt(disc)) if disc >= 0 else math.nan


def _sclera_radius(scene: Scene, over: dict[str, Any]) -> float:
    """The sclera radius when the anterior cornea changes. The sclera passes through the limbus
    (the cornea's edge at its semi-diameter h, sag s), so its centre lies z_c = s + √(ρ² − h²)
    behind the vertex. A flatter cornea (smaller sag) would bring the eyeball's centre forward
    and the retina out of it: the centre is kept, ρ' = √(h² + (z_c − s')²). A steeper one keeps
    ρ (the centre moves back by the sag's change, < 0.5 mm within the bounds): ρ' =
    max(ρ, √(h² + (z_c − s')²)). A cornea with no point at its edge keeps the base radius (the
    scene's own check then names it)."""
    front = scene.eye.surfaces[0]
    h = front.semi_diameter_mm
    s0 = _conic_sag(front.radius_mm, front.conic, h)
    z_c = s0 + math.sqrt(max(scene.eye.sclera_radius_mm**2 - h * h, 0.0))
    s1 = _conic_sag(
        over.get("eye.surfaces.0.radius_mm", front.radius_mm),
        over.get("eye.surfaces.0.conic", front.conic),
        h,
    )
    if math.isnan(s0) or math.isnan(s1):
        return scene.eye.sclera_radius_mm
    return max(scene.eye.sclera_radius_mm, math.hypot(h, z_c - s1))


def sample_people(
    scene: Scene,
    n: int,
    seed: int,
    population: Population | None = None,
    *,
    start: int = 0,
    build_scenes: bool = True,
) -> list[Person]:
    """People ``start`` … ``start + n − 1`` of the population of ``seed`` on ``scene``.

    Parameters
    ----------
    scene
        The base scene (its wavelength picks the skin's distribution; its lids and head offset
        are what the lid aperture and slip change).
    n, seed
        How many people, and the population's seed (≥ 0).
    population
        Conditions, parameters and distribution changes (default: ``Population()``: every
        parameter, the ``display`` ambient level); its ``size`` and ``seed`` are not used here
        (:func:`sample_population` uses them).
    start
        The first person's index: ``sample_people(s, 10, seed, start=40)`` are people 40–49 of
        any larger draw (chunks and workers give the same people).
    build_scenes
        Also validate each person's scene (``Person.scene``); False returns the values and
        overrides only (fast, for moments).

    Raises
    ------
    SceneError
        ``n`` < 0, a negative seed or start; a person whose scene cannot exist (naming the
        person, the field and the value); a cornea redrawn 100 times without fitting; the
        scene has no lids but ``lid_aperture_mm`` is listed explicitly in
        ``population.parameters``.
    """
    pop = population if population is not None else Population()
    if n < 0 or start < 0 or seed < 0:
        raise SceneError(f"n = {n}, start = {start}, seed = {seed}: each must be ≥ 0")
    if (
        pop.parameters is not None
        and "lid_aperture_mm" in pop.parameters
        and _lid_indices(scene) is None
    ):
        raise SceneError(
            "the scene has no 'upper eyelid' and 'lower eyelid' face tissues to open",
            field="population.parameters",
            value="lid_aperture_mm",
        )
    dists = resolved_distributions(scene, pop)
    children = np.random.SeedSequence(seed).spawn(start + n)[start:]
    people = []
    for i, child in enumerate(children, start=start):
        rng = np.random.default_rng(child)
        u = rng.random(len(PARAMETERS))
        values = {name: float(dists[name].ppf(u[k])) for k, name in enumerate(PARAMETERS)}
        redraw = _CORNEA + (_ASTIGMATISM if set(_ASTIGMATISM) & set(pop.used) else ())
        for _ in range(_CORNEA_TRIES):
            if not (set(redraw) & set(pop.used)) or _cornea_fits(scene, values, pop.used):
                break
            for name in redraw:
                values[name] = float(dists[name].ppf(rng.random()))
        else:
            raise SceneError(
                f"person {i}: {_CORNEA_TRIES} draws of the anterior cornea's radius, "
                "asphericity and astigmatism all make a cornea that does not reach its limbus "
                "in front of the iris; narrow their bounds",
                field="population.distributions.corneal_radius_mm / corneal_asphericity_q"
                + (" / corneal_astigmatism_j0_d / _j45_d" if len(redraw) > 2 else ""),
            )
        over, skipped = _overrides(scene, values, pop.used, dists)
        person = Person(i, values, over, None, skipped)
        if build_scenes:
            try:
                person.scene = apply_overrides(scene, over)
            except EyelumeError as exc:
                raise SceneError(f"person {i} of population seed {seed}: {exc}") from None
        people.append(person)
    return people


def load_population_file(path) -> Population:
    """A :class:`Population` from a TOML file: its ``[population]`` table (a study file serves)
    or, without one, the whole file as that table. SceneError naming the file: unreadable, not
    TOML, or a field refused (:func:`parse_population`)."""
    from pathlib import Path

    from eyelume.scene.textfile import decode_text

    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise SceneError(f"population file {p}: {exc.strerror or exc}") from None
    text = decode_text(raw, p, SceneError).lstrip("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"population file {p}: not valid TOML: {exc}") from None
    table = data.get("population", data)
    if not isinstance(table, dict):
        raise SceneError("must be a table", file=f"population file {p}", field="population")
    return parse_population(table, origin=f"population file {p}")


def sample_population(scene: Scene, population: Population, **kw: Any) -> list[Person]:
    """:func:`sample_people` with the population's own ``size`` and ``seed``."""
    return sample_people(scene, population.size, population.seed, population, **kw)
