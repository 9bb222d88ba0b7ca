"""A fresh user's findings on the command line: `info` without --json is text, --json is JSON;
messages name the option that is wrong (and the real one to use); a broken pipe (`| head -1`)
loses no outputs and exits quietly with 0; no stray blank line where stderr is no terminal."""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from eyelume.cli import app

runner = CliRunner()

PLATE = (
    'elements=[{kind="plate", name="w", position_mm=[0, 0, 20], thickness_mm=3, '
    'glass="N-BK7", semi_diameter_mm=18}]'
)


def test_info_prints_text_and_info_json_prints_json():
    text = runner.invoke(app, ["info"])
    as_json = runner.invoke(app, ["info", "--json"])
    assert text.exit_code == 0 and as_json.exit_code == 0, (text.output, as_json.output)
    assert text.stdout != as_json.stdout
    data = json.loads(as_json.stdout)
    with pytest.raises(json.JSONDecodeError):
        json.loads(text.stdout)
    lines = text.stdout.splitlines()
    assert "scene: paper2005" in lines
    efl = data["imaging_lens"]["effective_focal_length_mm"]
    assert f"  effective_focal_length_mm: {efl:.6g}" in lines


def _one_line(res) -> str:
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1, lines
    assert "Traceback" not in res.output
    return lines[0]


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--samples", "4", "--estimator", "forward"], ["--samples 4", "traces rays", "--rays"]),
        (["--rel-error", "0.1", "--estimator", "forward"], ["--rel-error 0.1", "--rays"]),
        (["--rays", "100", "--estimator", "fast"], ["--rays 100", "--samples"]),
        (["--samples", "0"], ["--samples 0: must be 1 to"]),
        (["--rays", "0"], ["--rays 0: must be ≥ 1"]),
    ],
)
def test_render_option_messages_name_the_real_option(tmp_path, args, words):
    line = _one_line(runner.invoke(app, ["render", "--out", str(tmp_path / "o"), *args]))
    assert all(w in line for w in words), line
    if "forward" in args:
        assert "with --estimator fast" not in line  # the old message told forward to use fast


@pytest.mark.parametrize(
    ("args", "named", "not_named"),
    [
        (["--samples", "0"], "--samples 0", "--seed"),
        (["--seed", "-1"], "--seed -1", "--samples"),
    ],
)
@pytest.mark.parametrize("command", ["evaluate-tracking", "optimize-tracking", "reproduce"])
def test_counts_name_the_option_that_is_wrong(tmp_path, command, args, named, not_named):
    head = [command, "paper2005"] if command == "reproduce" else [command]
    line = _one_line(runner.invoke(app, [*head, "--out", str(tmp_path / "o"), *args]))
    assert named in line and not_named not in line, line


CONVERGING = (
    'elements=[{kind="lens", name="eyepiece", position_mm=[0, 0, 20], thickness_mm=4, '
    'glass="N-BK7", semi_diameter_mm=15, front={radius_mm=60}, back={radius_mm=-60}}]'
)


@pytest.mark.parametrize(
    ("command", "element", "says"),
    [
        ("optimize-tracking", PLATE, "places LEDs by the paper's generator"),
        ("sweep-leds", PLATE, "places LEDs by the paper's generator"),
        ("evaluate-tracking", CONVERGING, "is a converging lens that takes"),
    ],
)
def test_tracking_with_elements_names_no_option_it_lacks(tmp_path, command, element, says):
    """optimize-tracking's generator lights the eye plane in free space, so it refuses any
    element — and so does sweep-leds, the generator itself, which swept without them saying
    nothing (its landscape and best placement were the free-space eye's); the refusal holds
    for any scene (it quoted paper2005-integrated's counts whatever the scene).
    evaluate-tracking renders with the fast estimator, which refuses a converging lens before
    paper2005's LED ring (it takes ~24 % of their light first): it advises moving the LEDs
    or taking the lens out, not a forward render (hundreds of frames at a tracking budget:
    noise). None names '--estimator forward'; and the progress bar left no blank line before
    the error where stderr is no terminal."""
    res = runner.invoke(app, [command, "--out", str(tmp_path / "o"), "--set", element])
    line = _one_line(res)
    assert res.output.startswith("error:"), repr(res.output)  # no blank line first
    assert says in line and "elements.0" in line, line
    assert "--estimator forward" not in line, line
    assert "paper2005-integrated 25" not in line, line
    if command == "evaluate-tracking":
        assert "move the LEDs so that less of their light meets elements.0 first" in line, line
    assert not (tmp_path / "o").exists()


def _cli(args: list[str], tmp_path) -> list[str]:
    return [sys.executable, "-c", "from eyelume.cli import app; app()", *args]


def test_a_broken_pipe_loses_no_outputs_and_exits_0(tmp_path):
    """`eyelume render … 2>&1 | head -1` exited 1 at its first message, writing nothing."""
    out = tmp_path / "o"
    args = ["render", "--out", str(out), "--rays", "20000", "--seed", "1"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen(
        _cli(args, tmp_path), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env
    )
    assert proc.stdout is not None
    first = proc.stdout.readline()
    proc.stdout.close()  # what `head -1` does
    assert proc.wait(timeout=600) == 0
    assert first.strip()
    assert (out / "summary.json").is_file() and (out / "eye_image.npy").is_file()

    info = subprocess.Popen(
        _cli(["info"], tmp_path), stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env
    )
    assert info.stdout is not None and info.stderr is not None
    info.stdout.close()  # before it writes: its output meets a closed pipe
    errors = info.stderr.read()
    assert info.wait(timeout=600) == 0
    assert b"Traceback" not in errors and b"BrokenPipe" not in errors, errors


def test_wavelengths_within_the_tolerance_are_one_group():
    """850 and 850.0000001 nm made two wavelength groups (a whole render each)."""
    from eyelume.compile import WAVELENGTH_TOLERANCE_NM, single_wavelength, wavelength_groups
    from eyelume.scene.io import load_scene

    near = load_scene("paper2005", {"leds.wavelength_nm": [850, 850.0000001, 850, 849.995]})
    assert single_wavelength(near)
    assert [(g.wavelength_nm, g.leds) for g in wavelength_groups(near)] == [(850.0, (0, 1, 2, 3))]
    apart = 850 + 2 * WAVELENGTH_TOLERANCE_NM
    far = load_scene("paper2005", {"leds.wavelength_nm": [850, apart, 850, 850]})
    assert not single_wavelength(far)
    assert [g.leds for g in wavelength_groups(far)] == [(0, 2, 3), (1,)]
    res = runner.invoke(
        app, ["info", "--json", "--set", "leds.wavelength_nm=[850, 850.0000001, 850, 850]"]
    )
    assert res.exit_code == 0 and "wavelength_groups" not in json.loads(res.stdout)


def test_the_time_projection_counts_every_wavelength_group(tmp_path, monkeypatch):
    """16 wavelength groups were projected '~1 s' and took 8.6 s: each group is a render."""
    import eyelume.estimators.fast_run as fast_run

    render_module = importlib.import_module("eyelume.render")  # eyelume.render: the function
    monkeypatch.setattr(fast_run, "pilot_rates", lambda cs, seed, grid: (1e4, 1e30))

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(render_module, "render", stop)
    said = {}
    for lams in ("[850, 850, 850, 850]", "[850, 900, 940, 980]"):
        res = runner.invoke(
            app,
            ["render", "--out", str(tmp_path / "o"), "--estimator", "fast", "--samples", "8",
             "--set", f"leds.wavelength_nm={lams}"],
        )  # fmt: skip
        assert res.exit_code == 130, res.output
        said[lams] = " ".join(res.stderr.split())  # unwrapped
    # 8 samples × 87 × 65 pixels at 1e4 camera samples per second: 4.5 s a render
    assert "~5 s and" in said["[850, 850, 850, 850]"]
    assert "~18 s (4 wavelength groups, a render each)" in said["[850, 900, 940, 980]"]


def test_progress_lines_without_a_terminal_keep_every_announcement():
    """Piped, later wavelength groups' announcements were throttled away and the last line
    carried a stale label at 100 %."""
    import io

    from rich.console import Console

    from eyelume.cli import _Progress

    sink = io.StringIO()
    bar = _Progress("{task.description}", "{task.percentage:>3.0f}%", announce=True,
                    console=Console(file=sink, force_terminal=False), disable=True)  # fmt: skip
    with bar:
        task = bar.add_task("", total=4)
        for g in range(4):
            bar.update(task, description=f"group {g + 1}")
            bar.update(task, completed=g + 1)
            bar.update(task, description=f"group {g + 1} done")
    lines = sink.getvalue().splitlines()
    for g in range(1, 4):
        assert any(ln.startswith(f"group {g} ") for ln in lines), lines
    finished = [ln for ln in lines if "100%" in ln]
    assert len(finished) == 1 and finished[0].startswith("group 4 done 100%"), lines


def test_the_defocus_warning_names_each_groups_wavelength():
    res = runner.invoke(app, ["info", "--json", "--set", "leds.wavelength_nm=[800, 830, 850, 850]"])
    assert res.exit_code == 0, res.output
    warns = [ln for ln in res.stderr.splitlines() if ln.startswith("warning: lens:")]
    assert warns and len(warns) == len(set(warns)), res.stderr
    assert all(" nm the sensor" in w for w in warns), warns
    assert any("at 800 nm" in w for w in warns), warns


@pytest.mark.parametrize(
    ("scale", "exit_code", "words"),
    [
        (1e-8, 0, '"ok": true'),  # a render's irradiance in W/mm²
        (1e-20, 2, "no usable signal: the largest value is 1e-20"),
        (0.0, 2, "no light: no pixel is above 0"),
    ],
)
def test_track_refuses_a_picture_with_no_usable_signal(tmp_path, scale, exit_code, words):
    """A picture of ~1e-20 values was 'tracked': its glints lost, its pupil mis-sized, exit 0."""
    from tests.analysis.test_detect import draw_eye

    picture = draw_eye().astype(np.float64)
    path = tmp_path / "eye.npy"
    np.save(path, picture / picture.max() * scale)
    res = runner.invoke(app, ["track", str(path), "--leds", "0,90,180,270"])
    assert res.exit_code == exit_code, res.output
    if exit_code == 2:
        line = _one_line(res)
        assert words in line and "eye.npy" in line, line
    else:
        assert words in res.stdout


def test_the_study_command_plans_its_runs_once(tmp_path, monkeypatch):
    """`eyelume study` planned the runs three times (the study's check, the banner's count,
    the runner); a Latin-hypercube or random study of 10⁵ runs paid for each."""
    from eyelume.optimize import study as study_module

    made = []
    plan = study_module._plan
    monkeypatch.setattr(study_module, "_plan", lambda st: made.append(st.name) or plan(st))
    monkeypatch.setattr(study_module, "_LAST_PLAN", None)
    path = tmp_path / "study.toml"
    path.write_text(
        'name = "once"\nscene = "paper2005"\nmetrics = ["eye_plane_merit"]\nseed = 3\n'
        '[[vary]]\npath = "leds.height_mm"\nrandom = [20.0, 40.0]\nsamples = 2\n',
        encoding="utf-8",
    )
    res = runner.invoke(app, ["study", str(path), "--out", str(tmp_path / "o"), "--workers", "1"])
    assert res.exit_code == 0, res.output
    assert made == ["once"]
    assert "2/2 runs" in res.stderr
    # the plan is the same list each call, fresh dicts (a caller's change does not leak)
    st = study_module.load_study(path)
    first = study_module.plan_runs(st)
    first[0]["leds.height_mm"] = -1.0
    assert study_module.plan_runs(st) == plan(st) and len(made) == 1


@pytest.mark.parametrize("cached", [False, True])
def test_track_says_so_before_the_detectors_first_compilation(tmp_path, monkeypatch, cached):
    """On a fresh machine the first `track` compiled the detector's Numba passes in silence
    (43 s at load 13). The probe itself: a Numba cache dir that holds nothing reads False."""
    import eyelume.cli as cli
    from tests.analysis.test_detect import draw_eye

    monkeypatch.setattr(cli, "_detect_kernels_cached", lambda: cached)
    path = tmp_path / "eye.npy"
    np.save(path, draw_eye().astype(np.float64))
    res = runner.invoke(app, ["track", str(path), "--leds", "0,90,180,270"])
    assert res.exit_code == 0, res.output
    said = "compiling detection kernels (first run only" in res.stderr
    assert said is not cached, res.stderr


def test_the_detector_cache_probe_reads_an_empty_cache_as_a_first_run(tmp_path):
    code = "from eyelume.cli import _detect_kernels_cached as p; print(p())"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "False", out


@pytest.mark.parametrize("command", ["optimize-tracking", "reproduce", "sweep-leds"])
def test_generator_commands_refuse_the_integrated_preset_with_the_reason(tmp_path, command):
    """optimize-tracking and reproduce move the paper's ring over the generator's grid, whose
    eye plane is lit in free space: on paper2005-integrated (an eyepiece and a hot mirror)
    their placements lie behind or beside the elements (6 of optimize-tracking's 27 in the
    camera's body, 19 lighting the eye through the eyepiece: measured with
    compile.element_light_shares), so they refuse it in one line, exit 2, saying why and what
    judges a placement instead — before any work."""
    head = [command, "paper2005-integrated"] if command == "reproduce" else [command]
    scene = [] if command == "reproduce" else ["--scene", "paper2005-integrated"]
    res = runner.invoke(app, [*head, *scene, "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    line = _one_line(res)
    assert "elements.0 (eyepiece), elements.1 (hot mirror)" in line, line
    assert "lit in free space" in line and "behind, inside or beside" in line, line
    assert "eyelume evaluate-tracking --set leds.distance_mm" in line, line
    assert not (tmp_path / "o").exists()


def test_optimize_tracking_refuses_a_camera_that_sees_no_eye(tmp_path):
    """paper2005-integrated without its elements (the element refusal's own hint) has a camera
    looking at nothing: optimize-tracking scored 29 placements inf° and named one
    'tracking-optimal', exit 0, where render and evaluate-tracking refuse the scene."""
    out = tmp_path / "o"
    res = runner.invoke(
        app,
        ["optimize-tracking", "--scene", "paper2005-integrated", "--set", "elements=[]",
         "--out", str(out)],
    )  # fmt: skip
    assert res.exit_code == 2, res.output
    line = _one_line(res)
    assert "camera: sees no eye" in line, line
    assert not out.exists()
