"""The files the optimisation commands write, from given results: the study's table and the
tracking sweep's table and comparison (the CLI only passes them on)."""

from __future__ import annotations

import csv

from eyelume.optimize.tracking import PlacementScore
from eyelume.report.optimize_outputs import write_study_table, write_tracking_sweep_outputs


def test_study_table_has_a_column_per_parameter_and_metric(tmp_path):
    rows = [
        {"index": 0, "overrides": {"leds.height_mm": 20.0}, "metrics": {"m": 1.5}, "seconds": 0.25},
        {"index": 1, "overrides": {"leds.height_mm": 40.0}, "metrics": {"m": None}, "seconds": 1},
    ]
    path = write_study_table(rows, tmp_path)
    with open(path, encoding="utf-8") as f:
        back = list(csv.DictReader(f))
    assert path == tmp_path / "table.csv"
    assert list(back[0]) == ["index", "leds.height_mm", "m", "seconds"]
    assert back[0]["m"] == "1.5" and back[1]["m"] == "" and back[1]["seconds"] == "1.000"


def test_tracking_sweep_outputs_list_every_placement_and_compare_three(tmp_path):
    grid = [PlacementScore("grid", 20.0, 50.0, th, 2.0 + th / 10, 1.0, 1.5) for th in (0, 15)]
    dopt = PlacementScore("δ-optimal (generator)", 25.0, 70.0, 5.0, 3.25, 0.5, 2.0)
    paper = PlacementScore("paper", 30.0, 70.0, 20.0, float("inf"), 0.0, float("nan"))
    meta = {"delta": 0.3, "samples_per_pixel": 8, "seed": 0, "sensor": [87, 65]}
    written = write_tracking_sweep_outputs(grid, grid[0], dopt, paper, meta, tmp_path)
    with open(written[0], encoding="utf-8") as f:
        back = list(csv.DictReader(f))
    assert [r["label"] for r in back] == ["grid", "grid", "δ-optimal (generator)", "paper"]
    assert back[2]["score_deg"] == "3.2500" and back[3]["score_deg"] == "inf"
    text = written[1].read_text(encoding="utf-8")
    assert "8 samples per pixel, seed 0, sensor 87 × 65" in text
    assert "| δ = 0.3 generator | 25 | 70 | 5 | 3.25 | 50% |" in text
    assert text.count("\n| ") == 4  # the header and three placements
