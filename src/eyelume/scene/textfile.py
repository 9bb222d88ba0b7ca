"""Text data files whose encoding nobody declared: catalogs and tables as vendors and
spreadsheets write them.

Zemax writes AGF catalogs in UTF-16 LE with a byte-order mark, some vendors' tools in UTF-16 BE
without one; spreadsheets export CSV as UTF-8 (often with a BOM), as Windows-1252 (a ``°`` in a
header) or as UTF-16. :func:`decode_text` tells them apart from the bytes alone.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from eyelume.errors import InputFileError

__all__ = ["decode_text", "read_csv_rows", "read_text_file"]


def decode_text(raw: bytes, path: Path, error: type[Exception]) -> str:
    """Text of a data file whose encoding is not declared: UTF-16 with a byte-order mark,
    UTF-16 LE or BE without one (mostly ASCII text: the NUL bytes of one parity give it away),
    UTF-8 (with or without a BOM), else Windows-1252 (a spreadsheet's or a vendor's legacy
    text; the five bytes it leaves undefined become U+FFFD). ``error`` (an exception class
    taking one message) is raised, naming the file, for UTF-16 that does not decode.

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
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


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
