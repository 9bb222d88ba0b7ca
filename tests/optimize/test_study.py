"""Studies: planning, a result store that survives kill -9, resume, refusal of a busy folder,
and identical results whatever the number of workers."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pytest

from eyelume.optimize.runner import run_study
from eyelume.optimize.store import ResultStore, StoreBusy
from eyelume.optimize.study import load_study, plan_runs
from eyelume.scene.io import SceneError

FAST = """
name = "fast"
scene = "paper2005"
seed = 3
metrics = ["eye_plane_merit", "safety"]
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, 3]
[[vary]]
path = "leds.distance_mm"
random = [50.0, 70.0]
samples = 2
"""

SLOW = """
name = "slow"
scene = "paper2005"
seed = 1
metrics = ["eye_image_merit", "safety"]
samples_per_pixel = 8
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, 8]
"""


def write(tmp_path, text, name="study.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def table(folder):
    return {r["key"]: (r["index"], r["overrides"], r["metrics"]) for r in _rows(folder)}


def _rows(folder):
    store = ResultStore(folder)
    try:
        return store.rows()
    finally:
        store.close()


def test_plan_is_the_product_and_seeded(tmp_path):
    st = load_study(write(tmp_path, FAST))
    runs = plan_runs(st)
    assert len(runs) == 6
    assert runs == plan_runs(st)  # the random draws come from the study's seed
    assert {r["leds.height_mm"] for r in runs} == {20.0, 30.0, 40.0}


def test_latin_hypercube_covers_each_stratum(tmp_path):
    text = FAST.replace("random = [50.0, 70.0]\nsamples = 2", "latin = [50.0, 70.0]\nsamples = 5")
    runs = plan_runs(load_study(write(tmp_path, text)))
    z = sorted({r["leds.distance_mm"] for r in runs})
    assert len(z) == 5
    assert [int((v - 50.0) / 4.0) for v in z] == [0, 1, 2, 3, 4]  # one draw per fifth


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda t: t.replace('path = "leds.height_mm"', 'path = "leds.nope"'), ["leds.nope"]),
        (lambda t: t.replace("grid = [20.0, 40.0, 3]", "grid = [20.0, 40.0, 3]\nvalues = [1]"),
         ["exactly one"]),
        (lambda t: t.replace('metrics = ["eye_plane_merit", "safety"]', 'metrics = ["magic"]'),
         ["metrics"]),
        # 10⁸ runs: refused at once (it used to build the list of runs silently for minutes)
        (lambda t: t.replace("grid = [20.0, 40.0, 3]", "grid = [20.0, 40.0, 100000000]"),
         ["field 'vary'", "200,000,000 runs", "more than 100,000"]),
    ],
)  # fmt: skip
def test_bad_study_files_name_the_problem(tmp_path, edit, words):
    with pytest.raises(SceneError) as exc:
        load_study(write(tmp_path, edit(FAST)))
    for w in words:
        assert w in str(exc.value)


@pytest.mark.slow
def test_same_results_with_one_or_two_workers(tmp_path):
    st = load_study(write(tmp_path, FAST))
    run_study(st, tmp_path / "a", workers=1)
    run_study(st, tmp_path / "b", workers=2)
    assert table(tmp_path / "a") == table(tmp_path / "b")


def test_a_busy_folder_is_refused(tmp_path):
    holder = ResultStore(tmp_path / "busy")
    try:
        with pytest.raises(StoreBusy, match=r"another eyelume run \(study or dataset\)"):
            ResultStore(tmp_path / "busy")
    finally:
        holder.close()


@pytest.mark.slow
def test_kill_9_then_resume_equals_an_uninterrupted_run(tmp_path):
    study = write(tmp_path, SLOW)
    killed = tmp_path / "killed"
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", "study", str(study),
           "--out", str(killed), "--workers", "1"]  # fmt: skip
    proc = subprocess.Popen(cmd, start_new_session=True, stderr=subprocess.DEVNULL)
    db = killed / "results.sqlite"
    deadline = time.time() + 240
    n = 0
    while time.time() < deadline:
        if db.exists():
            try:
                with sqlite3.connect(db) as con:
                    n = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
            except sqlite3.OperationalError:
                n = 0
        if n >= 2 or proc.poll() is not None:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)  # the study and its workers, mid-run
    proc.wait()
    assert 2 <= n < 8, n
    st = load_study(study)
    with pytest.raises(ValueError, match="--resume"):
        run_study(st, killed, workers=1)
    run_study(st, killed, workers=1, resume=True)
    run_study(st, tmp_path / "clean", workers=1)
    assert table(killed) == table(tmp_path / "clean")
    assert len(table(killed)) == 8


@pytest.mark.slow
def test_a_local_dask_cluster_gives_the_same_results(tmp_path):
    """A real scheduler and two worker processes (distributed.LocalCluster) run the study;
    the store equals the local pool's, row for row."""
    st = load_study(write(tmp_path, FAST))
    run_study(st, tmp_path / "pool", workers=2)
    run_study(st, tmp_path / "dask", workers=2, dask="local")
    assert table(tmp_path / "pool") == table(tmp_path / "dask")


@pytest.mark.slow
def test_tracking_metric_of_one_run():
    """The tracking metric: the pipeline's mean geometric gaze error over 9 gazes (a lost frame
    counted 10°) and the detection rate, with the safety margins beside them."""
    import eyelume
    from eyelume.optimize.study import Study, run_metrics

    st = Study(name="t", metrics=["tracking", "safety"], samples_per_pixel=8)
    m = run_metrics(eyelume.load_scene("paper2005"), {"leds.pitch_deg": 20.0}, st)
    assert 0 <= m["tracking_score_deg"] <= 10 and 0 <= m["detection_rate"] <= 1
    assert m["within_exempt_group"] and m["corneal_margin"] > 1


@pytest.mark.slow
def test_glints_metric_of_one_run():
    """The glints metric on the off-axis preset: over the ±20° × ±15° gaze grid, some gazes
    lose glints off the cornea (the camera is 50° off the eye's axis), primary gaze none."""
    import eyelume
    from eyelume.analysis.truth import glint_counts
    from eyelume.optimize.study import Study, run_metrics

    scene = eyelume.load_scene("vr-offaxis")
    m = run_metrics(scene, {}, Study(name="g", scene="vr-offaxis", metrics=["glints"]))
    counts = np.asarray(glint_counts(scene)["visible"], dtype=float)
    assert m["glints_visible_min"] == counts.min() < 8
    assert m["glints_visible_mean"] == pytest.approx(counts.mean())
    assert 0 < m["gaze_share_all_glints"] < 1


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_runs_and_resume_completes(tmp_path):
    study = write(tmp_path, SLOW.replace("grid = [20.0, 40.0, 8]", "grid = [20.0, 40.0, 40]"))
    out = tmp_path / "out"
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", "study", str(study),
           "--out", str(out), "--workers", "2"]  # fmt: skip
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    db = out / "results.sqlite"
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None:
        if db.exists():
            try:
                with sqlite3.connect(db) as con:
                    if con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] >= 2:
                        break
            except sqlite3.OperationalError:
                pass
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "--resume" in err
    done = len(table(out))
    assert 2 <= done < 40
    run_study(load_study(study), out, workers=2, resume=True)
    assert len(table(out)) == 40
