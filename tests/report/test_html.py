"""The study report opens in headless Chromium (Debian's package, installed by .ci/run) and
renders with its figures; runs over a safety limit are flagged."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from eyelume.optimize.best_run import save_best_run
from eyelume.optimize.runner import run_study
from eyelume.optimize.study import load_study
from eyelume.report.html import write_report

STUDY = """
name = "report"
scene = "paper2005"
seed = 1
metrics = ["eye_plane_merit", "safety"]
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, 3]
[[vary]]
path = "leds.radiant_intensity_w_sr"
values = [0.015, 1.0]
"""


@pytest.mark.slow
def test_report_renders_in_headless_chromium_with_its_figures(tmp_path):
    p = tmp_path / "study.toml"
    p.write_text(STUDY, encoding="utf-8")
    run_study(load_study(p), tmp_path / "out", workers=1)
    save_best_run(tmp_path / "out", "paper2005")  # the best run's pictures, stored
    page = write_report(tmp_path / "out")
    text = page.read_text(encoding="utf-8")
    n_img = text.count("<img ")
    assert n_img >= 3  # two metric landscapes (+ margins) and the best run's images
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    assert browser, "chromium is not installed (.ci/run installs Debian's chromium)"
    dom = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000",
         "--dump-dom", page.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    decoded = re.search(r'data-figures="(\d+)"', dom)
    assert decoded and int(decoded.group(1)) == n_img  # every figure decoded and has a size
    # 3 of the 6 runs have 1 W/sr LEDs: over the corneal limit, drawn in red
    assert dom.count('class="unsafe"') == 3
