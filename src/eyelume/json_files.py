"""Strict JSON for every file and listing eyelume writes: no bare ``Infinity`` or ``NaN``.

Layer: rank 0, beside :mod:`eyelume.errors` — it imports nothing from eyelume, so every layer
that writes JSON (optimize's stored best run, report's outputs, the CLI's listings) uses it.

Python's :mod:`json` writes non-finite floats as the tokens ``Infinity``, ``-Infinity`` and
``NaN``, which are not JSON (RFC 8259) and which other languages' parsers reject. Here every
non-finite number becomes ``null`` and the text is produced with ``allow_nan=False``, so a
non-finite value that slipped through is an error, never a bad file.

What ``null`` means where a number is expected (README, "Outputs"): the quantity is not a
finite number —

* an unbounded ratio: a safety margin whose exposure is 0 (no LED light reaches the eye, or no
  retinal thermal hazard at the wavelength), a relative error of a region whose mean is 0;
* an unknown quantity: the variance after a single sample set, a statistic of nothing (a mean
  gaze error with no detected frame, the merit of a placement that was not evaluated);
* ``None`` in the data itself (absent: a glint not visible, a profile with no exponent).

NumPy scalars and arrays are written as numbers and lists.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["dumps", "finite_or_null", "write_json"]


def finite_or_null(value: Any) -> Any:
    """``value`` with every non-finite float (±inf, NaN) replaced by ``None``, recursively
    through dicts, lists and tuples; NumPy scalars and arrays become Python numbers and lists.

    Examples
    --------
    >>> finite_or_null({"margin": float("inf"), "x": [1.0, float("nan")], "n": np.int64(3)})
    {'margin': None, 'x': [1.0, None], 'n': 3}
    """
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite_or_null(v) for v in value]
    if isinstance(value, np.ndarray):
        return finite_or_null(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def dumps(value: Any, **kwargs: Any) -> str:
    """Strict JSON text of ``value`` (:func:`finite_or_null` applied, ``allow_nan=False``);
    ``kwargs`` go to :func:`json.dumps` (``indent=2`` by default).

    Raises
    ------
    TypeError
        For a value JSON cannot hold (as :func:`json.dumps`).
    """
    kwargs.setdefault("indent", 2)
    return json.dumps(finite_or_null(value), allow_nan=False, **kwargs)


def write_json(path: str | Path, value: Any) -> Path:
    """Write ``value`` as strict JSON (UTF-8, a final newline) to ``path``; returns the path."""
    path = Path(path)
    path.write_text(dumps(value) + "\n", encoding="utf-8")
    return path
