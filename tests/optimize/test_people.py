"""Tracking over sampled people (issue 15 part 2): angle kappa in the scene and the truth, the
per-person rows and the distribution over people, `evaluate-tracking --population N` and a
study's `[population]` run — the same people and results whatever the worker count — and bad
input through the command line (one line naming the field, exit 2)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume
import eyelume.optimize.tracking as tr
from eyelume.analysis.tracking.detect import Detection
from eyelume.analysis.tracking.evaluate import FAILED_FRAME_DEG, Frame, TrackingReport
from eyelume.analysis.tracking.gaze import angles_from_axis, axis_from_angles
from eyelume.analysis.truth import eye_truth, optical_gaze_for, visual_axis
from eyelume.cli import app
from eyelume.compile import compile_scene
from eyelume.errors import GeometryError
from eyelume.scene.population import sample_people

runner = CliRunner()
TINY = ["--set", "sensor.cols=16", "--set", "sensor.rows=16", "--set", "sensor.pixel_pitch_um=75"]


# --- kappa -------------------------------------------------------------------------------------


@pytest.mark.parametrize("kappa", [(5.0, 0.0), (-3.0, 2.0), (13.0, -1.5)])
@pytest.mark.parametrize("gaze", [(0.0, 0.0), (15.0, -10.0), (-15.0, 10.0)])
def test_optical_gaze_puts_the_visual_axis_on_the_target(kappa, gaze):
    """The eye turned by optical_gaze_for looks at the target along its visual axis, and the
    angle between its optical and visual axes is kappa's own (a rotation keeps angles):
    cos θ = cos κv cos κh, the angle of k = axis(κh, κv) from the eye's z axis."""
    sc = eyelume.load_scene("paper2005", {"eye.kappa_deg": list(kappa)})
    gh, gv = optical_gaze_for(sc, *gaze)
    turned = eyelume.apply_overrides(
        sc, {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv}
    )
    world, angles = visual_axis(turned)
    assert angles == pytest.approx(gaze, abs=1e-8)
    assert world == pytest.approx(axis_from_angles(*gaze), abs=1e-9)  # paper2005: right eye
    optical = axis_from_angles(gh, gv)
    cos_kappa = math.cos(math.radians(kappa[1])) * math.cos(math.radians(kappa[0]))
    assert float(optical @ world) == pytest.approx(cos_kappa, abs=1e-12)


def test_kappa_zero_is_the_optical_axis_and_truth_reports_both():
    sc = eyelume.load_scene("paper2005", {"eye.gaze_horizontal_deg": 12.0})
    assert optical_gaze_for(sc, 7.0, -4.0) == (7.0, -4.0)
    t = eye_truth(compile_scene(sc), ghosts=False)
    assert t["kappa_deg"] == [0.0, 0.0]
    assert t["visual_axis"] == pytest.approx(t["optical_axis"], abs=1e-12)
    k = eyelume.apply_overrides(sc, {"eye.kappa_deg": [5.0, 1.0]})
    tk = eye_truth(compile_scene(k), ghosts=False)
    assert tk["optical_axis"] == pytest.approx(t["optical_axis"], abs=1e-12)  # same eye pose
    h, v = angles_from_axis(np.asarray(tk["visual_axis"]))
    assert (h, v) == pytest.approx(
        (tk["visual_axis_deg"]["horizontal"], tk["visual_axis_deg"]["vertical"]), abs=1e-9
    )
    assert h > 12.0 + 4.9  # nasal (+x for a right eye)


def test_a_left_eye_mirrors_the_visual_axis():
    right = eyelume.load_scene("paper2005", {"eye.kappa_deg": [5.0, 0.0]})
    left = eyelume.apply_overrides(right, {"eye_pose.which": "left"})
    wr, ar = visual_axis(right)
    wl, al = visual_axis(left)
    assert ar == pytest.approx(al)  # the file's (anatomical) angles
    assert wl == pytest.approx(wr * np.array([-1.0, 1.0, 1.0]))  # the world's, mirrored


def test_a_target_beyond_the_eye_is_refused():
    sc = eyelume.load_scene("paper2005", {"eye.kappa_deg": [12.0, 0.0]})
    with pytest.raises(GeometryError, match=r"kappa_deg.*beyond the eye's ±30°"):
        optical_gaze_for(sc, -25.0, 0.0)


@pytest.mark.parametrize("value", ["[20.0, 0.0]", "[0.0, -16.0]", "[5.0]"])
def test_bad_kappa_is_one_line_naming_the_field(value, tmp_path):
    res = runner.invoke(app, ["info", "--scene", "paper2005", "--set", f"eye.kappa_deg={value}"])
    assert res.exit_code == 2, res.output
    assert "kappa_deg" in res.output and "Traceback" not in res.output
    assert len(res.output.strip().splitlines()) == 1


def test_the_population_sets_kappa():
    scene = eyelume.load_scene("vr-offaxis")
    for p in sample_people(scene, 20, seed=4):
        assert p.scene.eye.kappa_deg == (p.values["kappa_horizontal_deg"], 0.0)


# --- a person's row and the distribution over people ---------------------------------------


def _frame(gaze, pccr, ok=True):
    det = Detection(ok=ok, failures=[] if ok else ["pupil not found"], pupil=None, glints=[])
    return Frame(gaze=gaze, detection=det, truth={}, pccr=pccr)


def _person(index, errors, ok=None):
    """A person whose test frames have PCCR errors ``errors`` (degrees, None: no estimate)."""
    ok = ok or [e is not None for e in errors]
    frames = [
        _frame((10.0 * k, 0.0), None if e is None else (10.0 * k + e, 0.0), good)
        for k, (e, good) in enumerate(zip(errors, ok, strict=True))
    ]
    rep = TrackingReport(frames, [], 0.01, {"detection_rate": float(np.mean(ok))})
    return tr.PersonResult(index, {"kappa_horizontal_deg": 5.0}, rep)


def test_tracked_means_every_gaze_detected_and_within_the_threshold():
    assert _person(0, [0.5, 1.9, 2.0]).row(2.0)["tracked"]
    assert not _person(0, [0.5, 2.01, 1.0]).row(2.0)["tracked"]
    assert not _person(0, [0.5, None, 1.0]).row(2.0)["tracked"]
    # detected but no PCCR estimate, or an estimate on a frame whose detection failed
    assert not _person(0, [0.5, 0.5], ok=[True, False]).row(2.0)["tracked"]
    row = _person(3, [1.0, None, 2.0]).row()
    assert row["score_deg"] == pytest.approx((1.0 + FAILED_FRAME_DEG + 2.0) / 3)
    assert row["pccr_mean_deg"] == pytest.approx(1.5) and row["pccr_max_deg"] == 2.0
    assert row["person"] == 3 and row["parameters"] == {"kappa_horizontal_deg": 5.0}


def test_population_summary_is_the_distribution_of_the_rows():
    rng = np.random.default_rng(2)
    people = [_person(i, list(rng.uniform(0, 3, 4))) for i in range(40)]
    rows = [p.row(2.0) for p in people]
    s = tr.population_summary(rows, 2.0)
    score = np.array([r["score_deg"] for r in rows])
    assert s["people"] == 40
    assert s["share_tracked"] == pytest.approx(np.mean([max(p) <= 2.0 for p in (
        [f.pccr[0] - f.gaze[0] for f in q.report.frames] for q in people)]))  # fmt: skip
    assert s["score_deg"]["mean"] == pytest.approx(score.mean())
    assert s["score_deg"]["p95"] == pytest.approx(np.percentile(score, 95))
    assert 0.0 < s["share_tracked"] < 1.0


# --- the command line --------------------------------------------------------------------------


@pytest.fixture()
def fake_frames(monkeypatch):
    """render_frame replaced by a stand-in: each frame's PCCR error is a function of the
    person's scene (its kappa), so rows tell people apart; what is tested is the bookkeeping."""

    def render(scene, h, v, samples, seed):
        det = Detection(ok=True, failures=[], pupil=None, glints=[])
        return Frame(gaze=(h, v), detection=det, truth={})

    calls = []

    def analyse(scene, leds, frames, calib):
        k = scene.eye.kappa_deg[0]
        for f in frames:
            f.pccr = (f.gaze[0] + 0.2 * k, f.gaze[1])
        calls.append(k)
        rep = TrackingReport(frames, calib, 0.01, {"detection_rate": 1.0})
        return rep

    monkeypatch.setattr(tr, "render_frame", render)
    monkeypatch.setattr(tr, "analyse_frames", analyse)
    return calls


def test_evaluate_tracking_population_writes_people_and_their_distribution(tmp_path, fake_frames):
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "6",
                              "--population-seed", "9", "--samples", "1", *TINY,
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    data = json.loads((out / "population.json").read_text(encoding="utf-8"))
    people = sample_people(eyelume.load_scene("vr-offaxis"), 6, 9, build_scenes=False)
    assert [r["parameters"] for r in data["people"]] == [p.values for p in people]
    tracked = [0.2 * p.values["kappa_horizontal_deg"] <= 2.0 for p in people]
    assert [r["tracked"] for r in data["people"]] == tracked
    assert data["summary"]["share_tracked"] == pytest.approx(np.mean(tracked))
    assert data["meta"]["population_seed"] == 9 and data["meta"]["population"]["size"] == 6
    lines = (out / "people.csv").read_text(encoding="utf-8").splitlines()
    assert len(lines) == 7 and lines[0].startswith("person,tracked,")
    assert "6 of 6 people: tracked" in " ".join(res.output.split())


def test_evaluate_tracking_population_keeps_the_people_finished(tmp_path, fake_frames, monkeypatch):
    import os
    import signal

    per = tr.people_frame_count()
    inner = tr.render_frame
    count = [0]

    def render(*a):
        count[0] += 1
        if count[0] == 2 * per + 3:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10**6):
                pass
        return inner(*a)

    monkeypatch.setattr(tr, "render_frame", render)
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", "--population", "5",
                              "--samples", "1", *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 143, res.output
    data = json.loads((out / "population.json").read_text(encoding="utf-8"))
    assert [r["person"] for r in data["people"]] == [0, 1]
    assert data["meta"]["partial"] == "interrupted after 2 of 5 people"


@pytest.mark.parametrize(
    ("args", "table", "words"),
    [
        (["--population", "-3"], None, ["--population -3"]),
        (["--population-seed", "2"], None, ["--population-seed"]),
        (["--population", "2", "--named-population"], None, ["--named-population"]),
        (["--population", "2", "--tracked-deg", "0"], None, ["--tracked-deg"]),
        ([], "[population]\nsize = 3\n[population.distributions.corneal_radius_mm]\nsd = -0.1",
         ["corneal_radius_mm", "sd = -0.1"]),
        ([], "[population]\n[population.distributions.pupil_diameter_mm]\nbounds = [0.2, 8.0]",
         ["pupil_diameter_mm.bounds", "physical"]),
        ([], "[population]\nsize = 0", ["size", "0"]),
        ([], "[population]\nambient = 'sunny'", ["ambient", "sunny"]),
        ([], "[population\nsize = 3", ["not valid TOML"]),
    ],
)  # fmt: skip
def test_bad_population_input_is_one_line(tmp_path, args, table, words):
    if table is not None:
        f = tmp_path / "people.toml"
        f.write_text(table, encoding="utf-8")
        args = [*args, "--population-file", str(f)]
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--scene", "vr-offaxis", *args, *TINY,
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert all(w in text for w in words), res.output
    assert "Traceback" not in res.output and not out.exists()


# --- a study's population, 1 and 2 workers -----------------------------------------------------

STUDY = """name = "people"
scene = "{scene}"
seed = 2
metrics = ["tracking", "safety"]
samples_per_pixel = 1
[[vary]]
path = "sensor.exposure_ms"
values = [2.0, 4.0]
[population]
size = 2
seed = 5
"""


@pytest.mark.slow
def test_a_study_population_gives_the_same_people_and_results_with_1_and_2_workers(tmp_path):
    """Real renders (a 24 × 24 picture of vr-offaxis, 1 sample per pixel: the numbers mean
    little, their equality everything): each run's population metrics identical with one
    worker and with two, and equal to evaluating the same people in this process."""
    from eyelume.optimize.runner import run_study
    from eyelume.optimize.study import load_study, population_metrics

    scene = eyelume.load_scene(
        "vr-offaxis",
        {"sensor.cols": 24, "sensor.rows": 24, "sensor.pixel_pitch_um": 50.0},
    )
    scene_file = tmp_path / "small.toml"
    eyelume.save_scene(scene, scene_file)
    f = tmp_path / "study.toml"
    f.write_text(STUDY.format(scene=scene_file.as_posix()), encoding="utf-8")
    study = load_study(f)
    one = run_study(study, tmp_path / "w1", workers=1)
    two = run_study(study, tmp_path / "w2", workers=2)
    m1 = [r["metrics"] for r in sorted(one, key=lambda r: r["index"])]
    m2 = [r["metrics"] for r in sorted(two, key=lambda r: r["index"])]
    assert m1 == m2
    assert all(m["population_people"] == 2 for m in m1)
    assert "tracking_score_deg" not in m1[0]  # the people, not the one eye
    here = population_metrics(eyelume.apply_overrides(scene, {"sensor.exposure_ms": 2.0}), study)
    assert {k: m1[0][k] for k in here} == here


def test_a_study_population_needs_the_tracking_metric(tmp_path):
    f = tmp_path / "study.toml"
    f.write_text(STUDY.format(scene="vr-offaxis").replace('"tracking", ', ""), encoding="utf-8")
    res = runner.invoke(app, ["study", str(f), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "population" in res.output and "tracking" in res.output
    assert "Traceback" not in res.output
