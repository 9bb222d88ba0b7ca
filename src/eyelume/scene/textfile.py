"""Text data files whose encoding nobody declared: catalogs and tables as vendors and
spreadsheets write them.

Zemax writes AGF catalogs in UTF-16 LE with a byte-order mark, some vendors' tools in UTF-16 BE
without one; spreadsheets export CSV as UTF-8 (often with a BOM), as Windows-1252 (a ``°`` in a
header) or as UTF-16. :func:`decode_text` tells them apart from the bytes alone.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from eyelume.errors import InputFileError

__all__ = ["decode_text", "is_header_row", "read_csv_rows", "read_csv_table", "read_text_file"]


def decode_text(raw: bytes, path: Path, error: type[Exception]) -> str:
    """Text of a data file whose encoding is not declared: UTF-16 with a byte-order mark,
    UTF-16 LE or BE without one (mostly ASCII text: the NUL bytes of one parity give it away),
    UTF-8 (with or without a BOM), else Windows-1252 (a spreadsheet's or a vendor's legacy
    text). ``error`` (an exception class taking one message) is raised, naming the file, for
    UTF-16 that does not decode and for bytes that are neither UTF-8 nor Windows-1252 (the five
    bytes 0x81, 0x8D, 0x8F, 0x90, 0x9D that Windows-1252 leaves undefined: named, with their
    offset, instead of read as U+FFFD).

    Examples
    --------
    >>> decode_text("angle °\\n".encode("cp1252"), Path("t.csv"), ValueError)
    'angle °\\n'
    >>> decode_text("NM G".encode("utf-16-be"), Path("c.agf"), ValueError)
    'NM G'
    """
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        try:
            return raw.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise error(f"{path}: not valid UTF-16 despite its BOM ({exc.reason})") from None
    head = raw[:4096]
    pairs = len(head) // 2
    if pairs:
        even_nul = head[0 : 2 * pairs : 2].count(0) / pairs
        odd_nul = head[1 : 2 * pairs : 2].count(0) / pairs
        for codec, nul, other in (
            ("utf-16-le", odd_nul, even_nul),
            ("utf-16-be", even_nul, odd_nul),
        ):
            if nul > 0.6 and other < 0.1:
                try:
                    return raw.decode(codec)
                except UnicodeDecodeError as exc:
                    raise error(f"{path}: looks like {codec.upper()} but {exc.reason}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc8:
        try:
            return raw.decode("cp1252")
        except UnicodeDecodeError as exc:
            # 0x81, 0x8D, 0x8F, 0x90, 0x9D: neither UTF-8 nor Windows-1252, so not text this
            # reads: refused rather than read with its characters replaced
            byte = raw[exc.start]
            raise error(
                f"{path}: not text in UTF-8, UTF-16 or Windows-1252 (byte 0x{byte:02x} at "
                f"offset {exc.start}; as UTF-8: {exc8.reason} at offset {exc8.start})"
            ) from None


def read_text_file(path: str | Path, error: type[Exception]) -> str:
    """The decoded text of ``path`` (:func:`decode_text`); ``error`` naming the file if it is
    missing or cannot be read."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except OSError as exc:
        raise error(f"{path}: cannot be read ({exc.strerror})") from None
    return decode_text(raw, path, error)


def read_csv_rows(path: str | Path, field: str) -> list[list[str]]:
    """The rows of a CSV table file (any encoding :func:`decode_text` knows; a BOM dropped),
    without empty lines and lines starting with ``#``, as lists of strings.

    Raises
    ------
    InputFileError
        One line naming the file and ``field``: missing, unreadable, or not CSV.
    """
    where = Path(path)
    try:
        text = read_text_file(where, InputFileError)
    except InputFileError as exc:
        raise InputFileError(exc.message, field=field) from None
    try:
        return [
            r
            for r in csv.reader(io.StringIO(text.lstrip("\ufeff")))
            if r and "".join(r).strip() and not r[0].lstrip().startswith("#")
        ]
    except csv.Error as exc:
        raise InputFileError(f"not a CSV table ({exc})", file=where, field=field) from None


def _number(cell: str) -> float | None:
    try:
        return float(cell)
    except ValueError:
        return None


def is_header_row(row: list[str]) -> bool:
    """Whether a table's first row is its header: no cell is empty or a number, and one at
    least holds a letter (``angle_deg, R``; ``Angle (°);Relative intensity``). ``nan``, ``inf``
    and ``1e-3`` are numbers, so a row mixing numbers and words (``0, R``; ``O.5, 1`` with a
    letter O for a zero) is no header: it is refused as a row that is not numbers.

    >>> is_header_row(["angle_deg", " R"]), is_header_row(["0", "R"]), is_header_row(["nan", "x"])
    (True, False, False)
    """
    cells = [c.strip() for c in row]
    return all(c and _number(c) is None for c in cells) and any(
        re.search(r"[^\W\d_]", c) for c in cells
    )


def read_csv_table(path: str | Path, field: str, columns: tuple[str, ...]) -> np.ndarray:
    """The numbers of a CSV table file of exactly ``len(columns)`` columns: a float array
    (rows, len(columns)). The one reader of every table's columns (the LED profile, a coating's
    R(angle); a table with a wavelength column passes its name among ``columns``).

    Rows as :func:`read_csv_rows` reads them (``#`` lines and empty lines skipped); empty cells
    at a row's end (a spreadsheet's trailing separators) are dropped. The first row may be a
    header, and is skipped, only if it is recognisably one (:func:`is_header_row`: words, no
    numbers); any other row must hold ``len(columns)`` numbers (``nan`` and ``inf`` are read
    as such: the caller's range checks refuse them, naming the row).

    Raises
    ------
    InputFileError
        One line naming the file, ``field`` and the row: a row of another number of columns
        (a third column is not silently ignored), a cell that is not a number. A file of no
        rows gives (0, len(columns)): the caller says how many rows it needs.
    """
    where = Path(path)
    names = ", ".join(columns)
    out = []
    for n, row in enumerate(read_csv_rows(where, field), 1):
        while row and not row[-1].strip():
            row = row[:-1]
        if n == 1 and is_header_row(row):
            if len(row) != len(columns):
                raise InputFileError(
                    f"header row {row!r} names {len(row)} columns; the table has "
                    f"{len(columns)}: {names}",
                    file=where,
                    field=field,
                )
            continue
        if len(row) != len(columns):
            raise InputFileError(
                f"row {n} {row!r} has {len(row)} columns; expected {len(columns)}: {names}",
                file=where,
                field=field,
            )
        values = [_number(c) for c in row]
        if any(v is None for v in values):
            raise InputFileError(
                f"row {n} {row!r} is not {len(columns)} numbers '{names}'"
                + (" (a header row is words only, e.g. 'angle_deg, R')" if n == 1 else ""),
                file=where,
                field=field,
            )
        out.append(values)
    return np.asarray(out, dtype=float).reshape(len(out), len(columns))
