"""The reference solar spectra (ASTM G173-03, AM1.5) that ``ambient.sun`` shines with.

The table ``presets/solar/astm_g173_03.csv`` holds the standard's 2002 rows, 280–4000 nm, in
W m⁻² nm⁻¹, copied unchanged from NREL's distribution of it (its source stated in the file).
Description only: how the sensor counts sunlight is :func:`eyelume.detectors.sensor.sunlight_band`.
"""

from __future__ import annotations

from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np

from eyelume.scene.model import SOLAR_SPECTRA
from eyelume.scene.textfile import read_csv_table

__all__ = ["SOLAR_TABLE", "solar_spectrum"]

#: The file of the ASTM G173-03 spectra, in ``eyelume/scene/presets/solar/``.
SOLAR_TABLE = "astm_g173_03.csv"
_COLUMNS = (
    "wavelength_nm",
    "extraterrestrial_w_m2_nm",
    "global_tilt_w_m2_nm",
    "direct_circumsolar_w_m2_nm",
)


@cache
def _table() -> np.ndarray:
    where = Path(str(resources.files("eyelume.scene.presets") / "solar" / SOLAR_TABLE))
    return read_csv_table(where, "ambient.sun.spectrum", _COLUMNS)


def solar_spectrum(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The spectral irradiance of the named spectrum (:data:`eyelume.scene.model.SOLAR_SPECTRA`,
    or ``"extraterrestrial"``): (wavelengths (2002,) nm, E_λ (2002,) W m⁻² nm⁻¹), ASTM G173-03
    at its native grid (0.5 nm to 400 nm, 1 nm to 1700 nm, 5 nm beyond), read-only arrays.

    >>> lam, e = solar_spectrum("am1.5-global")
    >>> float(lam[0]), float(lam[-1]), round(float(np.trapezoid(e, lam)), 1)
    (280.0, 4000.0, 1000.4)

    Raises
    ------
    KeyError
        An unknown name (the scene model admits only the known ones).
    """
    column = "extraterrestrial_w_m2_nm" if name == "extraterrestrial" else SOLAR_SPECTRA[name]
    t = _table()
    lam, e = t[:, 0].copy(), t[:, _COLUMNS.index(column)].copy()
    lam.flags.writeable = e.flags.writeable = False
    return lam, e
