"""The study report opens in headless Chromium (Debian's package, installed by .ci/run) and
renders with its figures; runs over a safety limit are flagged.

Without a ``chromium`` on PATH the browser test is skipped (saying why), so the README's test
command passes on a fresh machine — unless ``EYELUME_REQUIRE_CHROMIUM=1`` (set by ``.ci/run``,
which installs it): then a missing browser is a failure, so CI always runs the real browser.
"""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys

import pytest
from PIL import Image

from eyelume.optimize.best_run import save_best_run
from eyelume.optimize.runner import run_study
from eyelume.optimize.study import load_study
from eyelume.report.html import write_report
from eyelume.report.plots import observe_figures

sys.path.insert(0, os.path.dirname(__file__))
from test_figures import Caught  # noqa: E402

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
    caught = Caught(None)  # their captions are the page's: checked below
    with observe_figures(caught):  # the page's figures, checked from matplotlib's extents
        page = write_report(tmp_path / "out")
    assert not caught.defects, caught.defects
    text = page.read_text(encoding="utf-8")
    n_img = text.count("<img ")
    assert n_img >= 3  # two metric landscapes (+ margins) and the best run's images
    assert len(caught.names) == n_img
    assert text.count("<figcaption>") == n_img
    captions = [html.unescape(c) for c in re.findall(r"<figcaption>(.*?)</figcaption>", text)]
    landscapes, best = captions[:-1], captions[-1]
    for c in landscapes:  # the study's scene, as run_study recorded it, and the budget used
        assert "Study report: scene paper2005." in c, c
        # eye_plane_merit and the safety margins are closed form: the study's 16 camera samples
        # per pixel and seed 1 were not used for them, and the caption must not say they were
        assert "no camera samples, no random seed" in c and "16 camera samples" not in c, c
    # the runs table's headers carry units; the best runs read as settings, not Python dicts
    assert (
        "<th>leds.height_mm (mm)</th>" in text and "<th>corneal_margin (limit / exposure)" in text
    )
    best_runs = re.search(r"<h2>Best runs.*?</ol>", text, re.S).group(0)
    assert "{" not in best_runs and "leds.height_mm = " in best_runs and " mm" in best_runs
    assert "eye_plane_merit = " in best_runs and "(dimensionless)" in best_runs
    # the best run is rendered anew, with its own seed: said so
    assert "scene paper2005 with the run's overrides, seed 0, 16 camera samples" in best, best
    shots = tmp_path / "screenshots"  # the test's artefacts, kept in pytest's tmp folder
    shots.mkdir()
    for width in (1280, 1920):
        args = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                f"--window-size={width},1600", "--virtual-time-budget=5000"]  # fmt: skip
        dom = subprocess.run(
            [*args, "--dump-dom", page.as_uri()],
            capture_output=True, text=True, timeout=120, check=True,
        ).stdout  # fmt: skip
        decoded = re.search(r'data-figures="(\d+)"', dom)
        assert decoded and int(decoded.group(1)) == n_img  # every figure decoded, has a size
        overflow = re.search(r'data-overflow-px="(\d+)"', dom)
        assert overflow and int(overflow.group(1)) == 0, f"{width} px: page wider than window"
        # figures grow with the window (at 1920 px they are not left at their PNG's size)
        narrowest = int(re.search(r'data-figure-min-px="(\d+)"', dom).group(1))
        widest = int(re.search(r'data-figure-max-px="(\d+)"', dom).group(1))
        assert 0.4 * width <= narrowest <= widest <= width, (width, narrowest, widest)
        # 3 of the 6 runs have 1 W/sr LEDs: over the corneal limit, drawn in red
        assert dom.count('class="unsafe"') == 3
        shot = shots / f"report_{width}.png"
        subprocess.run(
            [*args, f"--screenshot={shot}", page.as_uri()],
            capture_output=True,
            timeout=120,
            check=True,
        )
        with Image.open(shot) as im:
            assert im.size == (width, 1600)


def test_report_escapes_user_text_and_scrolls_wide_tables(tmp_path):
    """A study and parameter names with markup are shown as text, and a runs table of 30
    columns sits in a box that scrolls sideways (overflow-x: auto): in headless Chromium at
    1280 px the page itself does not overflow."""
    from eyelume.optimize.store import ResultStore

    folder = tmp_path / "study"
    names = [f"leds.<b>parameter_number_{i}</b>" for i in range(30)]  # wider than any window
    store = ResultStore(folder)
    try:
        store.put("k0", 0, "s<i>", {n: 1.0 for n in names}, {"merit": 1.0}, 0.1)
    finally:
        store.close()
    page = write_report(folder)
    text = page.read_text(encoding="utf-8")
    assert "<b>" not in text and "<i>" not in text
    assert "leds.&lt;b&gt;parameter_number_0&lt;/b&gt;" in text and "s&lt;i&gt;" in text
    assert '<div class="scroll"><table>' in text
    # no study.json (a store written by another program): the captions say the seed is unknown
    assert "records no study scene or seed (study.json missing" in text
    browser = _browser()
    dom = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
         "--window-size=1280,900", "--virtual-time-budget=5000", "--dump-dom", page.as_uri()],
        capture_output=True, text=True, timeout=120, check=True,
    ).stdout  # fmt: skip
    overflow = re.search(r'data-overflow-px="(\d+)"', dom)
    assert overflow and int(overflow.group(1)) == 0


def test_without_chromium_the_browser_test_skips_unless_ci_requires_it(monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.delenv("EYELUME_REQUIRE_CHROMIUM", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no chromium"):
        _browser()
    monkeypatch.setenv("EYELUME_REQUIRE_CHROMIUM", "1")
    with pytest.raises(pytest.fail.Exception, match="EYELUME_REQUIRE_CHROMIUM"):
        _browser()


def test_axis_labels_take_the_unit_their_name_ends_with():
    from eyelume.report.html import axis_label

    assert axis_label("leds.height_mm") == "leds.height_mm (mm)"
    assert axis_label("leds.radiant_intensity_w_sr") == "leds.radiant_intensity_w_sr (W/sr)"
    assert axis_label("leds.pitch_deg") == "leds.pitch_deg (°)"
    assert axis_label("corneal_margin") == "corneal_margin (limit / exposure)"
    assert axis_label("eye_plane_merit") == "eye_plane_merit (dimensionless)"
    assert axis_label("glints") == "glints"  # no unit in the name: none invented


def _row(index, merit, safe):
    return {
        "index": index,
        "study": "s",
        "overrides": {"leds.height_mm": 20.0 + index},
        "metrics": {"eye_plane_merit": merit, "within_exempt_group": safe},
    }


def test_a_run_over_the_eye_safety_limit_is_never_best_when_a_compliant_one_exists():
    """Runs that tie on merit (and one over the limit with a better merit): the compliant runs
    rank first; the over-limit ones follow, marked in the Best runs list; with no compliant run
    the best one is over the limit and the page says so loudly."""
    from eyelume.optimize.best_run import best_runs
    from eyelume.report.html import _best_list, _best_warning

    rows = [_row(0, 0.5, False), _row(1, 0.5, True), _row(2, 0.1, False), _row(3, 0.7, True)]
    merit, best = best_runs(rows)
    assert merit == "eye_plane_merit" and [r["index"] for r in best] == [1, 3, 2, 0]
    items = re.findall(r"<li>.*?</li>", _best_list(best, merit))
    assert ["OVER the IEC 62471" in i for i in items] == [False, False, True, True]
    assert _best_warning(rows, best) == ""
    unsafe = [_row(0, 0.5, False), _row(1, 0.2, False)]
    _, best = best_runs(unsafe)
    assert best[0]["index"] == 1
    assert "No run of this study is within the IEC 62471 exempt-group limit" in _best_warning(
        unsafe, best
    )
