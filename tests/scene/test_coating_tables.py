"""Coating R(θ, λ) tables (issue 14): a third column, the wavelength, makes each wavelength's
rows an R(θ) curve of its own; the compiled surface takes R at its wavelength group's
wavelength, linear in λ between the bracketing curves (closed form here), never extrapolated.
Bad tables — an angle out of range, a non-numeric or short row, a wavelength outside the
table, a file that is not text — are one line naming the file and the row, exit code 2."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import compile_scene, wavelength_groups
from eyelume.errors import InputFileError
from eyelume.kernels.interact import interface_at
from eyelume.scene.elements import read_reflectance_table

A800 = [0.0, 30.0, 60.0, 90.0]
R800 = [0.10, 0.12, 0.20, 1.0]
A900 = [0.0, 45.0, 90.0]
R900 = [0.30, 0.40, 1.0]


def _write(path, rows, encoding="utf-8", header="angle_deg,wavelength_nm,R\n"):
    path.write_text(header + "".join(",".join(f"{x:g}" for x in r) + "\n" for r in rows), encoding)
    return str(path)


def _two_curves(tmp_path, encoding="utf-8"):
    rows = [(a, 800, r) for a, r in zip(A800, R800, strict=True)]
    rows += [(a, 900, r) for a, r in zip(A900, R900, strict=True)]
    return _write(tmp_path / "r.csv", rows, encoding)


def test_interpolated_in_wavelength_between_the_bracketing_curves(tmp_path):
    path = _two_curves(tmp_path)
    a, r = read_reflectance_table(path, "f", 800.0)
    assert np.allclose(np.degrees(a), A800) and np.allclose(r, R800)
    a, r = read_reflectance_table(path, "f", 900.0)
    assert np.allclose(np.degrees(a), A900) and np.allclose(r, R900)
    a, r = read_reflectance_table(path, "f", 825.0)
    grid = np.union1d(A800, A900)
    assert np.allclose(np.degrees(a), grid)
    expect = 0.75 * np.interp(grid, A800, R800) + 0.25 * np.interp(grid, A900, R900)
    assert np.allclose(r, expect, atol=1e-15)
    assert r[0] == pytest.approx(0.15)  # 0.75 * 0.10 + 0.25 * 0.30 at normal incidence
    # the same table in UTF-16 (with its BOM) reads the same
    a16, r16 = read_reflectance_table(_two_curves(tmp_path, "utf-16"), "f", 825.0)
    assert np.array_equal(a16, a) and np.array_equal(r16, r)
    for outside in (799.0, 900.5):
        with pytest.raises(InputFileError, match=r"outside the table's 800 … 900 nm") as info:
            read_reflectance_table(path, "f", outside)
        assert "r.csv" in str(info.value) and "\n" not in str(info.value)


def test_each_wavelength_group_compiles_its_own_reflectance(tmp_path):
    """Four LEDs, two at 800 nm and two at 900 nm: each group's compile puts that
    wavelength's R(θ) on the window's front surface."""
    path = _two_curves(tmp_path)
    coat = {"model": "table", "table_csv": path, "source": "made up for the test"}
    plate = {
        "kind": "plate",
        "name": "window",
        "position_mm": [0.0, 0.0, 45.0],
        "direction": [math.sin(math.radians(14)), 0.0, math.cos(math.radians(14))],
        "thickness_mm": 3.0,
        "glass": "N-BK7",
        "semi_diameter_mm": 27.0,
        "front": {"coating": coat},
    }
    scene = eyelume.load_scene(
        "paper2005",
        {"elements": [plate], "leds.wavelength_nm": [800.0, 800.0, 900.0, 900.0]},
    )
    nominal = compile_scene(scene)  # at the scene's 850 nm: the mean of the two curves
    front = nominal.surface_names.index("element 0 (window) front")
    assert interface_at(nominal.sf, nominal.si, front, -1.0).reflectance == pytest.approx(0.2)
    for group, r0 in zip(wavelength_groups(scene), (0.10, 0.30), strict=True):
        cs = compile_scene(scene, group, nominal=nominal)
        for theta in (0.0, 30.0, 45.0, 70.0):
            f = interface_at(cs.sf, cs.si, front, -math.cos(math.radians(theta)))
            curve = (A800, R800) if group.wavelength_nm == 800.0 else (A900, R900)
            assert f.reflectance == pytest.approx(np.interp(theta, *curve), abs=1e-12)
        assert interface_at(cs.sf, cs.si, front, -1.0).reflectance == pytest.approx(r0)


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("0,850,0.1\n95,850,0.2\n", r"row 3 .*angle of incidence 95 deg out of range 0 … 90"),
        (
            "0,850,0.1\nninety,850,0.2\n90,850,1\n",
            r"row 3 .* is not 'angle_deg, wavelength_nm, reflectance'",
        ),
        (
            "0,850,0.1\n45,0.2\n90,850,1\n",
            r"row 3 .* is not 'angle_deg, wavelength_nm, reflectance'",
        ),
        ("0,850,0.1\n45,-3,0.2\n90,850,1\n", r"row 3 .*wavelength -3 nm must be positive"),
        ("0,850,0.1\n45,850,nan\n90,850,1\n", r"row 3 .*must be finite"),
        ("0,800,0.1\n90,800,1\n0,900,0.2\n60,900,0.5\n", r"angles at 900 nm .* must increase"),
        ("0,800,0.1\n90,800,1\n", r"wavelength 850.0 nm outside the table's 800 … 800 nm"),
    ],
)
def test_bad_tables_are_one_line_naming_file_and_row(tmp_path, rows, message):
    path = tmp_path / "bad.csv"
    path.write_text("angle_deg,wavelength_nm,R\n" + rows, encoding="utf-8")  # the header is row 1
    with pytest.raises(InputFileError, match=message) as info:
        read_reflectance_table(str(path), "elements.0.front.coating.table_csv", 850.0)
    text = str(info.value)
    assert "bad.csv" in text and "table_csv" in text and "\n" not in text


def test_cli_bad_table_exit_2_one_line(tmp_path):
    """A table that is not text (NUL bytes) and one with an angle out of range: eyelume info
    (which compiles) answers one line naming the file, exit code 2."""
    import tomli_w

    table = tmp_path / "coat.csv"
    plate = {
        "kind": "plate",
        "name": "window",
        "position_mm": [0.0, 0.0, 45.0],
        "thickness_mm": 3.0,
        "glass": "N-BK7",
        "semi_diameter_mm": 27.0,
        "front": {"coating": {"model": "table", "table_csv": str(table), "source": "test"}},
    }
    base = tmp_path / "base.toml"
    eyelume.save_scene(eyelume.load_scene("paper2005"), base)
    text = base.read_text(encoding="utf-8").replace("elements = []\n", "")
    scene = tmp_path / "scene.toml"
    scene.write_text(text + "\n" + tomli_w.dumps({"elements": [plate]}), encoding="utf-8")
    runner = CliRunner()
    for content in (b"\x00\x01\x02\xff\x00garbage\x00", b"0,850,0.1\n91,850,0.2\n"):
        table.write_bytes(content)
        res = runner.invoke(app, ["info", "--scene", str(scene)], prog_name="eyelume")
        assert res.exit_code == 2, res.output
        lines = [ln for ln in res.output.splitlines() if ln.strip()]
        assert len(lines) == 1 and "coat.csv" in lines[0], res.output
