"""The study store holds finite numbers only, and its readers survive a store that does not
(issue 12): a non-finite metric is stored as null and flagged, a non-finite override refused,
and a store holding the non-JSON tokens NaN/Infinity (written by an older eyelume or another
program) is reported without a traceback, a NaN merit never ranked best."""

from __future__ import annotations

import json
import math
import re
import sqlite3

import pytest
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.errors import StoreError
from eyelume.optimize.best_run import best_runs
from eyelume.optimize.store import ResultStore, read_rows


def _strict(text: str):
    def refuse(token):
        raise AssertionError(f"non-JSON token {token} in the store")

    return json.loads(text, parse_constant=refuse)


def test_non_finite_metrics_are_stored_as_null_and_flagged(tmp_path):
    store = ResultStore(tmp_path)
    metrics = {"eye_plane_merit": math.nan, "corneal_margin": math.inf, "skin_cv": 0.1,
               "nested": {"x": [1.0, -math.inf]}}  # fmt: skip
    store.put("k", 0, "s", {"leds.height_mm": 20.0}, metrics, math.nan)
    store.close()
    ((text, seconds),) = sqlite3.connect(tmp_path / "results.sqlite").execute(
        "SELECT metrics, seconds FROM runs"
    )
    stored = _strict(text)
    assert stored["eye_plane_merit"] is None and stored["corneal_margin"] is None
    assert stored["skin_cv"] == 0.1 and stored["nested"] == {"x": [1.0, None]}
    assert stored["non_finite"] == ["eye_plane_merit", "corneal_margin", "nested.x.1"]
    assert seconds is None


def test_a_non_finite_override_is_refused_and_nothing_stored(tmp_path):
    store = ResultStore(tmp_path)
    with pytest.raises(StoreError, match="leds.height_mm"):
        store.put("k", 3, "s", {"leds.height_mm": math.nan}, {"skin_cv": 0.1}, 1.0)
    assert store.rows() == []
    store.close()


def test_a_store_with_nan_tokens_is_read_and_reported(tmp_path):
    """Written as an older eyelume did (json.dumps lets NaN and Infinity through)."""
    db = sqlite3.connect(tmp_path / "results.sqlite")
    db.execute("CREATE TABLE runs (key TEXT PRIMARY KEY, idx INTEGER, study TEXT, "
               "overrides TEXT, metrics TEXT, seconds REAL)")  # fmt: skip
    rows = [
        ("a", 0, "s", {"leds.height_mm": 20.0}, {"eye_plane_merit": math.nan}, 1.0),
        ("b", 1, "s", {"leds.height_mm": 25.0}, {"eye_plane_merit": 0.5,
                                                  "corneal_margin": math.inf}, math.nan),
        ("c", 2, "s", {"leds.height_mm": 30.0}, {"eye_plane_merit": 0.7}, 2.0),
    ]  # fmt: skip
    for k, i, st, ov, me, sec in rows:
        db.execute("INSERT INTO runs VALUES (?,?,?,?,?,?)",
                   (k, i, st, json.dumps(ov), json.dumps(me), sec))  # fmt: skip
    db.commit()
    db.close()
    got, _ = read_rows(tmp_path)
    assert got[0]["metrics"]["eye_plane_merit"] is None
    assert got[1]["metrics"]["corneal_margin"] is None and got[1]["seconds"] is None
    merit, best = best_runs(got)
    assert merit == "eye_plane_merit" and [r["index"] for r in best] == [1, 2]
    res = CliRunner().invoke(app, ["report", str(tmp_path)])
    assert res.exit_code == 0, res.output
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    # the text, not the figures' base64 data, which may spell "nan" by chance
    text = re.sub(r"data:image/[a-z]+;base64,[A-Za-z0-9+/=]+", "", page)
    assert "run 1:" in text and "nan" not in text.lower().replace("nanometre", "")
    assert "not a finite number" in page


def test_check_store_counts_the_runs_without_reading_them_and_refuses_a_damaged_store(tmp_path):
    """What `study`/`dataset` --resume check before their banner: the count read_rows would
    give, and the same StoreError for a damaged or missing store."""
    from eyelume.optimize.store import check_store

    store = ResultStore(tmp_path / "s")
    for i in range(3):
        store.put(f"k{i}", i, "s", {"leds.height_mm": 20.0 + i}, {"skin_cv": 0.1}, 1.0)
    store.close()
    assert check_store(tmp_path / "s") == len(read_rows(tmp_path / "s")[0]) == 3
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "results.sqlite").write_bytes(b"not a database at all" * 100)
    with pytest.raises(StoreError):
        check_store(tmp_path / "bad")
    with pytest.raises(StoreError, match="no results.sqlite"):
        check_store(tmp_path / "missing")
