"""A render interrupted inside its first round keeps the pixels it finished (issue 12): a big
picture's first round takes minutes, and an interrupt a few seconds in used to lose it all."""

from __future__ import annotations

import json
import os
import signal

import numpy as np
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import compile_scene
from eyelume.estimators import fast_run as FR


class _StopAfter:
    """A stop flag that turns on after ``n`` looks at it."""

    def __init__(self, n: int) -> None:
        self.n = n

    @property
    def requested(self) -> bool:
        self.n -= 1
        return self.n < 0


def test_a_cut_first_round_keeps_its_pixels_exactly():
    """The pixels a stopped first round finished hold exactly what an uninterrupted round puts
    there (a pixel's samples depend on its index, set and seed only); the rest are NaN; light
    paths were traced in proportion to the pixels done."""
    cs = compile_scene(eyelume.load_scene("paper2005", {"sensor.cols": 120, "sensor.rows": 90}))
    ratio = 2.0
    cut = FR._Run(cs, 2, 7)
    assert cut.add(2, ratio, _StopAfter(3)) is False
    per = FR.CHUNK_SAMPLES // (2 * 4)
    n = 120 * 90
    k = cut.covered
    assert k % per == 0 and 0 < k < n and cut.sets == 0  # whole camera chunks, not all
    full = FR._Run(cs, 2, 7)
    assert full.add(2, 0.0)
    np.testing.assert_array_equal(cut.cam_sum.reshape(-1)[:k], full.cam_sum.reshape(-1)[:k])
    assert not cut.cam_sum.reshape(-1)[k:].any()
    # light paths alongside, in proportion to the pixels done (fewer if the stop came in them)
    assert 0 < cut.paths <= int(round(ratio * 2 * 4)) * k // n
    est = cut.estimate(True)
    img = est.image.reshape(-1)
    assert np.isfinite(img[:k]).all() and np.isnan(img[k:]).all()
    assert est.covered_pixels == k and est.samples_per_pixel == 8 and est.variance_dof == 1


def test_render_interrupted_in_its_first_round_writes_the_finished_rows(tmp_path, monkeypatch):
    """SIGINT after the second camera chunk of a 300 × 200 render: exit 130, the top rows
    written, the rest NaN, summary.json saying so."""
    real = FR._Work.tick
    calls = [0]

    def tick(self, units):  # after each chunk of the first round: SIGINT after the second
        real(self, units)
        calls[0] += 1
        if calls[0] == 2:
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(FR._Work, "tick", tick)
    out = tmp_path / "o"
    sets = ["--set", "sensor.cols=300", "--set", "sensor.rows=200"]
    res = CliRunner().invoke(app, ["render", *sets, "--samples", "8", "--out", str(out)])
    assert res.exit_code == 130, res.output
    img = np.load(out / "eye_image.npy")
    finite = np.isfinite(img).reshape(-1)
    k = int(finite.sum())
    assert 0 < k < img.size and finite[:k].all() and not finite[k:].any()
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["interrupted"] and summary["missing_pixels"] == img.size - k
    assert "first round" in summary["note"]
    assert summary["regions"]["skin"]["pixels"] > 0
    assert summary["regions"]["skin"]["mean_w_mm2"] > 0
    digital = np.load(out / "eye_image_digital.npy")
    assert (digital.reshape(-1)[k:] == 0).all()
    assert "interrupted in the first round" in " ".join(res.output.split())
    # the sensor's total is not known with pixels missing: null in the JSON (was NaN, which a
    # strict JSON reader refuses) and said in words (was "on the sensor nan W")
    assert summary["power_w"]["sensor"] is None
    assert "on the sensor an unknown power (pixels missing)" in " ".join(res.output.split())
    assert "nan W" not in res.output
