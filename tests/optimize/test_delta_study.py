"""The Section 4 δ study end to end (reduced budgets), the evaluator merit's noise estimate, and the
direct optimisation's guarantee."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.analysis.masks import ideal_mask
from eyelume.cli import app
from eyelume.compile import compile_scene
from eyelume.optimize.delta_study import evaluate_placement, with_placement
from eyelume.optimize.direct import DirectSearch, optimize_direct

runner = CliRunner()
SMALL = {"sensor.cols": 44, "sensor.rows": 33}


@pytest.mark.slow
def test_reproduce_runs_end_to_end(tmp_path):
    out = tmp_path / "study"
    args = ["reproduce", "paper2005", "--out", str(out), "--deltas", "0,0.3,0.8"]
    res = runner.invoke(app, [*args, "--samples", "8", "--direct", "4"])
    assert res.exit_code == 0, res.output
    with open(out / "table.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["delta"]) for r in rows] == [0.0, 0.3, 0.8]
    for r in rows:
        assert 20 <= float(r["height_mm"]) <= 40 and 20 <= float(r["distance_mm"]) <= 70
        assert float(r["evaluator_merit"]) > 0 and float(r["skin_cv"]) > 0
    for name in ("merit_vs_delta.png", "deltas.png", "eye_image_delta_0.3.png"):
        assert (out / name).stat().st_size > 1000, name
    text = (out / "comparison.md").read_text(encoding="utf-8")
    assert "Best δ" in text and ("agrees" in text or "disagrees" in text)
    assert "Beyond the paper" in text
    study = json.loads((out / "delta_study.json").read_text(encoding="utf-8"))
    assert study["best_delta"] in (0.0, 0.3, 0.8) and study["direct"]["evaluations"] >= 1


def test_sweep_leds_command(tmp_path):
    out = tmp_path / "sweep"
    res = runner.invoke(app, ["sweep-leds", "--delta", "0.3", "--out", str(out)])
    assert res.exit_code == 0, res.output
    with open(out / "sweep.csv", encoding="utf-8") as f:
        assert len(list(csv.DictReader(f))) == 385
    best = json.loads((out / "best.json").read_text(encoding="utf-8"))
    assert best["refined"]["merit"] <= best["merit"] + 1e-12
    assert (out / "landscape.png").stat().st_size > 1000


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["sweep-leds", "--delta", "1.2"], ["delta", "1.2"]),
        (["reproduce", "paper2005", "--deltas", "0,x"], ["--deltas"]),
        (["reproduce", "paper2005", "--deltas", "0,1.5"], ["--deltas"]),
    ],
)
def test_bad_study_input_one_line_exit_2(tmp_path, args, words):
    res = runner.invoke(app, [*args, "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    message = res.stderr.strip()
    assert len(message.splitlines()) == 1, message
    for w in words:
        assert w.lower() in message.lower()


def test_evaluator_merit_noise_estimate_matches_scatter():
    """Six seeds of the same placement: the spread of the evaluator merit agrees with the
    standard error each render estimates for itself (ratio of variances inside the χ²₅ 99.8 %
    band), and the seed-to-seed mean sits where the noise bias says."""
    from scipy import stats

    scene = eyelume.load_scene("paper2005", SMALL)
    mask = ideal_mask(compile_scene(scene))
    runs = [evaluate_placement(scene, mask, 8, s) for s in range(6)]
    merits = np.array([m for _, m, _, _ in runs])
    se = np.mean([s for _, _, s, _ in runs])
    q = merits.var(ddof=1) / se**2
    lo, hi = stats.chi2.ppf([0.001, 0.999], len(runs) - 1) / (len(runs) - 1)
    assert lo < q < hi, f"scatter / estimate = {q:.2f}"


def test_direct_optimum_is_no_worse_than_its_start():
    """With common random numbers the search's objective is deterministic: the optimum found
    scores at most what its start scores under the same seed."""
    scene = eyelume.load_scene("paper2005", SMALL)
    mask = ideal_mask(compile_scene(scene))
    start = (30.0, 60.0, 15.0)
    _, m0, _, _ = evaluate_placement(with_placement(scene, *start), mask, 8, 5)
    search = DirectSearch(samples_per_pixel=8, seed=5, max_evaluations=8)
    found = optimize_direct(scene, mask, start, search)
    assert found.merit <= m0 + 1e-15
    assert np.isfinite(found.merit_check) and found.merit_check_se > 0


def test_direct_optimisation_over_led_count_spread_and_azimuths():
    """The optional variables run: 4 and 6 LEDs, the spread angle and each LED's azimuth; the
    result carries them and stays inside their bounds."""
    scene = eyelume.load_scene("paper2005", SMALL)
    mask = ideal_mask(compile_scene(scene))
    found = optimize_direct(
        scene,
        mask,
        (30.0, 60.0, 15.0),
        DirectSearch(
            led_counts=(4, 6),
            vary_spread=True,
            vary_azimuths=True,
            samples_per_pixel=8,
            seed=2,
            max_evaluations=4,
        ),
    )
    assert found.leds in (4, 6)
    assert len(found.azimuth_shifts_deg) == found.leds
    assert all(abs(a) <= 90.0 / found.leds + 1e-9 for a in found.azimuth_shifts_deg)
    assert 10.0 <= found.half_angle_deg <= 40.0
    assert np.isfinite(found.merit)


def test_the_direct_search_refuses_one_intensity_per_led():
    """It varies the LED count: a list of one I₀ per LED cannot follow (every count would score
    +inf as an impossible scene, silently); refused before any render."""
    from eyelume.errors import SceneError

    scene = eyelume.load_scene(
        "paper2005", {"leds.radiant_intensity_w_sr": [0.01, 0.02, 0.01, 0.02]}
    )
    with pytest.raises(SceneError, match="leds.radiant_intensity_w_sr") as e:
        optimize_direct(scene, None, (30.0, 70.0, 20.0))  # type: ignore[arg-type]
    assert "one value for every LED" in str(e.value)
