"""The root of every error a user can cause, and its kinds (after ray-optics' ``TraceError``).

Layer: none — every layer may import this module; it imports nothing from eyelume.

Every error eyelume raises because of its input (a scene file, a catalog, a table, a picture, a
budget, a study store) is an :class:`EyelumeError`. Each carries what it is about — the
``field`` (a dotted scene path or an option), the ``file``, and the ``value`` — and its
``str()`` is one line that names them::

    EyelumeError
    ├── SceneError        a scene (or study) file, field or value that cannot be used
    ├── InputFileError    a data file: glass catalog, LED profile CSV, target table, picture
    │   └── GlassError    a glass catalog, a missing glass, an index that cannot be evaluated
    ├── GeometryError     an impossible geometry (an LED inside the cornea, no real image, …)
    ├── BudgetError       a sample, ray or error budget that cannot be run
    ├── StoreError        a study's result store (folder, lock, another study's runs)
    └── OptionError       a command-line option value

Every kind except :class:`StoreError`'s busy case is also a :class:`ValueError`, as these
errors were before the root existed, so callers that catch ``ValueError`` keep working. The
command line (:mod:`eyelume.cli`) catches :class:`EyelumeError` in one place, prints its one
line and exits with code 2.

>>> str(SceneError("must be > 0", file="eye.toml", field="leds.height_mm", value=-3.0))
"eye.toml: field 'leds.height_mm' = -3.0: must be > 0"
>>> str(InputFileError("row 4 has a bad value", file="led.csv"))
'led.csv: row 4 has a bad value'
>>> isinstance(GlassError("x"), (EyelumeError, InputFileError, ValueError))
True
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = [
    "BudgetError",
    "EyelumeError",
    "EyelumeWarning",
    "GeometryError",
    "GlassError",
    "InputFileError",
    "OptionError",
    "SceneError",
    "StoreError",
]

_UNSET: Any = object()


class EyelumeError(Exception):
    """An error the user can fix: a one-line message naming the field or file and the value.

    Parameters
    ----------
    message : str
        What is wrong (the reason). When ``file``, ``field`` and ``value`` are not given it is
        the whole message.
    file : str or Path, optional
        The file the error is about; the line starts with it.
    field : str, optional
        The dotted scene path, record or option the error is about (``leds.height_mm``).
    value : any, optional
        The offending value, printed with ``repr`` after the field.

    The line is ``"{file}: field '{field}' = {value!r}: {message}"`` with the absent parts left
    out; line breaks inside ``message`` become spaces, so it is always one line.
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        field: str | None = None,
        value: Any = _UNSET,
    ) -> None:
        self.message = str(message)
        self.file = None if file is None else str(file)
        self.field = field
        self.value = None if value is _UNSET else value
        self.has_value = value is not _UNSET
        super().__init__(self._line())

    def _line(self) -> str:
        parts = []
        if self.file is not None:
            parts.append(self.file)
        if self.field is not None:
            where = f"field '{self.field}'"
            if self.has_value:
                where += f" = {self.value!r}"
            parts.append(where)
        elif self.has_value:
            parts.append(f"value {self.value!r}")
        parts.append(self.message)
        return " ".join(": ".join(parts).split())

    def __str__(self) -> str:
        return self._line()


class SceneError(EyelumeError, ValueError):
    """A scene (or study) file, field or value that cannot be used: unreadable or invalid TOML,
    an unknown or missing field, a value out of range, a bad ``--set`` override."""


class InputFileError(EyelumeError, ValueError):
    """A data file that cannot be used: a glass catalog, an LED profile CSV, a target table, a
    picture. The message names the file (and the line or row when there is one)."""


class GlassError(InputFileError):
    """A glass catalog cannot be read, a glass is missing, or an index cannot be evaluated.

    The message is one line naming what failed: the file and line number and the bad value
    for a malformed catalog, the glass and the catalogs searched for a missing glass, the
    wavelength for an index that cannot be evaluated.
    """


class GeometryError(EyelumeError, ValueError):
    """A geometry that cannot exist or cannot be imaged: an LED inside the cornea, a lens
    aperture beyond its conicoid, a placement that crosses the eye plane, no real image."""


class BudgetError(EyelumeError, ValueError):
    """A sample, ray, light-path or relative-error budget that cannot be run as asked."""


class StoreError(EyelumeError, ValueError):
    """A study folder's result store that cannot be used: it holds another study's runs, it
    holds finished runs without ``--resume``, another process holds it."""


class OptionError(EyelumeError, ValueError):
    """A command-line option whose value cannot be used (``--samples 0``, ``--set x``)."""


class EyelumeWarning(UserWarning):
    """An input that is used but deserves a look (a glass whose formula misses its own nd, a
    profile table that ends above zero, a sensor far from focus). Its message is one line
    naming the file or field and the value; the command line prints it as ``warning: …``
    (once per distinct message) and goes on."""
