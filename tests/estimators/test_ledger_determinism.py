"""Tests 6 and 8: the power ledger sums to the emitted power; results depend on the seed only."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import eyelume


def test_ledger_sums_to_emitted_power(paper_compiled):
    result = eyelume.render(paper_compiled, eyelume.RenderOptions(rays=400_000, seed=3))
    total = sum(result.ledger.values())
    assert abs(total - result.emitted_w) <= 1e-9 * result.emitted_w
    assert all(v >= 0 for v in result.ledger.values())
    # the sensor's share is the image integrated over the pixels
    sc = paper_compiled.scene
    px = (sc.sensor.width_mm / sc.sensor.cols) * (sc.sensor.height_mm / sc.sensor.rows)
    np.testing.assert_allclose(result.eye_image.sum() * px, result.ledger["sensor"], rtol=1e-12)
    # emitted power = N LEDs × I0 × 2π/(m+1) for the cos^m profile (closed form)
    m = np.log(0.5) / np.log(np.cos(np.radians(22.5)))
    expected = 4 * 0.015 * 2 * np.pi / (m + 1)
    np.testing.assert_allclose(result.emitted_w, expected, rtol=1e-9)
    summary = result.summary()["power_w"]
    parts = summary["sensor"] + summary["escaped"] + sum(summary["absorbed"].values())
    assert abs(parts - summary["emitted"]) <= 1e-9 * summary["emitted"]


def test_same_seed_same_arrays_whatever_the_batch_size(paper_compiled):
    a = eyelume.render(
        paper_compiled, eyelume.RenderOptions(rays=300_000, seed=11, batch_size=300_000)
    )
    b = eyelume.render(
        paper_compiled, eyelume.RenderOptions(rays=300_000, seed=11, batch_size=7_919)
    )
    assert np.array_equal(a.eye_image, b.eye_image)
    assert np.array_equal(a.eye_plane, b.eye_plane)
    assert a.ledger == b.ledger
    c = eyelume.render(paper_compiled, eyelume.RenderOptions(rays=300_000, seed=12))
    assert not np.array_equal(a.image_counts, c.image_counts)


_SCRIPT = """
import sys, numpy as np, eyelume
scene = eyelume.load_scene("paper2005")
r = eyelume.render(
    scene, eyelume.RenderOptions(rays=200_000, seed=5, batch_size=int(sys.argv[2]))
)
np.save(sys.argv[1], np.concatenate([r.eye_image.ravel(), r.eye_plane.ravel()]))
"""


@pytest.mark.slow
def test_same_seed_same_arrays_whatever_the_thread_count(tmp_path):
    outs = []
    for threads, batch in (("1", "200000"), ("2", "65536")):
        path = tmp_path / f"t{threads}.npy"
        subprocess.run(
            [sys.executable, "-c", _SCRIPT, str(path), batch],
            check=True,
            env={**os.environ, "NUMBA_NUM_THREADS": threads},
        )
        outs.append(np.load(path))
    assert np.array_equal(outs[0], outs[1])
