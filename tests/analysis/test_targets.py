"""Target patterns of the generator (paper §4.1.2): the δ-falloff normal distribution and user
patterns loaded from files."""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.targets import (
    bin_centres,
    gaussian_sigmas,
    gaussian_target,
    gaussian_value,
    load_target,
)
from eyelume.scene.model import EyePlane

PLANE = EyePlane()  # 40 × 30 mm, 21 × 15 bins
CORNERS = [(20.0, 15.0), (-20.0, 15.0), (20.0, -15.0), (-20.0, -15.0)]


def test_delta_zero_is_exactly_uniform():
    t = gaussian_target(0.0, PLANE)
    assert t.shape == (15, 21)
    assert np.array_equal(t, np.ones((15, 21)))
    assert np.array_equal(gaussian_target(0, PLANE, sigma_x_over_y=2.0), np.ones((15, 21)))


@pytest.mark.parametrize("aspect", [None, 0.5, 4 / 3, 2.0])
@pytest.mark.parametrize("delta", [1e-6, 0.1, 0.3, 0.5, 0.8, 0.99])
def test_corner_value_is_one_minus_delta_of_the_centre(delta, aspect):
    centre = float(gaussian_value(0.0, 0.0, delta, PLANE, aspect))
    assert centre == 1.0
    for x, y in CORNERS:
        corner = float(gaussian_value(x, y, delta, PLANE, aspect))
        assert corner == pytest.approx((1 - delta) * centre, rel=1e-12)
    # the binned target peaks at the centre bin and every bin lies between 1 − δ and 1
    t = gaussian_target(delta, PLANE, aspect)
    assert t[7, 10] == 1.0 and t.max() == 1.0
    assert np.all(t > 1 - delta)


def test_isotropic_unless_an_aspect_is_given():
    sx, sy = gaussian_sigmas(0.3, PLANE)
    assert sx == sy
    # same value at the same distance along x and along y
    assert float(gaussian_value(7.0, 0.0, 0.3, PLANE)) == float(
        gaussian_value(0.0, 7.0, 0.3, PLANE)
    )
    sx, sy = gaussian_sigmas(0.3, PLANE, sigma_x_over_y=1.5)
    assert sx / sy == pytest.approx(1.5, rel=1e-14)


def test_target_is_the_function_at_the_bin_centres_row_zero_at_plus_y():
    x = np.linspace(-20 + 40 / 42, 20 - 40 / 42, 21)
    y = np.linspace(15 - 1.0, -15 + 1.0, 15)  # row 0 at +y
    cx, cy = bin_centres(PLANE)
    np.testing.assert_allclose(cx, x, atol=1e-12)
    np.testing.assert_allclose(cy, y, atol=1e-12)
    t = gaussian_target(0.5, PLANE, sigma_x_over_y=2.0)
    expected = gaussian_value(x[None, :], y[:, None], 0.5, PLANE, 2.0)
    np.testing.assert_allclose(t, expected, rtol=1e-15)
    # the closed form of σ for the isotropic case: 2σ² ln(1/(1−δ)) = (w² + h²)/4
    sx, _ = gaussian_sigmas(0.5, PLANE)
    assert 2 * sx**2 * math.log(2) == pytest.approx((40**2 + 30**2) / 4, rel=1e-14)
    # a scene is accepted in place of its eye plane
    other = EyePlane(width_mm=20, height_mm=20, cols=5, rows=5)
    assert gaussian_target(0.2, other).shape == (5, 5)


@pytest.mark.parametrize("delta", [1.0, 1.5, -0.1, math.nan, math.inf, "abc", None])
def test_bad_delta_is_rejected_naming_delta_and_value(delta):
    with pytest.raises(ValueError, match=r"delta = ") as info:
        gaussian_target(delta, PLANE)
    assert repr(delta) in str(info.value)


@pytest.mark.parametrize("aspect", [0.0, -1.0, math.inf, math.nan])
def test_bad_aspect_is_rejected(aspect):
    with pytest.raises(ValueError, match="sigma_x_over_y"):
        gaussian_target(0.3, PLANE, sigma_x_over_y=aspect)


# --- user patterns from files ----------------------------------------------------------------


def _pattern() -> np.ndarray:
    rng = np.random.default_rng(4)
    return rng.uniform(0.0, 2.0, size=(15, 21))


def test_load_csv_and_npy_round_trip(tmp_path):
    p = _pattern()
    csv = tmp_path / "target.csv"
    np.savetxt(csv, p, delimiter=",", header="row 0 at +y", fmt="%.17g")
    np.testing.assert_array_equal(load_target(csv, PLANE), p)
    npy = tmp_path / "target.npy"
    np.save(npy, p)
    out = load_target(npy, PLANE)
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, p)
    np.save(tmp_path / "ints.npy", np.ones((15, 21), dtype=np.int32))
    assert load_target(tmp_path / "ints.npy", PLANE).dtype == np.float64


@pytest.mark.parametrize("encoding", ["utf-8-sig", "utf-16", "utf-16-be", "cp1252"])
def test_load_csv_as_spreadsheets_write_it(tmp_path, encoding):
    """A BOM, UTF-16 or Windows-1252 (a degree sign in a comment) read as the numbers (issue 12)."""
    p = _pattern()
    text = "# target, 20 °C\n" + "\n".join(",".join(f"{v:.17g}" for v in row) for row in p)
    csv = tmp_path / "target.csv"
    csv.write_bytes(text.encode(encoding))
    np.testing.assert_array_equal(load_target(csv, PLANE), p)


def _write(tmp_path, name: str, data) -> str:
    path = tmp_path / name
    if name.endswith(".npy"):
        np.save(path, data)
    else:
        path.write_text(data, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("name", "data", "problem"),
    [
        ("shape.npy", np.ones((21, 15)), r"shape \(21, 15\) but the eye plane has"),
        ("flat.npy", np.ones(315), r"shape \(315,\)"),
        ("nan.npy", np.where(np.eye(15, 21) > 0, np.nan, 1.0), "row 0, column 0 is nan"),
        ("inf.npy", np.full((15, 21), np.inf), "not finite"),
        ("neg.npy", -np.ones((15, 21)), "row 0, column 0 is -1.0 .negative"),
        ("zero.npy", np.zeros((15, 21)), "every value is zero"),
        ("text.npy", np.full((15, 21), "a"), "not numbers"),
        ("words.csv", "a,b,c\n1,2,3\n", "not a table of numbers"),
        ("short.csv", "1,2,3\n4,5,6\n", r"shape \(2, 3\)"),
        ("ragged.csv", "1,2,3\n4,5\n", "not a table of numbers"),
        ("pattern.txt", "1", "unknown format '.txt'"),
    ],
)
def test_load_target_errors_name_the_file_and_the_problem(tmp_path, name, data, problem):
    path = _write(tmp_path, name, data)
    with pytest.raises(ValueError, match=problem) as info:
        load_target(path, PLANE)
    assert f"target file '{path}'" in str(info.value)


def test_load_target_missing_file(tmp_path):
    path = tmp_path / "absent.csv"
    with pytest.raises(ValueError, match="cannot read") as info:
        load_target(path, PLANE)
    assert str(path) in str(info.value)
