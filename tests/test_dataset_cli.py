"""`eyelume dataset` (issue 17): bad input in one line with exit code 2 before anything is
written, a non-empty --out refused without --resume, SIGTERM stopping cleanly (finished pictures
and their labels kept, no worker left, exit 143) and --resume finishing the rest."""

from __future__ import annotations

import importlib
import json
import signal
import sqlite3
import subprocess
import sys
import time

import psutil
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.scene.io import load_scene, save_scene

runner = CliRunner()

TEXT = """
name = "tiny"
scene = "tiny.toml"
seed = 3
pictures = {pictures}
samples_per_pixel = 1
[[vary]]
path = "eye.pupil_diameter_mm"
range = [2.0, 7.0]
"""


def write(tmp_path, text=TEXT, pictures=3):
    sc = load_scene("vr-offaxis", {"sensor.cols": 40, "sensor.rows": 40, "sensor.width_mm": 1.2,
                                   "sensor.height_mm": 1.2})  # fmt: skip
    save_scene(sc, tmp_path / "tiny.toml")
    p = tmp_path / "ds.toml"
    p.write_text(text.format(pictures=pictures), encoding="utf-8")
    return p


@pytest.mark.parametrize(
    ("edit", "args", "words"),
    [
        (lambda t: t.replace("[2.0, 7.0]", "[2.0, 70.0]"), [], ["vary[0]", "70"]),
        (lambda t: t.replace("pictures = 3", "pictures = 'many'"), [], ["pictures"]),
        (lambda t: t, ["--workers", "0"], ["--workers 0"]),
        (lambda t: t, ["--workers", "2", "--dask", "tcp://x:1"], ["--dask"]),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, edit, args, words):
    p = write(tmp_path)
    p.write_text(edit(p.read_text(encoding="utf-8")), encoding="utf-8")
    out = tmp_path / "out"
    res = runner.invoke(app, ["dataset", str(p), "--out", str(out), *args])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    for w in words:
        assert w in lines[0]
    assert not out.exists()


def test_a_non_empty_out_is_refused_without_resume(tmp_path):
    p = write(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine", encoding="utf-8")
    res = runner.invoke(app, ["dataset", str(p), "--out", str(out)])
    assert res.exit_code == 2 and "not empty" in res.output and "--resume" in res.output
    assert sorted(x.name for x in out.iterdir()) == ["notes.txt"]


@pytest.mark.slow
def test_sigterm_keeps_the_finished_pictures_and_resume_finishes(tmp_path):
    p = write(tmp_path, pictures=8)
    out = tmp_path / "out"
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", "dataset", str(p),
           "--out", str(out), "--workers", "2"]  # fmt: skip
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    db, n, workers = out / "results.sqlite", 0, []
    try:
        deadline = time.time() + 300
        while time.time() < deadline and proc.poll() is None and n < 2:
            try:
                with sqlite3.connect(f"{db.absolute().as_uri()}?mode=ro", uri=True) as con:
                    n = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
            except sqlite3.OperationalError:
                n = 0
            time.sleep(0.05)
        workers = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
        proc.send_signal(signal.SIGTERM)  # the command only, as a service manager does
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=30)
    assert proc.returncode == 143, err
    assert "--resume" in err and "Traceback" not in err
    deadline = time.time() + 15
    while time.time() < deadline and any(psutil.pid_exists(w) and psutil.Process(w).status()
                                         != psutil.STATUS_ZOMBIE for w in workers):  # fmt: skip
        time.sleep(0.2)
    assert not any(psutil.pid_exists(w) and psutil.Process(w).status() != psutil.STATUS_ZOMBIE
                   for w in workers), "workers outlived the command"  # fmt: skip
    labels = (out / "labels.jsonl").read_text(encoding="utf-8").splitlines()
    done = [json.loads(x)["index"] for x in labels]
    assert 2 <= len(done) < 8 and done == sorted(done)
    for i in done:
        assert (out / "images" / f"{i:06d}.png").is_file()
    res = runner.invoke(app, ["dataset", str(p), "--out", str(out), "--resume", "--workers", "1"])
    assert res.exit_code == 0, res.output
    labels = (out / "labels.jsonl").read_text(encoding="utf-8").splitlines()
    assert [json.loads(x)["index"] for x in labels] == list(range(8))


STUDY = """
name = "s"
scene = "tiny.toml"
metrics = ["safety"]
[[vary]]
path = "leds.height_mm"
values = [20.0, 30.0]
"""


@pytest.mark.parametrize("address", ["nonsense:1", "foo://bar"])
@pytest.mark.parametrize("command", ["dataset", "study"])
def test_an_unreachable_or_malformed_dask_address_is_one_line_exit_2_within_seconds(
    tmp_path, command, address
):
    """Dask's own client waits 30 s and more for a scheduler that is not there (a fresh user
    saw the command hang): the runner's connect timeout refuses it in a few seconds, naming
    --dask and the address, from both commands (the same executor code)."""
    p = write(tmp_path, pictures=2)
    if command == "study":
        p = tmp_path / "study.toml"
        p.write_text(STUDY, encoding="utf-8")
    t0 = time.monotonic()
    res = runner.invoke(app, [command, str(p), "--out", str(tmp_path / "out"), "--dask", address])
    seconds = time.monotonic() - t0
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    assert f"--dask {address}" in lines[0] and "Traceback" not in res.output
    assert seconds < 20, f"{seconds:.0f} s to refuse --dask {address}"
    assert not (tmp_path / "out").exists()  # refused before anything is written


def test_resume_into_another_datasets_folder_is_refused_before_any_render(tmp_path, monkeypatch):
    """--resume into a folder of another dataset file: one line, exit 2, before the opening
    line and before any render (a fresh user waited ~27 s for the refusal)."""
    from eyelume.optimize import dataset as D

    p = write(tmp_path, pictures=2)
    out = tmp_path / "out"
    out.mkdir()
    ds = D.load_dataset(p)
    D._prepare(ds, D.bases(ds), out, resume=False)  # the folder as `eyelume dataset` begins it
    other = tmp_path / "other.toml"
    other.write_text(p.read_text(encoding="utf-8").replace("seed = 3", "seed = 4"), "utf-8")

    def no_render(*args, **kwargs):
        raise AssertionError("rendered before refusing the folder")

    monkeypatch.setattr(importlib.import_module("eyelume.render"), "render", no_render)
    monkeypatch.setattr("eyelume.optimize.runner.run_tasks", no_render)
    before = sorted(x.name for x in out.iterdir())
    res = runner.invoke(app, ["dataset", str(other), "--out", str(out), "--resume"])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:"), res.output
    assert "another dataset" in lines[0] and "differs in seed" in lines[0]
    assert f"{out}: {out}" not in lines[0]  # the folder named once
    assert sorted(x.name for x in out.iterdir()) == before


def test_a_first_run_says_it_compiles_the_kernels_before_it_does(tmp_path, monkeypatch):
    """On a fresh machine the kernels' compilation is a minute of silence: `dataset` says so in
    one line, as `render` does (its _warm_up), and compiles them in the parent before the
    workers start (they then load them from the shared cache)."""
    import eyelume.estimators.fast_run as fast_run
    from eyelume.optimize import dataset as D

    calls = []
    monkeypatch.setattr(fast_run, "kernels_cached", lambda *a: False)
    monkeypatch.setattr(fast_run, "warm_up", lambda cs: calls.append("warm_up") or 0.0)

    def run(*args, **kwargs):
        calls.append("run_dataset")
        return 0

    monkeypatch.setattr(D, "run_dataset", run)
    p = write(tmp_path, pictures=2)
    res = runner.invoke(app, ["dataset", str(p), "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    assert "compiling kernels (first run only" in res.output
    assert calls == ["warm_up", "run_dataset"]


def test_study_and_dataset_share_their_executor_options():
    """--resume, --workers, --dask and --lock-timeout are one set of options (cli.py's shared
    Annotated aliases): the same names, defaults and help in `study` and `dataset`."""
    import typer

    commands = typer.main.get_command(app).commands
    shared = ("resume", "workers", "dask", "lock_timeout")

    def options(name):
        params = {p.name: p for p in commands[name].params}
        return {k: (params[k].opts, params[k].default, params[k].help) for k in shared}

    assert options("study") == options("dataset")


def test_a_file_that_is_not_text_is_refused_naming_the_byte(tmp_path):
    """A fresh user's file with bytes 0x81 0x90 (neither UTF-8 nor Windows-1252) was read with
    U+FFFD in their place and the dataset started."""
    p = write(tmp_path)
    p.write_bytes(b'name = "x\x81\x90"\n' + p.read_bytes().split(b"\n", 2)[2])
    out = tmp_path / "out"
    res = runner.invoke(app, ["dataset", str(p), "--out", str(out)])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "ds.toml" in lines[0] and "byte 0x81" in lines[0], res.output
    assert not out.exists()
    p.write_bytes('name = "café"\n'.encode("cp1252") + p.read_bytes().split(b"\n", 1)[1])
    from eyelume.optimize.dataset import load_dataset

    assert load_dataset(p).name == "café"  # Windows-1252 text is still read


def test_resume_with_fewer_pictures_is_refused(tmp_path, monkeypatch):
    """Lowering `pictures` on --resume rewrote labels.jsonl and dataset.json for the first
    pictures only, the others' files left unlabelled: refused in one line now."""
    from eyelume.optimize import dataset as D

    p = write(tmp_path, pictures=4)
    out = tmp_path / "out"
    out.mkdir()
    ds = D.load_dataset(p)
    D._prepare(ds, D.bases(ds), out, resume=False)
    fewer = tmp_path / "fewer.toml"
    fewer.write_text(p.read_text(encoding="utf-8").replace("pictures = 4", "pictures = 2"), "utf-8")
    monkeypatch.setattr("eyelume.optimize.runner.run_tasks", None)  # nothing may run
    before = sorted(x.name for x in out.iterdir())
    res = runner.invoke(app, ["dataset", str(fewer), "--out", str(out), "--resume"])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and "pictures = 4" in lines[0] and "pictures = 2" in lines[0]
    assert sorted(x.name for x in out.iterdir()) == before
    more = tmp_path / "more.toml"
    more.write_text(p.read_text(encoding="utf-8").replace("pictures = 4", "pictures = 6"), "utf-8")
    D.check_out(D.load_dataset(more), out, resume=True)  # adding pictures stays allowed


def test_ctrl_c_during_the_first_compilation_exits_130_in_one_line(monkeypatch):
    """Numba turned a Ctrl-C inside an LLVM callback into RuntimeError('no compiled object
    yet'): a 344-line traceback and exit 1. An error without a signal still propagates."""
    import os
    import signal

    import typer

    import eyelume.cli as cli

    def compile_interrupted():
        os.kill(os.getpid(), signal.SIGINT)  # handled at once, in the main thread
        raise AssertionError("not reached")

    def numba_swallowed():
        try:
            os.kill(os.getpid(), signal.SIGINT)
        except KeyboardInterrupt:
            raise RuntimeError("no compiled object yet for <Library '_camera_branch'>") from None

    for fn in (compile_interrupted, numba_swallowed):
        with pytest.raises(typer.Exit) as exc:
            cli._interruptible_compile(fn)
        assert exc.value.exit_code == 130

    def broken():
        raise RuntimeError("a real failure")

    with pytest.raises(RuntimeError, match="a real failure"):
        cli._interruptible_compile(broken)
