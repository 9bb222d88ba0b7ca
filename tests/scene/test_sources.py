"""LED profile tables as datasheets and spreadsheets export them (issue 12)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.errors import InputFileError
from eyelume.scene.sources import read_profile_table

# a datasheet curve (angle deg, relative intensity) that reaches 0 at 60°
ROWS = [(0, 1.0), (10, 0.97), (20, 0.72), (30, 0.38), (40, 0.15), (50, 0.04), (60, 0.0)]
BODY = "".join(f"{a},{v}\r\n" for a, v in ROWS)


def _expected():
    a = np.radians([r[0] for r in ROWS])
    return a, np.array([r[1] for r in ROWS])


@pytest.mark.parametrize(
    ("header", "encoding"),
    [
        ("Angle (°),Relative intensity\r\n", "cp1252"),  # Excel on Windows, Western locale
        ("Angle (°),Relative intensity\r\n", "utf-16"),  # Excel's "Unicode text": LE with BOM
        ("Angle (°),Relative intensity\r\n", "utf-16-be"),  # BE, no BOM
        ("Angle (°),Relative intensity\r\n", "utf-8-sig"),
        ("", "utf-8-sig"),  # a BOM before a headerless file: the 0° row must stay
        ("", "utf-16-le"),
        ("# LED XYZ, 25 °C\r\n", "cp1252"),
    ],
)
def test_encodings_are_detected(tmp_path, header, encoding):
    p = tmp_path / "led.csv"
    p.write_bytes((header + BODY).encode(encoding))
    a, v = read_profile_table(str(p))
    want_a, want_v = _expected()
    np.testing.assert_allclose(a, want_a, rtol=0, atol=1e-15)
    np.testing.assert_allclose(v, want_v, rtol=0, atol=1e-15)


def test_table_ending_above_zero_is_refused_with_what_to_do(tmp_path):
    """30° at 28 %: the power beyond is unknown (taking it as 0 loses about a quarter of a
    typical LED's power), so the table is refused, naming the file, the angle, the level and
    how to state that nothing is emitted beyond."""
    p = tmp_path / "cut.csv"
    p.write_text("angle,rel\n0,1\n10,0.9\n20,0.6\n30,0.28\n", encoding="utf-8")
    with pytest.raises(InputFileError) as info:
        read_profile_table(str(p))
    msg = str(info.value)
    assert str(p) in msg and "leds.profile.table_csv" in msg and "\n" not in msg
    assert "30 deg" in msg and "28%" in msg and "'30, 0'" in msg, msg
    # the user's explicit statement is accepted: zero just past 30°
    p.write_text("angle,rel\n0,1\n10,0.9\n20,0.6\n30,0.28\n30.0001,0\n", encoding="utf-8")
    a, v = read_profile_table(str(p))
    assert v[-1] == 0.0 and math.degrees(a[-1]) == pytest.approx(30.0001)


def test_a_table_ending_near_zero_or_at_90_is_accepted(tmp_path):
    p = tmp_path / "ok.csv"
    p.write_text("0,1\n45,0.3\n80,0.01\n", encoding="utf-8")  # 1 %: the allowed end
    assert read_profile_table(str(p))[1][-1] == pytest.approx(0.01)
    p.write_text("0,1\n45,0.5\n90,0.2\n", encoding="utf-8")  # covers the hemisphere
    assert read_profile_table(str(p))[1][-1] == pytest.approx(0.2)


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (b"", "angles must start at 0"),
        (b"0,1\n", "angles must start at 0"),
        (b"0,0\n90,0\n", "on-axis"),
        (b"0,1\n45,-0.1\n90,0\n", "row 2"),
        (b"0,1\n45,inf\n90,0\n", "row 2"),
        (b"angle,rel\n0,1\n45\n", "row 3"),
        (b"\x00\x01\x02\xff" * 10, "led.csv"),
        (b"0,1e-320\n45,1e300\n90,0\n", "overflow"),
        (b"0,1\n10,1e308\n20,0.5\n90,0\n", "at 10 deg is 1e+308 times the on-axis value"),
        (b"0,1\n10,150\n90,0\n", "not a plausible LED profile"),
    ],
)
def test_bad_tables_name_the_file(tmp_path, content, fragment):
    p = tmp_path / "led.csv"
    p.write_bytes(content)
    with pytest.raises(InputFileError) as info:
        read_profile_table(str(p))
    msg = str(info.value)
    assert str(p) in msg and fragment in msg and "\n" not in msg, msg


def test_missing_file_names_it(tmp_path):
    with pytest.raises(InputFileError, match=r"leds.profile.table_csv.*nothere.csv: no such file"):
        read_profile_table(str(tmp_path / "nothere.csv"))
