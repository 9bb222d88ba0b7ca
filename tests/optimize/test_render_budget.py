"""The render budget a tracker's frames and a dataset's pictures share
(:mod:`eyelume.optimize.render_budget`): the target follows the pilot's skin electrons
(0.9 / sqrt(N̄)), the samples a frame uses follow the target, tracking evaluation pilots once
per scene (person), not per frame, and the command line's ``--render-noise``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
import eyelume.optimize.tracking as tr
from eyelume.analysis.tracking.detect import Detection
from eyelume.analysis.tracking.evaluate import Frame, TrackingReport
from eyelume.cli import app
from eyelume.errors import OptionError
from eyelume.optimize import render_budget as rb
from eyelume.scene.population import sample_people

runner = CliRunner()
TINY = ["--set", "sensor.cols=16", "--set", "sensor.rows=16", "--set", "sensor.pixel_pitch_um=75"]
#: vr-offaxis's 400 × 400 field on 32 × 32 pixels (the pilot's grid is the picture's own)
SMALL = {"sensor.cols": 32, "sensor.rows": 32, "sensor.pixel_pitch_um": 37.5}


@pytest.mark.parametrize(("text", "value"), [("sensor", "sensor"), (" Sensor", "sensor"),
                                             ("0.05", 0.05), ("1e-3", 1e-3)])  # fmt: skip
def test_parse_render_noise(text, value):
    assert rb.parse_render_noise(text) == value


@pytest.mark.parametrize("text", ["0", "1", "1.5", "-0.1", "nan", "inf", "noise", ""])
def test_a_bad_render_noise_names_the_option_and_value(text):
    with pytest.raises(OptionError, match=rf"--render-noise {text}: 'sensor' or a relative"):
        rb.parse_render_noise(text)


def test_dataset_and_tracking_share_one_budget_rule():
    from eyelume.optimize import dataset

    assert dataset.sensor_noise_target is rb.sensor_noise_target
    assert dataset.SENSOR_NOISE_MARGIN == rb.SENSOR_NOISE_MARGIN


def test_the_samples_follow_the_skin_electrons():
    """Four times the exposure: the pilot (same scene, same seed: the same irradiance) reads
    exactly 4 N̄, the target halves (0.9 / sqrt(N̄)), and the frame — whose median skin error
    falls as 1/sqrt(samples) — needs about four times the samples. The stopping rule sizes each
    round from the error it measured (× 1.1) and that error scatters on a 32 × 32 picture, so
    the ratio is asked within a factor 2 of 4."""
    used, electrons, targets = [], [], []
    for exposure in (0.05, 0.2):
        sc = eyelume.load_scene("vr-offaxis", {**SMALL, "sensor.exposure_ms": exposure})
        target, facts = rb.noise_options(sc, "sensor", 0)
        assert facts["budget"] == "sensor" and facts["target_rel_error"] == target
        n = facts["pilot_skin_electrons"]
        assert target == pytest.approx(rb.SENSOR_NOISE_MARGIN / math.sqrt(n), rel=1e-12)
        frame = tr.render_frame(sc, 0.0, 0.0, 1, 0, target)
        used.append(frame.samples_per_pixel)
        electrons.append(n)
        targets.append(target)
    assert electrons[1] / electrons[0] == pytest.approx(4.0, rel=1e-9)
    assert targets[1] / targets[0] == pytest.approx(0.5, rel=1e-9)
    assert 2.0 <= used[1] / used[0] <= 8.0, used


def test_a_fixed_relative_error_needs_no_pilot(monkeypatch):
    monkeypatch.setattr(rb, "sensor_noise_target", lambda *a: pytest.fail("no pilot"))
    sc = eyelume.load_scene("vr-offaxis", SMALL)
    assert rb.noise_options(sc, 0.04, 3) == (
        0.04, {"budget": "render_noise", "target_rel_error": 0.04,
               "max_samples_per_pixel": rb.MAX_SAMPLES_PER_PIXEL},
    )  # fmt: skip


@pytest.fixture()
def recorded(monkeypatch):
    """render_frame and the pilot replaced by stand-ins that record their calls: the pilot's
    target is a function of the person's scene (their corneal radius), the sunlight's a third
    of it (``ambients``: what each frame's sunlight render was asked)."""
    frames, pilots, ambients = [], [], []

    def render(
        scene, h, v, samples, seed, rel_error=None, max_samples=None, ambient_rel_error=None
    ):
        frames.append((id(scene), rel_error))
        ambients.append(ambient_rel_error)
        det = Detection(ok=True, failures=[], pupil=None, glints=[])
        f = Frame(gaze=(h, v), detection=det, truth={})
        f.samples_per_pixel = 7
        return f

    def pilot(scene, noise, seed, max_samples=rb.MAX_SAMPLES_PER_PIXEL):
        if noise != "sensor":
            return noise, {"budget": "render_noise", "target_rel_error": noise}
        target = scene.eye.surfaces[0].radius_mm / 1000.0
        pilots.append((id(scene), noise, seed))
        sun = target / 3.0
        return target, {"budget": "sensor", "target_rel_error": target,
                        "ambient_target_rel_error": sun}  # fmt: skip

    def analyse(scene, leds, fr, calib):
        return TrackingReport(fr, calib, 0.01, {"detection_rate": 1.0})

    monkeypatch.setattr(tr, "render_frame", render)
    monkeypatch.setattr(tr, "noise_options", pilot)
    monkeypatch.setattr(tr, "analyse_frames", analyse)
    return frames, pilots, ambients


def test_one_pilot_per_person_not_per_frame(recorded):
    frames, pilots, ambients = recorded
    people = sample_people(eyelume.load_scene("vr-offaxis"), 3, 4)
    results = tr.evaluate_people(people, 8, 5, render_noise="sensor")
    per = tr.people_frame_count()
    assert len(frames) == 3 * per
    assert [(p[1], p[2]) for p in pilots] == [("sensor", 5)] * 3  # one each, the frames' seed
    for k, person in enumerate(people):
        mine = frames[k * per : (k + 1) * per]
        assert {s for s, _ in mine} == {id(person.scene)}
        assert {t for _, t in mine} == {person.scene.eye.surfaces[0].radius_mm / 1000.0}
        # the pilot's sunlight target reaches every frame's sunlight render
        assert set(ambients[k * per : (k + 1) * per]) == {
            person.scene.eye.surfaces[0].radius_mm / 1000.0 / 3.0
        }
        budget = results[k].row()["render_budget"]
        assert budget["render_noise"] == "sensor" and budget["samples_per_pixel_used"] == [7, 7]
    frames.clear()
    pilots.clear()
    tr.evaluate_people(people[:1], 8, 5)  # no render_noise: the fixed budget, no pilot
    assert pilots == [] and {t for _, t in frames} == {None}


def test_population_defaults_to_the_sensor_budget(tmp_path, recorded):
    frames, pilots, _ = recorded
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "2",
                              *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert len(pilots) == 2 and all(p[1] == "sensor" for p in pilots)
    meta = json.loads((out / "population.json").read_text(encoding="utf-8"))["meta"]
    assert meta["render_noise"] == "sensor" and meta["samples_per_pixel"] is None
    assert meta["samples_per_pixel_used"] == [7, 7]
    frames.clear()
    pilots.clear()
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "1",
                              "--samples", "3", *TINY, "--out", str(tmp_path / "p")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert pilots == [] and {t for _, t in frames} == {None}
    frames.clear()
    sc = eyelume.load_scene("vr-offaxis")  # the one eye, every frame at that error, no pilot
    rep = tr.evaluate_tracking(sc, (0.0, 5.0), (0.0,), render_noise=0.05, calibrate=False)
    assert pilots == []
    assert {t for _, t in frames} == {0.05} and len(frames) == 2
    assert rep.summary["render_budget"]["render_noise"] == 0.05


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--render-noise", "2"], ["--render-noise 2", "relative error"]),
        (["--render-noise", "loud"], ["--render-noise loud"]),
        (["--samples", "4", "--render-noise", "sensor"], ["--samples 4", "--render-noise"]),
    ],
)
def test_bad_render_budget_options_are_one_line(tmp_path, args, words):
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "2",
                              *args, *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert all(w in text for w in words), res.output
    assert "Traceback" not in res.output and not out.exists()


def test_noise_target_uses_the_pilot_seed_not_the_frames():
    """The pilot's seed is derived from the frame seed (its samples are not the picture's) and
    the pilot is a pure function of (scene, seed)."""
    sc = eyelume.load_scene("vr-offaxis", SMALL)
    a = rb.sensor_noise_target(sc, 11)
    assert rb.sensor_noise_target(sc, 11) == a
    b = rb.sensor_noise_target(sc, 12)
    assert b != a and np.isclose(a[1], b[1], rtol=0.2)


#: the sun 40° up and 30° aside through a 40 nm band-pass about 850 nm (as in
#: benchmarks/design_850_940.py)
SUN = {"ambient.sun.elevation_deg": 40.0, "ambient.sun.azimuth_deg": 30.0,
       "sensor.filter.kind": "band_pass", "sensor.filter.cut_on_nm": 830.0,
       "sensor.filter.cut_off_nm": 870.0}  # fmt: skip


def test_with_the_sun_each_source_is_rendered_to_its_own_shot_noise():
    """The LEDs' and the sun's electrons are independent shot noises that add in variance, as
    the two renders' noises do: each source gets m / sqrt(its own N̄). The LEDs' pilot picture
    is the sunless scene's (the sunlight is rendered apart, with its own seed), so N̄_L is
    exactly the sunless pilot's; the two targets' noises sum to m sqrt(N̄_L + N̄_S)."""
    m = rb.SENSOR_NOISE_MARGIN
    lit = rb.sensor_noise_target(eyelume.load_scene("vr-offaxis", {**SMALL, **SUN}), 3)
    dark = rb.sensor_noise_target(eyelume.load_scene("vr-offaxis", SMALL), 3)
    assert dark.ambient_rel_error is None and dark.ambient_electrons is None
    assert lit.electrons == dark.electrons and lit.rel_error == dark.rel_error
    assert lit.rel_error == pytest.approx(m / math.sqrt(lit.electrons), rel=1e-12)
    assert lit.ambient_electrons > 0
    assert lit.ambient_rel_error == pytest.approx(m / math.sqrt(lit.ambient_electrons), rel=1e-12)
    noise = math.hypot(lit.rel_error * lit.electrons, lit.ambient_rel_error * lit.ambient_electrons)
    assert noise == pytest.approx(m * math.sqrt(lit.electrons + lit.ambient_electrons), rel=1e-12)
    target, facts = rb.noise_options(
        eyelume.load_scene("vr-offaxis", {**SMALL, **SUN}), "sensor", 3
    )
    assert target == lit.rel_error
    assert facts["ambient_target_rel_error"] == lit.ambient_rel_error
    assert facts["pilot_ambient_skin_electrons"] == lit.ambient_electrons


def test_the_sunlight_render_takes_its_own_target():
    """``ambient_rel_error`` reaches the sunlight's render alone: a tighter one traces more of
    the sunlight's paths and leaves the LEDs' picture as it was (same seed, same samples)."""
    from eyelume.render import RenderOptions, render

    sc = eyelume.load_scene("vr-offaxis", {**SMALL, **SUN})
    runs = [
        render(sc, RenderOptions(estimator="fast", rel_error=0.05, seed=4, ambient_rel_error=a))
        for a in (None, 0.005)
    ]
    assert np.array_equal(runs[0].eye_image, runs[1].eye_image)
    assert runs[1].ambient.rays > 4 * runs[0].ambient.rays


@pytest.mark.slow
def test_people_on_two_workers_give_the_rows_of_one(tmp_path):
    """Real renders (vr-offaxis on 16 × 16 pixels, 8 samples per pixel: the numbers mean
    little, their equality everything): `evaluate-tracking --population 2 --workers 2` writes
    the same people rows as one process."""
    rows = {}
    for w in (1, 2):
        out = tmp_path / f"w{w}"
        res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population",
                                  "2", "--samples", "1", "--workers", str(w), *TINY,
                                  "--out", str(out)])  # fmt: skip
        assert res.exit_code == 0, res.output
        data = json.loads((out / "population.json").read_text(encoding="utf-8"))
        assert data["meta"]["workers"] == w
        rows[w] = (data["people"], data["summary"])
    assert rows[1] == rows[2]
    assert [r["person"] for r in rows[1][0]] == [0, 1]


def test_workers_need_a_population(tmp_path):
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--workers", "2",
                              *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 2 and "--workers 2: only with --population" in res.output
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "2",
                              "--workers", "0", *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 2 and "--workers 0" in res.output and not out.exists()
