"""A long render stopped with Ctrl-C keeps the batches it finished and writes them out."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import pytest


@pytest.mark.slow
def test_ctrl_c_writes_the_finished_batches(tmp_path):
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-c",
        "from eyelume.cli import app; app()",
        "render",
        "--rays",
        "1000000000",
        "--seed",
        "3",
        "--out",
        str(out),
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = proc.stderr.readline()  # printed once the scene is compiled, as tracing starts
        if first.startswith("compiling kernels"):  # a cold Numba cache says so first
            first = proc.stderr.readline()
        assert "tracing" in first, first
        time.sleep(2.0)  # the first batch may still compile the kernel: the stop waits for it
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=300)
    finally:  # a failed check must not leave a 10⁹-ray render running
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    batch = 262_144  # the preset's run.batch_size
    assert 0 < summary["rays"] < 1_000_000_000 and summary["rays"] % batch == 0
    p = summary["power_w"]
    assert p["sensor"] + p["escaped"] + sum(p["absorbed"].values()) == pytest.approx(
        p["emitted"], rel=1e-9
    )
    assert "interrupted" in err
