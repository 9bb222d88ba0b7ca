"""The schematic-eye library and the ocular media's near-infrared dispersion.

Data (with their sources, in the files): ``presets/eyes/eye_models.toml`` — the Arizona eye
(the paper's Table 1), Escudero-Sanz & Navarro 1999 and the Gullstrand–Le Grand full
theoretical eye (Le Grand & El Hage 1980), each a list of surfaces (radius, conic constant,
thickness, medium after it), its dispersion law and its pupil's surface;
``presets/eyes/ocular_dispersion.toml`` — Atchison & Smith's (JOSA A 22:29, 2005) Cauchy fits
for cornea, aqueous, lens and vitreous over 400–1060 nm, and the tear film's index.

This module sits below :mod:`eyelume.scene.model` (which fills an eye's surfaces from here when
a scene names ``eye.model`` without writing them) and imports nothing of eyelume's.
"""

from __future__ import annotations

import copy
import math
import tomllib
from functools import cache
from importlib import resources
from typing import Any

__all__ = [
    "DISPERSION_RANGE_NM",
    "MEDIA",
    "atchison_smith_index",
    "eye_model_names",
    "eye_model_data",
    "ocular_index",
    "tear_film_index",
    "tear_film_reflectance",
]

_EYES = "eyelume.scene.presets.eyes"

#: The media Atchison & Smith (2005) fit, in the order light meets them.
MEDIA = ("cornea", "aqueous", "lens", "vitreous")


@cache
def _read(name: str) -> dict[str, Any]:
    with resources.as_file(resources.files(_EYES) / name) as path:
        return tomllib.loads(path.read_text(encoding="utf-8"))


def _dispersion() -> dict[str, Any]:
    return _read("ocular_dispersion.toml")


#: The wavelengths (nm) over which Atchison & Smith's fits hold, (low, high).
DISPERSION_RANGE_NM: tuple[float, float] = tuple(_dispersion()["range_nm"])  # type: ignore[assignment]


def eye_model_names() -> list[str]:
    """The names a scene's ``eye.model`` may take to draw its surfaces from the library."""
    return sorted(_read("eye_models.toml"))


def eye_model_data(name: str) -> dict[str, Any]:
    """A fresh copy of library eye ``name``'s fields (``surfaces``, ``iris_surface``,
    ``dispersion``, ``reference_wavelength_nm``; ``source`` is dropped: it stays in the file).

    Raises
    ------
    KeyError
        ``name`` is not in the library (:func:`eye_model_names`).
    """
    data = copy.deepcopy(_read("eye_models.toml")[name])
    data.pop("source", None)
    return data


def _check_range(wavelength_nm: float, field: str) -> None:
    lo, hi = DISPERSION_RANGE_NM
    if not (math.isfinite(wavelength_nm) and lo <= wavelength_nm <= hi):
        raise ValueError(
            f"{field} = {wavelength_nm!r} nm lies outside the ocular dispersion model's range "
            f"{lo:g}-{hi:g} nm (Atchison & Smith 2005)"
        )


def atchison_smith_index(medium: str, wavelength_nm: float) -> float:
    """Atchison & Smith's (2005) index of ``medium`` (one of :data:`MEDIA`) at
    ``wavelength_nm``: n = A + B/λ² + C/λ⁴ + D/λ⁶, λ in µm (their Gullstrand-number-1 level:
    1.376, 1.336, 1.406, 1.336 at 555 nm).

    Raises
    ------
    ValueError
        The wavelength lies outside the fits' 400–1060 nm (:data:`DISPERSION_RANGE_NM`), one
        line naming it; KeyError for an unknown medium.

    Examples
    --------
    >>> round(atchison_smith_index("cornea", 555.0), 6)
    1.376
    """
    _check_range(wavelength_nm, "wavelength_nm")
    c = _dispersion()["media"][medium]
    x = 1.0 / (wavelength_nm * 1e-3) ** 2
    return c["A"] + x * (c["B"] + x * (c["C"] + x * c["D"]))


def ocular_index(medium: str, n_ref: float, reference_wavelength_nm: float, wavelength_nm: float):
    """Index at ``wavelength_nm`` of a medium whose model index is ``n_ref`` at
    ``reference_wavelength_nm``, dispersed as Atchison & Smith's ``medium`` scaled to its level:

        n(λ) = n_ref + (n_ref − 1) / (n_AS(λ_ref) − 1) · (n_AS(λ) − n_AS(λ_ref)),

    so n(λ_ref) = n_ref exactly (the scaling: see ``ocular_dispersion.toml``).

    Raises
    ------
    ValueError
        Either wavelength outside 400–1060 nm (one line naming it).
    """
    a_ref = atchison_smith_index(medium, reference_wavelength_nm)
    return n_ref + (n_ref - 1.0) / (a_ref - 1.0) * (
        atchison_smith_index(medium, wavelength_nm) - a_ref
    )


def tear_film_index(wavelength_nm: float) -> float:
    """The precorneal tear film's index at ``wavelength_nm``: 1.33698 at 589.3 nm (Craig et al.
    1995) dispersed as the aqueous humour (:func:`ocular_index`; ASSUMPTION in the data file).
    About 1.330 at 850 nm."""
    t = _dispersion()["tear_film"]
    return ocular_index(t["dispersion_of"], t["n_ref"], t["reference_wavelength_nm"], wavelength_nm)


def tear_film_reflectance(wavelength_nm: float) -> float:
    """The cornea's glint reflectance from its tear film at normal incidence (Fresnel, air to
    tears): R = ((n − 1)/(n + 1))², n = :func:`tear_film_index` — about 2.0 % at 850 nm.

    Raises
    ------
    ValueError
        The wavelength lies outside 400–1060 nm.
    """
    n = tear_film_index(wavelength_nm)
    return ((n - 1.0) / (n + 1.0)) ** 2
