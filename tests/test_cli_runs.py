"""Runs from the command line (issue 12): a bad --out is refused before any work with one line
and exit 2; budgets beyond the model are refused; what is rendered is said; a large render
answers SIGTERM within seconds (exit 143) and writes the pixels its first round finished."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from eyelume.cli import app

runner = CliRunner()

STUDY = """
name = "s"
scene = "paper2005"
metrics = ["safety"]
[[vary]]
path = "leds.height_mm"
values = [20.0, 30.0]
"""

COMMANDS = {
    "render": ["render"],
    "sweep-leds": ["sweep-leds"],
    "reproduce": ["reproduce", "paper2005"],
    "evaluate-tracking": ["evaluate-tracking"],
    "optimize-tracking": ["optimize-tracking"],
    "study": ["study", "STUDY"],
}
#: The work each command would start with: called means the --out check came too late.
WORK = {
    "render": "eyelume.compile.compile_scene",
    "sweep-leds": "eyelume.optimize.sweep.sweep_leds",
    "reproduce": "eyelume.optimize.delta_study.run_delta_study",
    "evaluate-tracking": "eyelume.optimize.tracking.evaluate_tracking",
    "optimize-tracking": "eyelume.optimize.tracking.sweep_tracking",
    "study": "eyelume.optimize.runner.run_study",
}


def _one_line_exit_2(res):
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    assert "Traceback" not in res.output
    return lines[0]


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("kind", ["an existing file", "under a file"])
def test_a_bad_out_is_refused_before_any_work(tmp_path, monkeypatch, command, kind):
    study = tmp_path / "study.toml"
    study.write_text(STUDY, encoding="utf-8")
    blocker = tmp_path / "taken.txt"
    blocker.write_text("not a folder", encoding="utf-8")
    out = blocker if kind == "an existing file" else blocker / "out"

    def no_work(*a, **k):
        raise AssertionError("work started before --out was checked")

    module, name = WORK[command].rsplit(".", 1)
    monkeypatch.setattr(f"{module}.{name}", no_work)
    args = [a.replace("STUDY", str(study)) for a in COMMANDS[command]]
    line = _one_line_exit_2(runner.invoke(app, [*args, "--out", str(out)]))
    assert "--out" in line and str(out) in line.replace("\n", "")
    assert blocker.read_text(encoding="utf-8") == "not a folder"


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--samples", "10000000"], ["--samples 10000000", "1,000,000"]),
        (["--samples", "0"], ["--samples 0"]),
        (["--rel-error", "0.01", "--max-samples", "0"], ["--max-samples 0"]),
        (["--rel-error", "0.01", "--max-samples", "1"], ["--max-samples 1", "2 to"]),
    ],
)
def test_budgets_beyond_the_model_are_refused(tmp_path, args, words):
    line = _one_line_exit_2(runner.invoke(app, ["render", *args, "--out", str(tmp_path / "o")]))
    for w in words:
        assert w in line


def test_the_console_says_what_is_rendered(tmp_path):
    res = runner.invoke(app, ["render", "--samples", "9", "--out", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "12 samples per pixel (asked 9" in text
    assert "pilot's projection" in text


@pytest.mark.slow
def test_a_large_render_answers_sigterm_within_seconds(tmp_path):
    """1024 × 768 at 64 samples per pixel: a camera set over every pixel takes minutes here,
    so the signal lands inside the first round: exit 143 within seconds, not after the round,
    with the pixels that round finished written (the rest missing, NaN) and said so — or, if
    no chunk had finished, nothing written and said so."""
    out = tmp_path / "big"
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", "render",
           "--set", "sensor.cols=1024", "--set", "sensor.rows=768", "--samples", "64",
           "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    try:
        deadline = time.time() + 240
        line = ""
        while time.time() < deadline and "rendering" not in line:
            line = proc.stderr.readline()
            if not line and proc.poll() is not None:
                break
        assert "rendering" in line, line
        time.sleep(3.0)
        t0 = time.time()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        answered = time.time() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err
    assert answered < 20, answered  # a chunk is a fraction of a second; generous for load
    if "nothing usable" in err:
        assert not (out / "eye_image.npy").exists()
        return
    import json

    import numpy as np

    assert "interrupted in the first round" in " ".join(err.split())
    img = np.load(out / "eye_image.npy")
    finite = np.isfinite(img).reshape(-1)
    k = int(finite.sum())
    assert 0 < k < img.size and finite[:k].all()
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["interrupted"] and summary["missing_pixels"] == img.size - k


def test_a_saturated_picture_is_written_with_a_warning(tmp_path):
    out = tmp_path / "o"
    res = runner.invoke(app, ["render", "--samples", "8", "--set", "sensor.exposure_ms=2000",
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    import json

    share = json.loads((out / "summary.json").read_text())["camera"]["saturated_share"]
    assert share > 0.5  # 100× the exposure that puts skin at half scale
    text = " ".join(res.output.split())
    assert f"{share:.0%} of the camera's pixels saturate" in text


def test_a_forward_picture_saturated_by_its_few_rays_is_not_blamed_on_the_exposure(tmp_path):
    """paper2005's forward render at 2 million rays: a ray reaching a pixel is worth about
    16000 e⁻, more than the 6000 e⁻ well, so every pixel one ray reaches saturates by Monte
    Carlo noise; next to none does beyond 2 standard errors of the estimate, and the warning
    says so instead of blaming the exposure (whose nominal picture's median pixel is about a
    quarter of the well, the fast estimator's picture saturating 0.07 %:
    test_nominal_picture_has_no_saturation_warning)."""
    out = tmp_path / "o"
    res = runner.invoke(app, ["render", "--estimator", "forward", "--rays", "2000000",
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    import json

    cam = json.loads((out / "summary.json").read_text())["camera"]
    assert cam["saturated_share"] > 0.05 and cam["saturated_share_beyond_noise"] < 0.01
    text = " ".join(res.output.split())
    assert f"{cam['saturated_share']:.0%} of the camera's pixels saturate" in text
    assert "beyond the render's noise" in text and "shorten" not in text


def test_nominal_picture_has_no_saturation_warning(tmp_path):
    res = runner.invoke(app, ["render", "--samples", "8", "--out", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    assert "saturate" not in res.output


@pytest.mark.slow
def test_lost_tracking_frames_name_saturation_as_the_reason():
    import eyelume
    from eyelume.analysis.tracking.evaluate import failure_reason
    from eyelume.optimize.tracking import evaluate_tracking

    sc = eyelume.load_scene("paper2005", {"sensor.exposure_ms": 2000.0})
    rep = evaluate_tracking(sc, [0.0], [0.0], 8, 0, calibrate=False)
    s = rep.summary
    assert s["detection_rate"] == 0.0 and s["saturated_share"] > 0.5
    assert failure_reason(s).startswith("saturation: ")
    nominal = evaluate_tracking(eyelume.load_scene("paper2005"), [0.0], [0.0], 8, 0,
                                calibrate=False).summary  # fmt: skip
    assert nominal["detection_rate"] == 1.0 and failure_reason(nominal) is None


@pytest.mark.parametrize("command", ["evaluate-tracking", "optimize-tracking"])
def test_tracking_commands_refuse_a_gaze_override(tmp_path, command):
    res = runner.invoke(app, [command, "--set", "eye.gaze_horizontal_deg=10", "--out",
                              str(tmp_path / "o")])  # fmt: skip
    line = _one_line_exit_2(res)
    assert "eye.gaze_horizontal_deg" in line and "sets the gaze itself" in line
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_kernel_loading_is_timed_apart_and_first_compilation_is_said(tmp_path):
    """A new process loads the kernels (from Numba's cache here): summary.json keeps that time
    apart from the render's wall time. With an empty cache the first call compiles: the check
    behind the console's 'compiling kernels (first run only)' says so."""
    import json
    import os

    out = tmp_path / "o"
    cmd = [*(sys.executable, "-c", "from eyelume.cli import app; app()"), "render", "--samples",
           "8", "--out", str(out)]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert res.returncode == 0, res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kernel_compile_s"] > 0 and summary["wall_time_s"] > 0
    probe = "from eyelume.estimators.fast_run import kernels_cached; print(kernels_cached())"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty-cache")}
    fresh = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                           timeout=300, env=env)  # fmt: skip
    assert fresh.stdout.strip() == "False", fresh.stderr
    warm = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    assert warm.stdout.strip() == "True", warm.stderr


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["render", "--samples", "64", "--rel-error", "0.01"], ["--samples 64", "--rel-error"]),
        (["render", "--samples", "4", "--rays", "1000"], ["--rays 1000 with --samples 4"]),
        (["render", "--rel-error", "0.1", "--rays", "10"], ["--rays 10 with --rel-error 0.1"]),
        (["render", "--max-samples", "100"], ["--max-samples 100", "--rel-error"]),
        (["render", "--samples", "8", "--max-samples", "100"], ["--max-samples 100"]),
        (["sweep-leds", "--target", "T", "--delta", "0.5"], ["--delta 0.5", "--target"]),
        (["reproduce", "paper2005", "--direct", "0", "--direct-leds", "6"], ["--direct-leds 6"]),
        (["reproduce", "paper2005", "--direct", "0", "--vary-spread"], ["--vary-spread"]),
        (["reproduce", "paper2005", "--direct", "0", "--vary-azimuths"], ["--vary-azimuths"]),
        (["study", "STUDY", "--workers", "2", "--dask", "tcp://h:8786"], ["--workers 2", "--dask"]),
    ],
)
def test_contradictory_options_are_refused_before_any_work(tmp_path, monkeypatch, args, words):
    """Two options of which one would be silently ignored: one line naming them, exit 2, and
    no work started."""
    study = tmp_path / "study.toml"
    study.write_text(STUDY, encoding="utf-8")
    target = tmp_path / "t.csv"
    target.write_text("1,1\n1,1\n", encoding="utf-8")

    def no_work(*a, **k):
        raise AssertionError("work started before the options were checked")

    for dotted in (*WORK.values(), "eyelume.compile.compile_scene"):
        module, name = dotted.rsplit(".", 1)
        monkeypatch.setattr(f"{module}.{name}", no_work)
    args = [a.replace("STUDY", str(study)).replace("T", str(target)) if a in ("STUDY", "T")
            else a for a in args]  # fmt: skip
    line = _one_line_exit_2(runner.invoke(app, [*args, "--out", str(tmp_path / "o")]))
    for w in words:
        assert w in line, (w, line)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        ("grid = [20.0, nan, 3]", ["vary[0].grid[1]", "nan"]),
        ("random = [20.0, inf]\nsamples = 3", ["vary[0].random[1]", "inf"]),
        ("values = [20.0, -5]", ["vary[0].values (leds.height_mm)", "-5"]),
        ("grid = [-10.0, 30.0, 5]", ["vary[0].grid (leds.height_mm)", "-10.0"]),
        ('values = [20.0, "tall"]', ["vary[0].values (leds.height_mm)", "'tall'"]),
    ],
)
def test_a_bad_study_file_is_refused_before_the_store_is_touched(tmp_path, vary, words):
    """Every value the study would run is checked first: one line naming the study file, the
    field and the value, exit 2, and no folder or results.sqlite created."""
    study = tmp_path / "bad_study.toml"
    study.write_text(
        f'name = "s"\nmetrics = ["safety"]\n[[vary]]\npath = "leds.height_mm"\n{vary}\n',
        encoding="utf-8",
    )
    out = tmp_path / "o"
    line = _one_line_exit_2(runner.invoke(app, ["study", str(study), "--out", str(out)]))
    assert str(study) in line.replace("\n", "")
    for w in words:
        assert w in line, (w, line)
    assert not out.exists()


def test_a_finished_study_rerun_without_resume_is_one_line(tmp_path):
    """A study folder that holds finished runs, run again without --resume: the one error
    line (use --resume or a new --out), exit 2 — no banner line before it (session 34's new
    user: "study s: 2 runs into …" then the error)."""
    study = tmp_path / "st.toml"
    study.write_text(
        'name = "s"\nmetrics = ["safety"]\n[[vary]]\npath = "leds.height_mm"\n'
        "values = [20.0, 25.0]\n",
        encoding="utf-8",
    )
    out = tmp_path / "o"
    assert runner.invoke(app, ["study", str(study), "--out", str(out)]).exit_code == 0
    line = _one_line_exit_2(runner.invoke(app, ["study", str(study), "--out", str(out)]))
    assert "2 finished runs" in line and "--resume" in line, line
