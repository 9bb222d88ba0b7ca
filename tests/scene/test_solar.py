"""The stored ASTM G173-03 spectra against the standard's published totals, and what they say
about 850 against 940 nm."""

from __future__ import annotations

import numpy as np
import pytest

from eyelume.scene.solar import solar_spectrum


@pytest.mark.parametrize(
    ("name", "total_w_m2"),
    # ASTM G173-03's integrals over 280-4000 nm (the standard and NREL's page): 1000.4 W/m²
    # global tilt, 900.1 W/m² direct + circumsolar, 1348 W/m² extraterrestrial (AM0).
    [("am1.5-global", 1000.4), ("am1.5-direct", 900.1), ("extraterrestrial", 1348.0)],
)
def test_integral_is_the_published_total(name, total_w_m2):
    lam, e = solar_spectrum(name)
    assert lam.shape == (2002,) and lam[0] == 280.0 and lam[-1] == 4000.0
    assert np.all(np.diff(lam) > 0)
    # the trapezoid rule on the native grid is how the totals are formed; the published
    # totals are rounded to 0.1 W/m² (1 W/m² for AM0)
    assert np.trapezoid(e, lam) == pytest.approx(total_w_m2, abs=0.1 if total_w_m2 < 1300 else 1)


def test_rows_are_the_published_ones():
    """A few rows against NREL's ASTMG173.csv as read independently (pvlib-python's copy)."""
    lam, glob = solar_spectrum("am1.5-global")
    _, direct = solar_spectrum("am1.5-direct")
    rows = {850.0: (0.89372, 0.829), 940.0: (0.47181, 0.44411), 1666.0: (0.17884, 0.17411)}
    for wl, (g, d) in rows.items():
        k = int(np.searchsorted(lam, wl))
        assert lam[k] == wl
        assert (glob[k], direct[k]) == (g, d)


def test_sunlight_is_about_three_times_weaker_at_940_nm_than_at_850_nm():
    """The water band at 940 nm, as the table says it: over 20 nm bands (840-860 against
    930-950 nm, an LED's width) the direct beam is 3.16× weaker at 940 nm; over 40 nm bands
    2.31× (the band's edges are less deep); 1.87× at the two wavelengths alone."""
    lam, e = solar_spectrum("am1.5-direct")

    def band(lo, hi):
        m = (lam >= lo) & (lam <= hi)
        return np.trapezoid(e[m], lam[m])

    assert band(840, 860) / band(930, 950) == pytest.approx(3.156, abs=1e-3)
    assert band(830, 870) / band(920, 960) == pytest.approx(2.311, abs=1e-3)
    k850, k940 = np.searchsorted(lam, [850.0, 940.0])
    assert e[k850] / e[k940] == pytest.approx(1.867, abs=1e-3)
