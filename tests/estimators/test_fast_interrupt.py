"""An interrupted fast render is right for what it finished (issue 12): one camera set gives the
unbiased mean of that set with an unknown variance (not half the true value), a round stopped
half way is undone, nothing finished is an error, and a --rel-error target beyond the sample cap
stops there and says so. The interrupt is simulated by a stop flag raised from the callbacks."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

import eyelume
from eyelume.analysis.regions import region_masks
from eyelume.estimators import fast_run as FR

SPP = 16  # 2 × 2 sets: four of them, one per round


class _Flag:
    requested = False
    signum = None


@pytest.fixture
def flag(monkeypatch):
    f = _Flag()
    monkeypatch.setattr(FR, "interrupt_between_batches", lambda: contextlib.nullcontext(f))
    return f


def _light(cs, spp):
    sc = cs.scene
    return int(round(sc.run.light_paths_per_pixel * sc.sensor.cols * sc.sensor.rows * spp / 16))


def test_one_finished_set_is_unbiased_and_its_variance_unknown(paper_compiled, flag):
    cs = paper_compiled
    skin = region_masks(cs)["skin"]

    def after_round(msg):
        flag.requested = True  # "Ctrl-C" during the second round

    one = FR.trace_fast(cs, SPP, _light(cs, SPP), 7, progress=after_round)
    assert one.interrupted and one.samples_per_pixel == 4 and one.variance_dof == 0
    assert np.isinf(one.variance).all()  # unknown, not a made-up figure
    flag.requested = False
    full = FR.trace_fast(cs, SPP, _light(cs, SPP), 7)
    assert not full.interrupted and full.samples_per_pixel == SPP and full.variance_dof == 3
    # the skin mean of one set against four: the same quantity. The one-set mean's standard
    # error is √4 = 2× the four-set one's (σ4 from full.variance); 5σ of the difference.
    m1, m4 = one.image[skin].mean(), full.image[skin].mean()
    se4 = math.sqrt(full.variance[skin].sum()) / skin.sum()
    assert abs(m1 - m4) < 5 * math.hypot(2 * se4, se4), (m1, m4, se4)
    assert abs(m1 / m4 - 1) < 0.05  # the defect gave ≈ 0.5


def test_a_round_stopped_half_way_is_undone(paper_compiled, flag, monkeypatch):
    cs = paper_compiled
    monkeypatch.setattr(FR, "CHUNK_SAMPLES", 2000)  # many chunks per round
    calls = []

    def after_round(msg):
        calls.append(msg)

    def tick(done, planned):
        if calls and done > 4 * cs.scene.sensor.cols * cs.scene.sensor.rows + 6000:
            flag.requested = True  # a few camera chunks into round 2

    half = FR.trace_fast(
        cs, SPP, _light(cs, SPP), 7, progress=after_round, control=FR.RunControl(advance=tick)
    )
    assert half.interrupted and half.samples_per_pixel == 4  # round 2 undone, every pixel

    flag.requested = False
    calls.clear()

    def stop_after_first(msg):
        flag.requested = True

    one = FR.trace_fast(cs, SPP, _light(cs, SPP), 7, progress=stop_after_first)
    np.testing.assert_array_equal(half.image, one.image)  # exactly the first round


def test_nothing_finished_is_said(paper_compiled, flag):
    flag.requested = True
    with pytest.raises(KeyboardInterrupt, match="nothing usable"):
        FR.trace_fast(paper_compiled, SPP, _light(paper_compiled, SPP), 7)


def test_an_unreachable_target_stops_at_the_cap_and_says_so(paper_compiled):
    cs = paper_compiled
    said = []
    skin = region_masks(cs)["skin"]
    cap = FR.RunControl(max_samples_per_pixel=32)
    est = FR.trace_fast(cs, 8, _light(cs, 8), 3, rel_error=1e-6, progress=said.append,
                        target_pixels=skin, control=cap)  # fmt: skip
    assert est.target_reached is False and not est.interrupted
    assert est.samples_per_pixel <= 32
    assert 1e-6 < est.rel_error_achieved < 0.2
    assert any("over the cap of 32" in s for s in said), said


@pytest.mark.parametrize(("first", "cap"), [(32, 16), (32, 8), (8, 4), (8, 2)])
def test_a_run_never_renders_more_than_its_cap(paper_compiled, first, cap):
    """The grid of a capped run is the finest whose two sets fit under the cap: an unreachable
    target renders exactly the cap (before: a first round of 32 samples per pixel, two 4 × 4
    sets, was rendered whole under a cap of 16 or 8, and 2 × 2 sets under a cap of 4 or 2)."""
    cs = paper_compiled
    skin = region_masks(cs)["skin"]
    est = FR.trace_fast(cs, first, _light(cs, first), 3, rel_error=1e-6, target_pixels=skin,
                        control=FR.RunControl(max_samples_per_pixel=cap))  # fmt: skip
    assert est.target_reached is False
    assert est.samples_per_pixel == cap


def test_the_pilot_tries_no_grid_over_the_cap(paper_compiled, monkeypatch):
    """The pilot of a run capped at 16 samples per pixel does not trace 4 × 4 sets (two of them
    are 32): uncapped, the same pilot traces them (so the spy can see it)."""
    cs = paper_compiled
    target = np.zeros((cs.picture.rows, cs.picture.cols), dtype=bool)
    target[20:45:2, 25:60:3] = True
    traced = []
    real = FR.F.camera_pass

    def spy(seed_, first, n_sets, tables, cam, grid, sums):
        traced.append(grid)
        return real(seed_, first, n_sets, tables, cam, grid, sums)

    monkeypatch.setattr(FR.F, "camera_pass", spy)
    FR._pilot(cs, 3, target, 1e-4, 0.5)
    assert FR.GRID_FINE in traced
    traced.clear()
    grid, sets = FR._pilot(cs, 3, target, 1e-4, 0.5, FR._largest_grid(16))
    assert FR.GRID_FINE not in traced and grid <= FR.GRID_COARSE
    assert traced


def test_a_cap_below_two_samples_is_refused(paper_compiled):
    with pytest.raises(eyelume.errors.BudgetError, match="max_samples_per_pixel = 1: must be ≥ 2"):
        FR.trace_fast(paper_compiled, 8, 0, 3, rel_error=0.01,
                      control=FR.RunControl(max_samples_per_pixel=1))  # fmt: skip


def test_samples_rendered_are_whole_sets():
    assert [FR.planned_sets(n) for n in (1, 9, 33)] == [(2, 2), (2, 3), (4, 3)]
    r = eyelume.render(
        eyelume.load_scene("paper2005"), eyelume.RenderOptions(samples_per_pixel=1, seed=1)
    )
    assert r.samples_per_pixel == 8 and r.summary()["samples_per_pixel"] == 8
