"""The CSV tables' columns (a fresh user's finding): a non-numeric first row was taken as a
header whatever it held, and a third column was silently ignored. A header is a row of words
only; a row of another number of columns is refused, one line naming file, field and row."""

from __future__ import annotations

import pytest

from eyelume.errors import InputFileError
from eyelume.scene.elements import read_reflectance_table
from eyelume.scene.sources import read_profile_table
from eyelume.scene.textfile import is_header_row, read_csv_table

GOOD = "0,0.04\n45,0.05\n90,1\n"


@pytest.mark.parametrize(
    "header", ["", "angle_deg,R\n", "Angle (°);R\n".replace(";", ","), "# a note\n"]
)
def test_a_header_of_words_is_skipped(tmp_path, header):
    p = tmp_path / "r.csv"
    p.write_text(header + GOOD, encoding="utf-8")
    angles, r = read_reflectance_table(str(p), "elements.0.front.coating.table_csv")
    assert r.tolist() == [0.04, 0.05, 1.0]


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("0,7,0.04,1\n45,7,0.05,1\n90,7,1,1\n", "row 1 ['0', '7', '0.04', '1'] is not"),
        (GOOD + "95,0.2,1,3\n", "row 4"),
        ("O.5,0.04\n45,0.05\n90,1\n", "row 1 ['O.5', '0.04'] is not"),
        ("0,R\n0,0.04\n90,1\n", "row 1 ['0', 'R'] is not"),
    ],
)
def test_a_coating_table_of_other_columns_is_one_line(tmp_path, text, words):
    p = tmp_path / "r.csv"
    p.write_text(text, encoding="utf-8")
    field = "elements.0.front.coating.table_csv"
    with pytest.raises(InputFileError) as info:
        read_reflectance_table(str(p), field)
    msg = str(info.value)
    assert words in msg and str(p) in msg and field in msg and "\n" not in msg, msg


def test_an_led_profile_with_a_third_column_is_refused(tmp_path):
    p = tmp_path / "led.csv"
    p.write_text("angle,rel\n0,1,9\n45,0.5,9\n90,0,9\n", encoding="utf-8")
    with pytest.raises(InputFileError, match=r"row 2 .* has 3 columns; expected 2"):
        read_profile_table(str(p))
    p.write_text("0,1,\n45,0.5,\n90,0,\n", encoding="utf-8")  # trailing separators: 2 columns
    assert read_profile_table(str(p))[1].tolist() == [1.0, 0.5, 0.0]


def test_a_wavelength_column_is_one_more_name():
    """A table with a wavelength column goes through the same reader, naming it."""
    assert is_header_row(["wavelength_nm", "angle_deg", "R"])


def test_read_csv_table_reads_named_columns(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("wavelength_nm,angle_deg,R\n850,0,0.1\n850,90,1\n", encoding="utf-8")
    t = read_csv_table(p, "f", ("wavelength_nm", "angle_deg", "reflectance"))
    assert t.shape == (2, 3) and t[1].tolist() == [850.0, 90.0, 1.0]
