"""The illumination generator (paper §4.1): the generator merit, the LED sweep, its refinement."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest

import eyelume
from eyelume.analysis.merit import generator_merit
from eyelume.analysis.targets import gaussian_target
from eyelume.estimators.closed_form import eye_plane_irradiance
from eyelume.optimize import refine, sweep_leds
from eyelume.optimize.sweep import PAPER_BOUNDS

#: The keys of SweepResult.table_rows, in order (the module's own constant was dead code).
TABLE_COLUMNS = ("index", "height_mm", "distance_mm", "pitch_deg", "merit", "best", "problem")

# --- the generator merit -------------------------------------------------------------------------


def test_merit_is_zero_for_the_same_shape_at_any_scale(rng):
    t = rng.uniform(0.5, 2.0, size=(15, 21))
    assert generator_merit(t, t) == 0.0
    assert generator_merit(3e-6 * t, 7 * t) == pytest.approx(0.0, abs=1e-25)


def test_merit_is_the_sum_of_squares_of_unit_mean_differences(rng):
    p, t = rng.uniform(0, 1, size=(2, 15, 21))
    expected = np.sum((p / p.mean() - t / t.mean()) ** 2)
    assert generator_merit(p, t) == pytest.approx(expected, rel=1e-14)
    # vectorised over leading axes; NaN patterns score NaN, dark ones +inf
    batch = np.stack([p, t, np.full_like(p, np.nan), np.zeros_like(p)])
    m = generator_merit(batch, t)
    assert m.shape == (4,)
    assert m[0] == pytest.approx(expected, rel=1e-14) and m[1] == 0.0
    assert math.isnan(m[2]) and m[3] == math.inf


def test_merit_rejects_mismatched_or_empty_targets():
    with pytest.raises(ValueError, match="do not match"):
        generator_merit(np.ones((15, 21)), np.ones((21, 15)))
    with pytest.raises(ValueError, match="positive mean"):
        generator_merit(np.ones((15, 21)), np.zeros((15, 21)))


# --- the sweep ---------------------------------------------------------------------------------


def test_paper_grid_has_385_configurations_in_c_order(paper_scene):
    r = sweep_leds(paper_scene, gaussian_target(0.3, paper_scene.eye_plane))
    assert len(r.merit) == 385 and r.patterns.shape == (385, 15, 21)
    assert r.problems == {} and np.all(np.isfinite(r.merit))
    assert r.merit_grid().shape == (5, 11, 7)
    # C order: Y slowest, θ fastest
    i = (2 * 11 + 4) * 7 + 3
    assert (r.height_mm[i], r.distance_mm[i], r.pitch_deg[i]) == (30.0, 40.0, 15.0)
    np.testing.assert_allclose(
        r.patterns[i], eye_plane_irradiance(paper_scene, 30.0, 40.0, 15.0), rtol=1e-12
    )
    assert r.best["merit"] == np.min(r.merit) and r.best["index"] == r.best_index


def test_a_grid_configuration_is_found_from_its_own_pattern_and_beats_its_neighbours(paper_scene):
    heights, distances, pitches = (
        np.arange(20, 41, 5.0),
        np.arange(20, 71, 5.0),
        np.arange(0, 31, 5.0),
    )
    iy, iz, it = 2, 5, 3  # Y 30, Z 45, θ 15
    target = eye_plane_irradiance(paper_scene, heights[iy], distances[iz], pitches[it])
    r = sweep_leds(paper_scene, target, heights, distances, pitches)
    grid = r.merit_grid()
    assert r.best_index == np.ravel_multi_index((iy, iz, it), grid.shape)
    assert r.best["merit"] < 1e-20
    for axis in range(3):
        for step in (-1, 1):
            k = [iy, iz, it]
            k[axis] += step
            assert grid[tuple(k)] > 1e-6, (axis, step)


def test_impossible_configurations_get_nan_and_are_reported_never_chosen(paper_scene):
    # Z = 2.5 mm: a body of radius 2.5 mm reaches the eye plane; Y = 1 mm: four bodies overlap.
    # The target is the pattern of a configuration at Z = 2.6, close to the impossible ones.
    target = eye_plane_irradiance(paper_scene, 30.0, 2.6, 0.0)
    r = sweep_leds(paper_scene, target, [1.0, 30.0], [2.5, 2.6, 40.0], [0.0, 10.0])
    bad = {i for i in range(12) if r.height_mm[i] == 1.0 or r.distance_mm[i] == 2.5}
    assert set(r.problems) == bad
    assert all(math.isnan(r.merit[i]) for i in bad)
    assert all(np.isnan(r.patterns[i]).all() for i in bad)
    assert "crosses the eye plane" in r.problems[6] and "overlap" in r.problems[2]
    assert r.best["height_mm"] == 30.0 and r.best["distance_mm"] == 2.6
    rows = r.table_rows()
    assert [row["problem"] != "" for row in rows] == [i in bad for i in range(12)]
    with pytest.raises(ValueError, match="no configuration of the grid is possible"):
        sweep_leds(paper_scene, target, [30.0], [1.0, 2.5], [0.0])


def test_table_rows_write_as_csv(paper_scene):
    r = sweep_leds(
        paper_scene, gaussian_target(0.5, paper_scene.eye_plane), [20, 40], [30], [0, 30]
    )
    rows = r.table_rows()
    assert len(rows) == 4 and tuple(rows[0]) == TABLE_COLUMNS
    assert sum(row["best"] for row in rows) == 1 and rows[r.best_index]["best"] == 1
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=TABLE_COLUMNS)
    writer.writeheader()
    writer.writerows(rows)
    back = list(csv.DictReader(io.StringIO(buf.getvalue())))
    assert [float(b["merit"]) for b in back] == pytest.approx(r.merit.tolist(), rel=1e-15)


def test_target_shape_must_match_the_eye_plane(paper_scene):
    with pytest.raises(ValueError, match="target shape"):
        sweep_leds(paper_scene, np.ones((21, 15)))


# --- the refinement ------------------------------------------------------------------------------


@pytest.mark.parametrize("delta", [0.0, 0.3, 0.8])
def test_refine_is_never_worse_than_its_start(paper_scene, delta):
    target = gaussian_target(delta, paper_scene.eye_plane)
    r = sweep_leds(paper_scene, target)
    b = r.best
    for start in [(b["height_mm"], b["distance_mm"], b["pitch_deg"]), (20.0, 20.0, 0.0)]:
        start_merit = generator_merit(eye_plane_irradiance(paper_scene, *start), target)
        y, z, t, m = refine(paper_scene, target, start=start)
        assert m <= start_merit * (1 + 1e-12)
        for v, (lo, hi) in zip((y, z, t), PAPER_BOUNDS, strict=True):
            assert lo <= v <= hi
        assert m == pytest.approx(
            generator_merit(eye_plane_irradiance(paper_scene, y, z, t), target), rel=1e-9
        )


def test_refine_recovers_an_off_grid_placement(paper_scene):
    truth = (32.5, 47.5, 12.5)
    target = eye_plane_irradiance(paper_scene, *truth)
    b = sweep_leds(paper_scene, target).best
    y, z, t, m = refine(
        paper_scene, target, start=(b["height_mm"], b["distance_mm"], b["pitch_deg"])
    )
    assert m < 1e-3 * b["merit"]
    np.testing.assert_allclose((y, z, t), truth, atol=0.05)


def test_refine_rejects_impossible_bounds_and_starts(paper_scene):
    target = gaussian_target(0.3, paper_scene.eye_plane)
    with pytest.raises(ValueError, match="crosses the eye plane"):
        refine(paper_scene, target, start=(30, 30, 10), bounds=((20, 40), (2, 70), (0, 30)))
    with pytest.raises(ValueError, match="not within bounds"):
        refine(paper_scene, target, start=(30, 80, 10))


def test_generator_runs_on_a_table_profile(tmp_path, paper_scene):
    csv_path = tmp_path / "led.csv"
    csv_path.write_text("angle_deg,rel\n0,1\n20,0.8\n45,0.2\n90,0\n", encoding="utf-8")
    scene = eyelume.apply_overrides(
        paper_scene, {"leds.profile.kind": "table", "leds.profile.table_csv": str(csv_path)}
    )
    target = gaussian_target(0.5, scene.eye_plane)
    r = sweep_leds(scene, target, [20, 40], [30, 60], [0, 20])
    b = r.best
    y, z, t, m = refine(scene, target, start=(b["height_mm"], b["distance_mm"], b["pitch_deg"]))
    assert m <= b["merit"]


def test_eye_safe_sweep_excludes_placements_over_the_limit():
    """With LEDs of 0.1 W/sr the close placements exceed 100 W/m² at the cornea: the eye-safe
    sweep lists them as problems and never chooses one."""
    import eyelume
    from eyelume.analysis.safety import eye_safety
    from eyelume.analysis.targets import gaussian_target
    from eyelume.optimize.sweep import sweep_leds

    scene = eyelume.load_scene("paper2005", {"leds.radiant_intensity_w_sr": 0.1})
    target = gaussian_target(0.3, scene.eye_plane)
    free = sweep_leds(scene, target)
    safe = sweep_leds(scene, target, eye_safe=True)
    over = [i for i, w in safe.problems.items() if "IEC 62471" in w]
    assert over and len(safe.problems) > len(free.problems)
    b = safe.best
    placed = eyelume.load_scene(
        "paper2005",
        {"leds.radiant_intensity_w_sr": 0.1, "leds.height_mm": b["height_mm"],
         "leds.distance_mm": b["distance_mm"], "leds.pitch_deg": b["pitch_deg"]},
    )  # fmt: skip
    assert eye_safety(placed)["within_exempt_group"]
