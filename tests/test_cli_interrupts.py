"""Ctrl-C and SIGTERM in the long commands beyond render (issue 12): `reproduce`,
`evaluate-tracking` (and its population) and `optimize-tracking` keep the units of work that
finished — δ values, test gazes, population members, placements — write them marked partial,
drop the unit in flight whole, and exit 128 + the signal.

Each unit is replaced by a quick stand-in that returns a fixed result (what is tested is the
run's bookkeeping, not the physics) and, at the unit chosen, delivers a real signal to this
process: SIGTERM, which the command line turns into KeyboardInterrupt at once, or SIGINT
inside a render's own handler, which only asks the render to stop early — so the unit returns
normally with a partial result, and must still be dropped."""

from __future__ import annotations

import dataclasses
import json
import os
import signal

import numpy as np
import pytest
from typer.testing import CliRunner

import eyelume.optimize.delta_study as ds
import eyelume.optimize.tracking as tr
from eyelume.analysis.tracking.detect import Detection
from eyelume.analysis.tracking.evaluate import Frame
from eyelume.cli import app
from eyelume.estimators.interrupt import interrupt_between_batches

runner = CliRunner()
TINY = ["--set", "sensor.cols=16", "--set", "sensor.rows=12"]


def _signal(kind: str) -> None:
    """Deliver a signal as a user would: SIGTERM (raises at once), or SIGINT while a render's
    handler is installed (the render finishes its chunk and returns: a partial unit)."""
    if kind == "SIGTERM":
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(10**6):  # the handler raises KeyboardInterrupt within a few bytecodes
            pass
        raise AssertionError("SIGTERM did not interrupt")
    with interrupt_between_batches() as stop:
        os.kill(os.getpid(), signal.SIGINT)
        while not stop.requested:
            pass


class _Units:
    """A stand-in for one unit of work that signals during unit number ``at`` (1-based)."""

    def __init__(self, result, at: int, kind: str) -> None:
        self.result, self.at, self.kind, self.calls = result, at, kind, 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        if self.calls == self.at:
            _signal(self.kind)
        return self.result(*args, **kwargs) if callable(self.result) else self.result


def _row(scene, mask, delta, samples, seed):
    return ds.DeltaRow(delta, 30.0, 70.0, 20.0, 1.0, (30.0, 70.0, 20.0, 1.0), 0.1 + delta,
                       0.01, 0.0, 1e-6, 1e-7, 0.1, np.ones((15, 21)), np.ones((12, 16)),
                       5.0, 40.0)  # fmt: skip


@pytest.mark.parametrize("kind", ["SIGTERM", "SIGINT"])
def test_reproduce_keeps_the_deltas_finished(tmp_path, monkeypatch, kind):
    units = _Units(_row, at=3, kind=kind)
    monkeypatch.setattr(ds, "_delta_row", units)
    monkeypatch.setattr(ds, "evaluate_paper_placement", lambda *a: pytest.fail("not reached"))
    out = tmp_path / "o"
    res = runner.invoke(app, ["reproduce", "paper2005", "--deltas", "0.1,0.2,0.3,0.4",
                              "--direct", "0", *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 128 + getattr(signal, kind), res.output
    summary = json.loads((out / "delta_study.json").read_text(encoding="utf-8"))
    assert [r["delta"] for r in summary["rows"]] == [0.1, 0.2]  # the third dropped whole
    assert summary["meta"]["partial"] == "interrupted after 2 of 4 δ values"
    assert "Partial run" in (out / "comparison.md").read_text(encoding="utf-8")
    assert "partial: interrupted after 2 of 4 δ values" in " ".join(res.output.split())


def test_reproduce_interrupted_before_a_delta_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setattr(ds, "_delta_row", _Units(_row, at=1, kind="SIGTERM"))
    out = tmp_path / "o"
    res = runner.invoke(app, ["reproduce", "paper2005", "--deltas", "0.1,0.2", "--direct", "0",
                              *TINY, "--out", str(out)])  # fmt: skip
    assert res.exit_code == 143, res.output
    assert "nothing usable" in res.output and not out.exists()


@pytest.fixture(scope="module")
def frame():
    det = Detection(ok=False, failures=["pupil not found"], pupil=None, glints=[])
    return Frame(gaze=(0.0, 0.0), detection=det, truth={})


def _framer(frame):
    return lambda scene, h, v, samples, seed: dataclasses.replace(frame, gaze=(h, v))


@pytest.mark.parametrize("kind", ["SIGTERM", "SIGINT"])
def test_evaluate_tracking_keeps_the_gazes_finished(tmp_path, monkeypatch, frame, kind):
    calib = tr.frame_count() - tr.frame_count(calibrate=False)
    monkeypatch.setattr(tr, "render_frame", _Units(_framer(frame), at=calib + 6, kind=kind))
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--samples", "1", *TINY, "--out", str(out)])
    assert res.exit_code == 128 + getattr(signal, kind), res.output
    rows = (out / "frames.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + 5  # header and the five test gazes finished
    meta = json.loads((out / "summary.json").read_text(encoding="utf-8"))["meta"]
    assert meta["partial"] == f"interrupted after 5 of {tr.frame_count(calibrate=False)} test gazes"


def test_evaluate_tracking_during_calibration_writes_nothing(tmp_path, monkeypatch, frame):
    monkeypatch.setattr(tr, "render_frame", _Units(_framer(frame), at=4, kind="SIGTERM"))
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--samples", "1", *TINY, "--out", str(out)])
    assert res.exit_code == 143, res.output
    assert "nothing usable" in res.output and not out.exists()


def test_the_population_keeps_the_members_finished(tmp_path, monkeypatch, frame):
    per = tr.frame_count()
    monkeypatch.setattr(tr, "render_frame", _Units(_framer(frame), at=2 * per + 3, kind="SIGTERM"))
    out = tmp_path / "o"
    res = runner.invoke(app, ["evaluate-tracking", "--named-population", "--samples", "1", *TINY,
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 143, res.output
    table = json.loads((out / "population.json").read_text(encoding="utf-8"))
    assert set(table) == {"nominal", "dark iris", "partial"}
    assert table["partial"] == f"interrupted after 2 of {len(tr.POPULATION)} population members"
    assert (out / "frames.csv").exists() and (out / "dark_iris" / "frames.csv").exists()
    assert not (out / "light_iris").exists()


@pytest.mark.parametrize("kind", ["SIGTERM", "SIGINT"])
def test_optimize_tracking_keeps_the_placements_finished(tmp_path, monkeypatch, kind):
    def score(scene, y, z, th, samples, seed, label=""):
        return tr.PlacementScore(label, y, z, th, 1.0 + y / 100, 1.0, 1.0)

    monkeypatch.setattr(tr, "score_placement", _Units(score, at=8, kind=kind))
    out = tmp_path / "o"
    res = runner.invoke(app, ["optimize-tracking", "--samples", "1", *TINY, "--out", str(out)])
    assert res.exit_code == 128 + getattr(signal, kind), res.output
    rows = (out / "tracking_sweep.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 1 + 7 and all(r.startswith("grid") for r in rows[1:])
    text = (out / "comparison.md").read_text(encoding="utf-8")
    assert "Partial run** (interrupted after 7 of 29 placements)" in text
    assert "not scored (interrupted)" in text


def test_the_units_drive_a_progress_bar_with_an_eta(tmp_path, monkeypatch):
    """One step of the bar per unit, to the planned total, with a time-remaining column."""
    from rich.progress import TimeRemainingColumn

    import eyelume.cli as cli

    bars = []
    real = cli._progress_bar

    def recording(label, count):
        bars.append(real(label, count))
        return bars[-1]

    def score(scene, y, z, th, samples, seed, label=""):
        return tr.PlacementScore(label, y, z, th, 1.0 + y / 100, 1.0, 1.0)

    monkeypatch.setattr(cli, "_progress_bar", recording)
    monkeypatch.setattr(tr, "score_placement", score)
    out = tmp_path / "o"
    res = runner.invoke(app, ["optimize-tracking", "--samples", "1", *TINY, "--out", str(out)])
    assert res.exit_code == 0, res.output
    (bar,) = bars
    (task,) = bar.tasks
    assert task.total == 29 and task.completed == 29
    assert any(isinstance(c, TimeRemainingColumn) for c in bar.columns)


def test_without_a_terminal_the_progress_is_plain_lines(tmp_path, monkeypatch):
    """Where stderr is no terminal (a log, CI) Rich draws no bar: plain lines carry the count,
    the first at once and one when the work is done (the 10 s spacing is not waited for)."""

    def score(scene, y, z, th, samples, seed, label=""):
        return tr.PlacementScore(label, y, z, th, 1.0 + y / 100, 1.0, 1.0)

    monkeypatch.setattr(tr, "score_placement", score)
    out = tmp_path / "o"
    res = runner.invoke(app, ["optimize-tracking", "--samples", "1", *TINY, "--out", str(out)])
    assert res.exit_code == 0, res.output
    lines = [ln for ln in res.output.splitlines() if "/29 " in ln]
    assert lines[0].split("/29")[0].endswith(" 1"), lines
    assert " 29/29 " in lines[-1] and lines[-1].rstrip().endswith(" s"), lines
    assert len(lines) < 29  # rate-limited, not a line per unit
