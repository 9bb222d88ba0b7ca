"""Studies as processes and their store under stress (issue 12): a report of a study still
running or of a read-only folder, SIGTERM handled like Ctrl-C with no worker left behind (nor
after kill -9 of the parent alone), another program holding the write lock, a relative scene
path, a damaged results.sqlite. Every process is a subprocess with a timeout, ended by pid."""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

import psutil
import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.errors import StoreError
from eyelume.optimize import store as store_mod
from eyelume.optimize.runner import run_study
from eyelume.optimize.store import StoreLocked, read_rows
from eyelume.optimize.study import load_study

runner = CliRunner()

SLOW = """
name = "slow"
scene = "paper2005"
seed = 1
metrics = ["eye_image_merit", "safety"]
samples_per_pixel = 8
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, 30]
"""

FAST = """
name = "fast"
scene = "paper2005"
metrics = ["eye_plane_merit", "safety"]
[[vary]]
path = "leds.height_mm"
values = [20.0, 30.0, 40.0]
"""

CLI = [sys.executable, "-c", "from eyelume.cli import app; app()"]


def _write(tmp_path, text, name="study.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def _committed(db):
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(f"{db.absolute().as_uri()}?mode=ro", uri=True) as con:
            return con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    except sqlite3.OperationalError:
        return 0


def _start_study(study, out, workers=2):
    cmd = [*CLI, "study", str(study), "--out", str(out), "--workers", str(workers)]
    return subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)


def _wait_for_runs(proc, db, n, timeout=300):
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None:
        if _committed(db) >= n:
            return
        time.sleep(0.1)
    raise AssertionError(f"the study did not commit {n} runs (exit {proc.poll()})")


def _gone(pids, timeout=15.0):
    """The pids among ``pids`` still alive (not zombies) after up to ``timeout`` s."""
    deadline = time.time() + timeout
    alive = list(pids)
    while alive and time.time() < deadline:
        alive = [p for p in alive if psutil.pid_exists(p) and
                 psutil.Process(p).status() != psutil.STATUS_ZOMBIE]  # fmt: skip
        time.sleep(0.2)
    return alive


def _pool_workers():
    """This process's multiprocessing workers (not its resource tracker)."""
    return [c.pid for c in psutil.Process().children(recursive=True)
            if "spawn_main" in " ".join(c.cmdline())]  # fmt: skip


def _end(proc):
    if proc.poll() is None:
        proc.kill()
        proc.wait(timeout=30)


@pytest.mark.slow
def test_sigterm_keeps_what_is_committed_ends_the_workers_and_report_reads_meanwhile(tmp_path):
    study, out = _write(tmp_path, SLOW), tmp_path / "out"
    proc = _start_study(study, out)
    workers = []
    try:
        _wait_for_runs(proc, out / "results.sqlite", 2)
        workers = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
        assert workers, "no worker processes"
        # the study is running and holds the folder's lock: report reads what is committed
        res = runner.invoke(app, ["report", str(out), "--out", str(tmp_path / "mid.html")])
        assert res.exit_code == 0, res.output
        assert "runs committed" in (tmp_path / "mid.html").read_text(encoding="utf-8")
        proc.send_signal(signal.SIGTERM)  # the parent only, as a service manager does
        _, err = proc.communicate(timeout=60)
    finally:
        _end(proc)
    assert proc.returncode == 143, err
    assert "--resume" in err and "Traceback" not in err
    assert _gone(workers) == [], "workers outlived their study"
    done = len(read_rows(out)[0])
    assert 2 <= done < 30
    run_study(load_study(study), out, workers=2, resume=True)
    assert len(read_rows(out)[0]) == 30


@pytest.mark.slow
def test_kill_9_of_the_parent_alone_leaves_no_worker(tmp_path):
    study, out = _write(tmp_path, SLOW), tmp_path / "out"
    proc = _start_study(study, out)
    workers = []
    try:
        _wait_for_runs(proc, out / "results.sqlite", 1)
        workers = [c.pid for c in psutil.Process(proc.pid).children(recursive=True)]
        assert workers
        proc.send_signal(signal.SIGKILL)  # no handler runs: the workers must notice alone
        proc.wait(timeout=30)
        assert _gone(workers) == [], "orphaned workers"
    finally:
        _end(proc)
        for pid in _gone(workers, timeout=0):  # never leave one behind, even on failure
            os.kill(pid, signal.SIGKILL)


@pytest.mark.slow
def test_another_program_holding_the_write_lock_stops_the_study_at_once(tmp_path):
    study = load_study(_write(tmp_path, SLOW.replace("30]", "6]")))
    out = tmp_path / "out"
    holder = []

    def lock_after_first(done, total):
        if done >= 1 and not holder:  # another program takes the write lock and keeps it
            code = ("import sqlite3, sys, time; c = sqlite3.connect(sys.argv[1], "
                    "isolation_level=None); c.execute('BEGIN IMMEDIATE'); print('locked', "
                    "flush=True); time.sleep(120)")  # fmt: skip
            p = subprocess.Popen([sys.executable, "-c", code, str(out / "results.sqlite")],
                                 stdout=subprocess.PIPE, text=True)  # fmt: skip
            holder.append(p)
            assert p.stdout.readline().strip() == "locked"
            holder.append(time.time())
            holder.append(_pool_workers())

    waits = []
    try:
        with pytest.raises(StoreLocked, match="--resume continues") as exc:
            run_study(study, out, workers=1, progress=lock_after_first, lock_timeout_s=1.0,
                      note=waits.append)  # fmt: skip
        stopped = time.time() - holder[1]
        assert "results.sqlite" in str(exc.value) and len(str(exc.value).splitlines()) == 1
        assert waits and "write lock" in waits[0]
        # one run in flight may finish first; then 5 s of SQLite's wait + the 1 s asked
        assert stopped < 6.0 + 30, stopped
        assert holder[2], "no pool worker seen"
        assert _gone(holder[2], timeout=5) == [], "workers left computing runs to throw away"
    finally:
        if holder:
            holder[0].kill()
            holder[0].wait(timeout=30)
    assert 1 <= len(read_rows(out)[0]) < 6
    run_study(study, out, workers=1, resume=True)
    assert len(read_rows(out)[0]) == 6


def test_the_cli_says_the_lock_in_one_line(tmp_path):
    study, out = _write(tmp_path, FAST), tmp_path / "out"
    assert runner.invoke(app, ["study", str(study), "--out", str(out)]).exit_code == 0
    study.write_text(FAST.replace("40.0]", "40.0, 50.0]"), encoding="utf-8")  # one run more
    con = sqlite3.connect(out / "results.sqlite", isolation_level=None)
    con.execute("BEGIN IMMEDIATE")
    try:
        res = runner.invoke(
            app, ["study", str(study), "--out", str(out), "--resume", "--lock-timeout", "0"]
        )
    finally:
        con.execute("ROLLBACK")
        con.close()
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "write lock" in lines[0] and "--resume" in lines[0], res.stderr
    assert "Traceback" not in res.output
    res = runner.invoke(app, ["study", str(study), "--out", str(out), "--resume"])
    assert res.exit_code == 0, res.output
    assert len(read_rows(out)[0]) == 4


def test_a_study_file_finds_its_scene_beside_it(tmp_path, monkeypatch):
    from eyelume.scene.io import load_scene, save_scene

    folder = tmp_path / "project"
    folder.mkdir()
    save_scene(load_scene("paper2005", {"leds.height_mm": 27.0}), folder / "my_scene.toml")
    _write(folder, FAST.replace('scene = "paper2005"', 'scene = "my_scene.toml"'))
    monkeypatch.chdir(tmp_path)  # elsewhere: the path is the study file's, not the cwd's
    st = load_study("project/study.toml")
    assert load_scene(st.scene).leds.height_mm == 27.0
    res = runner.invoke(app, ["study", "project/study.toml", "--out", "o", "--workers", "1"])
    assert res.exit_code == 0, res.output


@pytest.mark.parametrize("damage", ["garbage", "truncated"])
def test_a_damaged_store_is_one_line_and_exit_2(tmp_path, damage):
    study, out = _write(tmp_path, FAST), tmp_path / "out"
    assert runner.invoke(app, ["study", str(study), "--out", str(out)]).exit_code == 0
    db = out / "results.sqlite"
    data = db.read_bytes()
    db.write_bytes(b"not a database, whatever it is\n" * 50 if damage == "garbage" else
                   data[:100] + b"\0" * (len(data) - 100))  # fmt: skip
    for args in (["report", str(out)], ["study", str(study), "--out", str(out), "--resume"]):
        res = runner.invoke(app, args)
        assert res.exit_code == 2, (args, res.output)
        assert "Traceback" not in res.output
        lines = [ln for ln in res.stderr.splitlines() if ln.startswith("error:")]
        assert len(lines) == 1 and "results.sqlite" in lines[0], res.stderr
        # the one line only: no study banner before it
        assert [ln for ln in res.stderr.splitlines() if ln.strip()] == lines, res.stderr
    with pytest.raises(StoreError):
        read_rows(out)


def test_a_read_only_folder_is_read_as_it_is(tmp_path, monkeypatch):
    """Where SQLite cannot create its WAL index (a read-only folder), the database file is read
    immutable; the report says so, and needs --out."""
    study, out = _write(tmp_path, FAST), tmp_path / "out"
    run_study(load_study(study), out, workers=1)
    monkeypatch.setattr(store_mod, "_read_only_fs", lambda folder: True)
    rows, note = read_rows(out)
    assert len(rows) == 3 and "cannot be written" in note


@pytest.mark.slow
def test_report_of_a_really_read_only_folder(tmp_path):
    """A read-only bind mount (in a user and mount namespace: `unshare -rm`): report with --out
    elsewhere works; without it, one line and exit 2."""
    unshare = shutil.which("unshare")
    probe = subprocess.run([unshare or "unshare", "-rm", "true"], capture_output=True) if unshare \
        else None  # fmt: skip
    if probe is None or probe.returncode != 0:
        pytest.skip("needs `unshare -rm` (user and mount namespaces) for a read-only mount")
    study, out = _write(tmp_path, FAST), tmp_path / "out"
    run_study(load_study(study), out, workers=1)
    page = tmp_path / "elsewhere" / "report.html"
    env = {**os.environ}
    script = (f"mount --bind -o ro {out} {out} && {sys.executable} -c 'from eyelume.cli import "
              f"app; app()' report {out} --out {page}; echo rc=$?; {sys.executable} -c 'from "
              f"eyelume.cli import app; app()' report {out}; echo rc=$?; {sys.executable} -c "
              f"'from eyelume.cli import app; app()' report {out} --scene paper2005 --out {page}; "
              f"echo rc=$?")  # fmt: skip
    res = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True,
                         timeout=300, env=env)  # fmt: skip
    assert "rc=0" in res.stdout.splitlines()[0], res.stderr
    assert "rc=2" in res.stdout.splitlines()[1], res.stderr
    assert "3 runs committed" in page.read_text(encoding="utf-8")
    assert "--out" in res.stderr and "Traceback" not in res.stderr
    # --scene would store the best run in the read-only folder: refused before evaluating it
    assert "rc=2" in res.stdout.splitlines()[2], res.stderr
    assert "--scene stores the best run in" in res.stderr and "evaluating" not in res.stderr
