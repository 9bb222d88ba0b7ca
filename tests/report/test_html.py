"""The study report opens in headless Chromium (Debian's package, installed by .ci/run) and
renders with its figures; runs over a safety limit are flagged.

Without a ``chromium`` on PATH the browser test is skipped (saying why), so the README's test
command passes on a fresh machine — unless ``EYELUME_REQUIRE_CHROMIUM=1`` (set by ``.ci/run``,
which installs it): then a missing browser is a failure, so CI always runs the real browser.
"""

from __future__ import annotations

import os
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


def _browser() -> str | None:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        if os.environ.get("EYELUME_REQUIRE_CHROMIUM") == "1":
            pytest.fail(
                "EYELUME_REQUIRE_CHROMIUM=1 but no chromium on PATH (.ci/run installs Debian's)"
            )
        pytest.skip(
            "no chromium on PATH (Debian's `chromium`; .ci/run installs it and requires it)"
        )
    return browser


@pytest.mark.slow
def test_report_renders_in_headless_chromium_with_its_figures(tmp_path):
    browser = _browser()  # before the study: no work when it will be skipped
    p = tmp_path / "study.toml"
    p.write_text(STUDY, encoding="utf-8")
    run_study(load_study(p), tmp_path / "out", workers=1)
    save_best_run(tmp_path / "out", "paper2005")  # the best run's pictures, stored
    page = write_report(tmp_path / "out")
    text = page.read_text(encoding="utf-8")
    n_img = text.count("<img ")
    assert n_img >= 3  # two metric landscapes (+ margins) and the best run's images
    dom = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000",
         "--dump-dom", page.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    decoded = re.search(r'data-figures="(\d+)"', dom)
    assert decoded and int(decoded.group(1)) == n_img  # every figure decoded and has a size
    # 3 of the 6 runs have 1 W/sr LEDs: over the corneal limit, drawn in red
    assert dom.count('class="unsafe"') == 3


def test_without_chromium_the_browser_test_skips_unless_ci_requires_it(monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.delenv("EYELUME_REQUIRE_CHROMIUM", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no chromium"):
        _browser()
    monkeypatch.setenv("EYELUME_REQUIRE_CHROMIUM", "1")
    with pytest.raises(pytest.fail.Exception, match="EYELUME_REQUIRE_CHROMIUM"):
        _browser()
