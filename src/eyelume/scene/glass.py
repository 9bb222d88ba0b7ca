"""Optical glass from Zemax AGF catalogs: dispersion formulas, parsing, sourced lookup.

A glass is a named dispersion formula with its vendor coefficients, read from an AGF file
(the plain-text catalog format of Zemax OpticStudio, which every glass vendor publishes).
Indices are air-relative, as catalogs give them. Wavelengths are in nanometres at this
module's interface and in micrometres only inside the formulas, where the catalogs'
coefficients expect them.

The shipped catalog, ``presets/glass/eyelume.agf``, holds the glasses of the paper's imaging
lens (Table 3) or their documented substitutes; every entry's ``GC`` line names its source.

Examples
--------
>>> cat = load_catalog()
>>> g = cat["n-sk16"]
>>> round(g.index(587.5618), 5)
1.62041
>>> g.in_range(850.0)
True
"""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from eyelume.errors import EyelumeWarning, GlassError
from eyelume.scene.textfile import decode_text

__all__ = [
    "FORMULAS",
    "SHIPPED_CATALOG",
    "Glass",
    "GlassCatalog",
    "GlassError",
    "GlassWarning",
    "conrady",
    "extended",
    "extended2",
    "extended3",
    "handbook1",
    "handbook2",
    "herzberger",
    "load_catalog",
    "schott",
    "sellmeier1",
    "sellmeier2",
    "sellmeier3",
    "sellmeier4",
    "sellmeier5",
]

SHIPPED_CATALOG = Path(__file__).resolve().parent / "presets" / "glass" / "eyelume.agf"
"""Path of the catalog that :func:`load_catalog` reads when given no file."""

_MAX_NAMES_IN_MESSAGE = 12


class GlassWarning(EyelumeWarning):
    """A catalog that loads but deserves a look: a glass named twice (the first kept), or a
    formula that misses the glass's own nd at the d line by more than :data:`ND_TOLERANCE`.
    The message is one line naming the file, the line and the glass."""


ND_TOLERANCE = 1e-4
"""Largest accepted |n_formula(587.5618 nm) − nd|. Vendors give nd to 5-6 decimals and fit
their formulas to better than 1e-5 at the d line, so a larger gap means the coefficients were
misread (a CD record cut short, a wrong formula number) or belong to another glass."""

LAMBDA_D_NM = 587.5618
"""The helium d line (nm), where catalogs state nd."""


# ---------------------------------------------------------------------------------------------
# Dispersion formulas, numbered as in AGF files (Zemax OpticStudio manual, "Glass catalogs",
# dispersion formulas 1-13). λ is the wavelength in air in micrometres, as the catalogs'
# coefficients expect; c holds the CD coefficients in file order (missing ones are 0). Each
# returns the air-relative index n (dimensionless) and accepts floats or numpy arrays.
# ---------------------------------------------------------------------------------------------


def schott(lam_um, c: Sequence[float]):
    r"""Formula 1, Schott power series.

    .. math:: n^2 = a_0 + a_1\lambda^2 + a_2\lambda^{-2} + a_3\lambda^{-4} + a_4\lambda^{-6}
              + a_5\lambda^{-8}

    Parameters
    ----------
    lam_um : float or ndarray
        Wavelength λ in micrometres.
    c : sequence of float
        ``a0 .. a5`` (CD order).

    Returns
    -------
    float or ndarray
        Refractive index n.

    Examples
    --------
    >>> float(schott(1.0, (1.0, 0.5, 0.25, 0.25, 0.125, 0.125)))
    1.5
    """
    a = _pad(c, 6)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] * w2 + _inverse_square_series(w2, a[2:]))


def sellmeier1(lam_um, c: Sequence[float]):
    r"""Formula 2, Sellmeier 1 (three resonances).

    .. math:: n^2 - 1 = \frac{K_1\lambda^2}{\lambda^2 - L_1} + \frac{K_2\lambda^2}{\lambda^2 - L_2}
              + \frac{K_3\lambda^2}{\lambda^2 - L_3}

    ``c`` is ``K1 L1 K2 L2 K3 L3`` (CD order; L in µm²). A vendor's ``B1 B2 B3 C1 C2 C3`` map
    to ``K1 = B1, L1 = C1, ...``. λ in micrometres; returns n.

    Examples
    --------
    >>> float(sellmeier1(1.0, (0.625, 0.5)))
    1.5
    """
    return np.sqrt(1.0 + _sellmeier_sum(lam_um * lam_um, _pad(c, 6), 3))


def herzberger(lam_um, c: Sequence[float]):
    r"""Formula 3, Herzberger.

    .. math:: n = A + BL + CL^2 + D\lambda^2 + E\lambda^4 + F\lambda^6,
              \qquad L = \frac{1}{\lambda^2 - 0.028}

    ``c`` is ``A B C D E F``; λ in micrometres (0.028 µm² is part of the formula); returns n.

    Examples
    --------
    >>> float(herzberger(1.0, (1.5,)))
    1.5
    """
    a = _pad(c, 6)
    w2 = lam_um * lam_um
    big_l = 1.0 / (w2 - 0.028)
    return a[0] + a[1] * big_l + a[2] * big_l**2 + a[3] * w2 + a[4] * w2**2 + a[5] * w2**3


def sellmeier2(lam_um, c: Sequence[float]):
    r"""Formula 4, Sellmeier 2.

    .. math:: n^2 - 1 = A + \frac{B_1\lambda^2}{\lambda^2 - \lambda_1^2}
              + \frac{B_2}{\lambda^2 - \lambda_2^2}

    ``c`` is ``A B1 λ1 B2 λ2`` (λ1, λ2 in µm; note the second term has no λ² in its numerator);
    λ in micrometres; returns n.

    Examples
    --------
    >>> float(sellmeier2(1.0, (1.25,)))
    1.5
    """
    a = _pad(c, 5)
    w2 = lam_um * lam_um
    return np.sqrt(1.0 + a[0] + a[1] * w2 / (w2 - a[2] ** 2) + a[3] / (w2 - a[4] ** 2))


def conrady(lam_um, c: Sequence[float]):
    r"""Formula 5, Conrady.

    .. math:: n = n_0 + \frac{A}{\lambda} + \frac{B}{\lambda^{3.5}}

    ``c`` is ``n0 A B``; λ in micrometres; returns n.

    Examples
    --------
    >>> float(conrady(1.0, (1.5,)))
    1.5
    """
    a = _pad(c, 3)
    return a[0] + a[1] / lam_um + a[2] / lam_um**3.5


def sellmeier3(lam_um, c: Sequence[float]):
    r"""Formula 6, Sellmeier 3 (four resonances).

    .. math:: n^2 - 1 = \sum_{i=1}^{4} \frac{K_i\lambda^2}{\lambda^2 - L_i}

    ``c`` is ``K1 L1 K2 L2 K3 L3 K4 L4`` (L in µm²); λ in micrometres; returns n.

    Examples
    --------
    >>> float(sellmeier3(1.0, (0.625, 0.5)))
    1.5
    """
    return np.sqrt(1.0 + _sellmeier_sum(lam_um * lam_um, _pad(c, 8), 4))


def handbook1(lam_um, c: Sequence[float]):
    r"""Formula 7, Handbook of Optics 1.

    .. math:: n^2 = A + \frac{B}{\lambda^2 - C} - D\lambda^2

    ``c`` is ``A B C D`` (C in µm²); λ in micrometres; returns n.

    Examples
    --------
    >>> float(handbook1(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 4)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] / (w2 - a[2]) - a[3] * w2)


def handbook2(lam_um, c: Sequence[float]):
    r"""Formula 8, Handbook of Optics 2.

    .. math:: n^2 = A + \frac{B\lambda^2}{\lambda^2 - C} - D\lambda^2

    ``c`` is ``A B C D`` (C in µm²); λ in micrometres; returns n.

    Examples
    --------
    >>> float(handbook2(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 4)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] * w2 / (w2 - a[2]) - a[3] * w2)


def sellmeier4(lam_um, c: Sequence[float]):
    r"""Formula 9, Sellmeier 4.

    .. math:: n^2 = A + \frac{B\lambda^2}{\lambda^2 - C} + \frac{D\lambda^2}{\lambda^2 - E}

    ``c`` is ``A B C D E`` (C, E in µm²); λ in micrometres; returns n.

    Examples
    --------
    >>> float(sellmeier4(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 5)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] * w2 / (w2 - a[2]) + a[3] * w2 / (w2 - a[4]))


def extended(lam_um, c: Sequence[float]):
    r"""Formula 10, Extended (Schott series to λ⁻¹²).

    .. math:: n^2 = a_0 + a_1\lambda^2 + a_2\lambda^{-2} + a_3\lambda^{-4} + a_4\lambda^{-6}
              + a_5\lambda^{-8} + a_6\lambda^{-10} + a_7\lambda^{-12}

    ``c`` is ``a0 .. a7``; λ in micrometres; returns n.

    Examples
    --------
    >>> float(extended(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 8)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] * w2 + _inverse_square_series(w2, a[2:]))


def sellmeier5(lam_um, c: Sequence[float]):
    r"""Formula 11, Sellmeier 5 (five resonances).

    .. math:: n^2 - 1 = \sum_{i=1}^{5} \frac{K_i\lambda^2}{\lambda^2 - L_i}

    ``c`` is ``K1 L1 ... K5 L5`` (L in µm²); λ in micrometres; returns n.

    Examples
    --------
    >>> float(sellmeier5(1.0, (0.625, 0.5)))
    1.5
    """
    return np.sqrt(1.0 + _sellmeier_sum(lam_um * lam_um, _pad(c, 10), 5))


def extended2(lam_um, c: Sequence[float]):
    r"""Formula 12, Extended 2.

    .. math:: n^2 = a_0 + a_1\lambda^2 + a_2\lambda^{-2} + a_3\lambda^{-4} + a_4\lambda^{-6}
              + a_5\lambda^{-8} + a_6\lambda^4 + a_7\lambda^6

    ``c`` is ``a0 .. a7``; λ in micrometres; returns n.

    Examples
    --------
    >>> float(extended2(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 8)
    w2 = lam_um * lam_um
    return np.sqrt(
        a[0] + a[1] * w2 + _inverse_square_series(w2, a[2:6]) + a[6] * w2**2 + a[7] * w2**3
    )


def extended3(lam_um, c: Sequence[float]):
    r"""Formula 13, Extended 3.

    .. math:: n^2 = a_0 + a_1\lambda^2 + a_2\lambda^4 + a_3\lambda^{-2} + a_4\lambda^{-4}
              + a_5\lambda^{-6} + a_6\lambda^{-8} + a_7\lambda^{-10} + a_8\lambda^{-12}

    ``c`` is ``a0 .. a8``; λ in micrometres; returns n.

    Examples
    --------
    >>> float(extended3(1.0, (2.25,)))
    1.5
    """
    a = _pad(c, 9)
    w2 = lam_um * lam_um
    return np.sqrt(a[0] + a[1] * w2 + a[2] * w2**2 + _inverse_square_series(w2, a[3:]))


@dataclass(frozen=True)
class _Formula:
    name: str
    function: Callable
    n_coefficients: int


FORMULAS: dict[int, _Formula] = {
    1: _Formula("Schott", schott, 6),
    2: _Formula("Sellmeier1", sellmeier1, 6),
    3: _Formula("Herzberger", herzberger, 6),
    4: _Formula("Sellmeier2", sellmeier2, 5),
    5: _Formula("Conrady", conrady, 3),
    6: _Formula("Sellmeier3", sellmeier3, 8),
    7: _Formula("Handbook1", handbook1, 4),
    8: _Formula("Handbook2", handbook2, 4),
    9: _Formula("Sellmeier4", sellmeier4, 5),
    10: _Formula("Extended", extended, 8),
    11: _Formula("Sellmeier5", sellmeier5, 10),
    12: _Formula("Extended2", extended2, 8),
    13: _Formula("Extended3", extended3, 9),
}
"""AGF formula number -> (name, function of (λ in µm, coefficients), number of coefficients)."""


def _pad(c: Sequence[float], n: int) -> tuple[float, ...]:
    """The first ``n`` coefficients of ``c``, missing ones taken as 0 (as Zemax does)."""
    c = tuple(c)
    return c[:n] + (0.0,) * (n - len(c))


def _inverse_square_series(w2, a: tuple[float, ...]):
    """Σ a_i λ^(−2(i+1)) = a_0 λ⁻² + a_1 λ⁻⁴ + … by Horner's rule; ``w2`` is λ² in µm²."""
    inv = 1.0 / w2
    total = 0.0
    for coefficient in reversed(a):
        total = inv * (coefficient + total)
    return total


def _sellmeier_sum(w2, a: tuple[float, ...], terms: int):
    """Σ K_i λ² / (λ² − L_i) over ``terms`` pairs ``K_i, L_i`` of ``a``; ``w2`` is λ² in µm²."""
    total = 0.0
    for i in range(terms):
        total = total + a[2 * i] * w2 / (w2 - a[2 * i + 1])
    return total


# ---------------------------------------------------------------------------------------------
# Glass and catalog
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Glass:
    """One catalog glass: a dispersion formula, its coefficients and where they came from.

    Attributes
    ----------
    name : str
        Name as written in the catalog (``NM`` line).
    formula_number : int
        AGF dispersion formula number, 1-13 (see :data:`FORMULAS`).
    coefficients : tuple of float
        ``CD`` coefficients in file order (units as the formula expects, λ in µm).
    nd : float
        Catalog index at the d line, 587.5618 nm (``NM`` line), air-relative.
    vd : float
        Catalog Abbe number (nd − 1)/(nF − nC) (``NM`` line).
    wavelength_range_nm : tuple of float or None
        ``(lo, hi)`` in nm over which the catalog states the formula is valid (``LD`` line);
        None when the catalog states none (``LD 0 0``, or no ``LD`` record).
    source : str
        The ``GC`` comment: where the coefficients came from.
    catalog : str
        File name of the catalog the glass was read from.
    """

    name: str
    formula_number: int
    coefficients: tuple[float, ...]
    nd: float
    vd: float
    wavelength_range_nm: tuple[float, float] | None
    source: str
    catalog: str

    @property
    def formula(self) -> str:
        """Name of the dispersion formula, e.g. ``"Sellmeier1"``."""
        return FORMULAS[self.formula_number].name

    def index(self, wavelength_nm: float) -> float:
        """Air-relative refractive index at a wavelength.

        Evaluated by the catalog's dispersion formula at λ = ``wavelength_nm`` / 1000 µm, also
        outside :attr:`wavelength_range_nm` (check :meth:`in_range` where that matters).

        Parameters
        ----------
        wavelength_nm : float
            Wavelength in nanometres (in air, as the catalog's own).

        Returns
        -------
        float
            Refractive index n, dimensionless.

        Raises
        ------
        GlassError
            If the wavelength is not a finite positive number, or the formula gives no real
            index there (n² ≤ 0 or a pole of the formula).

        Examples
        --------
        >>> round(load_catalog()["F5"].index(850.0), 4)
        1.591
        """
        lam_nm = _checked_wavelength(wavelength_nm, self.name)
        with np.errstate(all="ignore"):
            n = float(FORMULAS[self.formula_number].function(lam_nm / 1000.0, self.coefficients))
        if not (math.isfinite(n) and n > 0.0):
            raise GlassError(
                f"glass {self.name!r} ({self.catalog}): formula {self.formula} gives no real "
                f"index at {wavelength_nm!r} nm"
            )
        return n

    def in_range(self, wavelength_nm: float) -> bool | None:
        """Whether a wavelength (nm) lies inside the catalog's stated range (ends included);
        None when the catalog states no range.

        Raises
        ------
        GlassError
            If the wavelength is not a finite positive number.
        """
        lam_nm = _checked_wavelength(wavelength_nm, self.name)
        if self.wavelength_range_nm is None:
            return None
        lo, hi = self.wavelength_range_nm
        return bool(lo <= lam_nm <= hi)


def _checked_wavelength(wavelength_nm: float, glass_name: str) -> np.float64:
    """The wavelength as a float64, or GlassError naming the value if not finite and > 0.

    float64 (not float) so that a pole of a formula gives inf instead of ZeroDivisionError.
    """
    if not isinstance(wavelength_nm, numbers.Real) or isinstance(wavelength_nm, bool):
        raise GlassError(
            f"glass {glass_name!r}: wavelength {wavelength_nm!r} is not a number (nm expected)"
        )
    lam = np.float64(wavelength_nm)
    if not (math.isfinite(lam) and lam > 0.0):
        raise GlassError(
            f"glass {glass_name!r}: wavelength {wavelength_nm!r} nm is not a finite positive number"
        )
    return lam


class GlassCatalog:
    """Glasses read from one or more AGF files, looked up by name, case-insensitively.

    When several files define the same name, the first file given wins (as in Zemax's
    catalog search order); each :class:`Glass` records the file it came from.
    """

    def __init__(self, glasses: Sequence[Glass], files: Sequence[str | Path]) -> None:
        self._glasses: dict[str, Glass] = {}
        for g in glasses:
            self._glasses.setdefault(g.name.upper(), g)
        self._files = tuple(Path(f) for f in files)

    @property
    def names(self) -> tuple[str, ...]:
        """Glass names as written in the catalogs, in file order."""
        return tuple(g.name for g in self._glasses.values())

    @property
    def files(self) -> tuple[Path, ...]:
        """The catalog files read, in search order."""
        return self._files

    def __getitem__(self, name: str) -> Glass:
        key = name.upper() if isinstance(name, str) else None
        if key in self._glasses:
            return self._glasses[key]
        which = ", ".join(f.name for f in self._files)
        noun = "catalog" if len(self._files) == 1 else "catalogs"
        have = list(self.names)
        listed = ", ".join(have[:_MAX_NAMES_IN_MESSAGE])
        if len(have) > _MAX_NAMES_IN_MESSAGE:
            listed += f", ... ({len(have) - _MAX_NAMES_IN_MESSAGE} more)"
        raise GlassError(f"glass {name!r} not found in {noun} {which} (has: {listed})")

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name.upper() in self._glasses

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __len__(self) -> int:
        return len(self._glasses)

    def __repr__(self) -> str:
        files = ", ".join(f.name for f in self._files)
        return f"GlassCatalog({len(self)} glasses from {files})"


def load_catalog(*paths: str | Path) -> GlassCatalog:
    """Read AGF glass catalogs.

    Parameters
    ----------
    *paths : str or Path
        AGF files: UTF-16 (little- or big-endian, with or without a byte-order mark, as Zemax
        and vendors write them), UTF-8 or a legacy 8-bit code page. None: the shipped
        ``eyelume.agf`` (:data:`SHIPPED_CATALOG`). Several: merged, the first file that names a
        glass wins.

    Vendors' files are read as Zemax reads them: a ``CD`` record may continue on the next lines
    (lines that start with a number), ``LD 0 0`` or no ``LD`` means no stated range, a glass
    named twice in one file keeps its first definition (with a :class:`GlassWarning`), and a
    glass whose formula misses its own nd at the d line by more than :data:`ND_TOLERANCE`
    loads with a :class:`GlassWarning` naming both values.

    Returns
    -------
    GlassCatalog

    Raises
    ------
    GlassError
        A file is missing or unreadable, holds no glass record ("not an AGF catalog"), or is
        malformed (the message names the file, the line number and the bad value).

    Examples
    --------
    >>> cat = load_catalog()
    >>> "BSM24" in cat, "bsm24" in cat
    (True, True)
    """
    files = [Path(p) for p in paths] if paths else [SHIPPED_CATALOG]
    glasses: list[Glass] = []
    for f in files:
        glasses.extend(_parse_agf(f))
    return GlassCatalog(glasses, files)


# ---------------------------------------------------------------------------------------------
# AGF parsing
# ---------------------------------------------------------------------------------------------


def _read_text(path: Path) -> str:
    """File contents decoded: UTF-16 (BOM, as Zemax writes), UTF-8 (BOM or not), else Latin-1."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise GlassError(f"glass catalog file not found: {path}") from None
    except OSError as exc:
        raise GlassError(f"glass catalog file {path} cannot be read: {exc.strerror}") from None
    return decode_text(raw, path, GlassError)


@dataclass
class _Block:
    """A glass being read: the NM fields plus what later lines add."""

    name: str
    formula_number: int
    nd: float
    vd: float
    line: int
    coefficients: tuple[float, ...] | None = None
    range_um: tuple[float, float] | None = None
    has_range: bool = False
    source: str = ""


class _AgfReader:
    """Reads one AGF file's records into :class:`_Block` s, one method per record kind.

    The records eyelume reads: ``NM`` (a glass: name, formula, nd, vd), ``CD`` (its dispersion
    coefficients, continued on following lines that start with a number), ``LD`` (its stated
    wavelength range, ``LD 0 0`` for none) and ``GC`` (a comment, kept as the glass's source).
    ``TD``, ``OD``, ``ED``, ``IT``, ``CC``, ``BD`` and any other record are not needed for the
    index and are passed over, as are their continuation lines. A glass named a second time in
    the file keeps its first definition: every record up to the next ``NM`` is skipped.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.blocks: list[_Block] = []
        self.seen: dict[str, int] = {}  # upper-case name -> line of its NM record
        self.last_record = ""
        self.skipping = False  # inside a glass named a second time: its records are ignored

    def bad(self, lineno: int, what: str) -> GlassError:
        """The error for a malformed line: file, line number, what is wrong."""
        return GlassError(f"{self.path}: line {lineno}: {what}")

    def number(self, tok: str, lineno: int, what: str) -> float:
        """``tok`` as a finite float, else GlassError naming ``what`` and the value."""
        try:
            x = float(tok)
        except ValueError:
            raise self.bad(lineno, f"{what} {tok!r} is not a number") from None
        if not math.isfinite(x):
            raise self.bad(lineno, f"{what} {tok!r} is not finite")
        return x

    def current(self, lineno: int, record: str) -> _Block:
        """The glass a record belongs to (the last NM), else GlassError."""
        if not self.blocks:
            raise self.bad(lineno, f"{record} record before any NM (glass name) record")
        return self.blocks[-1]

    def line(self, lineno: int, line: str) -> None:
        """One non-empty, stripped line: a continuation of the last record, or a record."""
        tokens = line.split()
        if _is_number(tokens[0]):
            self.continuation(lineno, tokens)
            return
        record = tokens[0].upper()
        self.last_record = record
        if record == "NM":
            self.nm(lineno, tokens, line)
        elif self.skipping:
            return
        elif record == "CD":
            self.cd(lineno, tokens)
        elif record == "LD":
            self.ld(lineno, tokens, line)
        elif record == "GC":
            self.gc(lineno, line)
        # TD, OD, ED, IT, CC, BD and any other record: not needed for the index

    def coefficients(self, tokens: list[str], lineno: int) -> tuple[float, ...]:
        """CD coefficients of the current glass from ``tokens``."""
        name = self.blocks[-1].name
        return tuple(self.number(t, lineno, f"CD coefficient of glass {name!r}") for t in tokens)

    def continuation(self, lineno: int, tokens: list[str]) -> None:
        """A line that starts with a number: Zemax reads a CD record's coefficients on as many
        lines as the vendor wrote them; other records' continuations hold nothing eyelume
        reads."""
        if self.last_record == "CD" and not self.skipping:
            block = self.blocks[-1]
            block.coefficients = block.coefficients + self.coefficients(tokens, lineno)

    def nm(self, lineno: int, tokens: list[str], line: str) -> None:
        """``NM name formula MIL nd vd ...``: a new glass, or a duplicate name to skip."""
        if len(tokens) < 6:
            raise self.bad(lineno, f"NM record needs 'NM name formula MIL nd vd ...', got {line!r}")
        name = tokens[1]
        formula_number = _formula_number(tokens[2], self.bad, lineno, name)
        nd = self.number(tokens[4], lineno, f"nd of glass {name!r}")
        vd = self.number(tokens[5], lineno, f"vd of glass {name!r}")
        if nd <= 0.0:
            raise self.bad(lineno, f"nd of glass {name!r} is {tokens[4]!r}, must be > 0")
        key = name.upper()
        self.skipping = key in self.seen
        if self.skipping:
            warnings.warn(
                f"{self.path}: line {lineno}: glass {name!r} already defined on line "
                f"{self.seen[key]}: the first definition is used",
                GlassWarning,
                stacklevel=6,  # the frame it named when _parse_agf warned itself (4), two up
            )
            return
        self.seen[key] = lineno
        self.blocks.append(_Block(name, formula_number, nd, vd, lineno))

    def cd(self, lineno: int, tokens: list[str]) -> None:
        """``CD c1 c2 ...``: the glass's dispersion coefficients (one CD per glass)."""
        block = self.current(lineno, "CD")
        if block.coefficients is not None:
            raise self.bad(lineno, f"second CD record for glass {block.name!r}")
        block.coefficients = self.coefficients(tokens[1:], lineno)

    def ld(self, lineno: int, tokens: list[str], line: str) -> None:
        """``LD min_um max_um``: the stated range; ``LD 0 0`` states none."""
        block = self.current(lineno, "LD")
        if len(tokens) < 3:
            raise self.bad(lineno, f"LD record needs 'LD min_um max_um', got {line!r}")
        lo = self.number(tokens[1], lineno, f"LD minimum wavelength of glass {block.name!r}")
        hi = self.number(tokens[2], lineno, f"LD maximum wavelength of glass {block.name!r}")
        block.has_range = True
        if lo == 0.0 and hi == 0.0:
            return  # "LD 0 0": the vendor states no range
        if not 0.0 < lo < hi:
            raise self.bad(
                lineno,
                f"LD range of glass {block.name!r} is {tokens[1]!r} to {tokens[2]!r} um, "
                "need 0 < min < max",
            )
        block.range_um = (lo, hi)

    def gc(self, lineno: int, line: str) -> None:
        """``GC text``: a comment, appended to the glass's source."""
        block = self.current(lineno, "GC")
        comment = line[2:].strip()
        block.source = f"{block.source} {comment}".strip() if block.source else comment

    def glass(self, b: _Block) -> Glass:
        """A read glass as a :class:`Glass`; GlassError when it has no CD record."""
        if b.coefficients is None:
            raise self.bad(b.line, f"glass {b.name!r} has no CD (dispersion coefficients) record")
        rng = None
        if b.range_um is not None:
            rng = tuple(round(x * 1000.0, 6) for x in b.range_um)
        return Glass(
            name=b.name,
            formula_number=b.formula_number,
            coefficients=b.coefficients,
            nd=b.nd,
            vd=b.vd,
            wavelength_range_nm=rng,
            source=b.source,
            catalog=self.path.name,
        )


def _parse_agf(path: Path) -> list[Glass]:
    """The glasses of one AGF file; GlassError naming file, line and value if malformed."""
    text = _read_text(path)
    reader = _AgfReader(path)
    for lineno, raw_line in enumerate(text.splitlines(), start=1):
        line = raw_line.strip().lstrip("\ufeff")
        if line:
            reader.line(lineno, line)
    if not reader.blocks:
        raise GlassError(
            f"{path}: not an AGF catalog (no NM glass record in {len(text.splitlines())} lines)"
        )
    glasses = []
    for b in reader.blocks:
        g = reader.glass(b)
        _check_nd(g, path, b.line)  # called from here: its stacklevel counts this frame
        glasses.append(g)
    return glasses


def _check_nd(g: Glass, path: Path, line: int) -> None:
    """Warn (GlassWarning) when the formula misses the glass's own nd at the d line."""
    try:
        n = g.index(LAMBDA_D_NM)
    except GlassError:
        n = math.nan
    if not abs(n - g.nd) <= ND_TOLERANCE:
        got = "no real index" if math.isnan(n) else f"n = {n:.6f}"
        warnings.warn(
            f"{path}: line {line}: glass {g.name!r}: its formula gives {got} at the d line "
            f"({LAMBDA_D_NM} nm) but its nd is {g.nd} (difference above {ND_TOLERANCE:g}): "
            "check its CD coefficients and formula number",
            GlassWarning,
            stacklevel=4,
        )


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _formula_number(tok: str, bad: Callable[[int, str], GlassError], lineno: int, name: str) -> int:
    """The AGF formula field as an int in FORMULAS, or GlassError naming the value."""
    try:
        x = float(tok)
    except ValueError:
        raise bad(lineno, f"formula number {tok!r} of glass {name!r} is not a number") from None
    if not x.is_integer() or int(x) not in FORMULAS:
        raise bad(
            lineno,
            f"formula number {tok!r} of glass {name!r} is not supported (AGF formulas 1-13)",
        )
    return int(x)
