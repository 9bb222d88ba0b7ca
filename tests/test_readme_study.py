"""The README's example study file (issue 12): the README shows examples/led_study.toml as it
stands, the file names every field the study loader knows, and it runs end to end."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.optimize.study import METRICS, Study, Vary, load_study, plan_runs

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "led_study.toml"


def test_the_readme_shows_the_example_file_as_it_stands():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```toml\n(.*?)```", readme, flags=re.S)
    assert EXAMPLE.read_text(encoding="utf-8") in blocks


def test_the_example_documents_every_field_of_the_format():
    text = EXAMPLE.read_text(encoding="utf-8")
    data = tomllib.loads(text)
    # every top-level field, with its default; a table with no default (population) shown
    # commented out
    shown = set(data) | {f for f in Study.model_fields if f"# [{f}]" in text}
    assert shown == set(Study.model_fields)
    for name in Vary.model_fields:
        assert name in text, name
    for metric in METRICS:
        assert metric in text, metric
    study = load_study(EXAMPLE)
    assert len(plan_runs(study)) == 9


def test_the_example_study_runs_and_reports(tmp_path):
    out = tmp_path / "led_study"
    runner = CliRunner()
    res = runner.invoke(app, ["study", str(EXAMPLE), "--out", str(out), "--workers", "1"])
    assert res.exit_code == 0, res.output
    assert "9/9 runs" in " ".join(res.output.split())
    rows = (out / "table.csv").read_text(encoding="utf-8").splitlines()
    assert len(rows) == 10 and "eye_plane_merit" in rows[0] and "corneal_margin" in rows[0]
    res = runner.invoke(app, ["report", str(out)])
    assert res.exit_code == 0, res.output
    assert (out / "report.html").is_file()
