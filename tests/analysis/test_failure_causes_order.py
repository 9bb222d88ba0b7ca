"""evaluate.failure_causes: the same frames give the same causes in the same order in every
process (ties by name), so `evaluate-tracking`'s "mostly …" line does not change between runs
of identical frames (it named LED 2's cause in one run and LED 0's in the next: the order of a
set of strings follows the process's hash seed)."""

from __future__ import annotations

import os
import subprocess
import sys

SNIPPET = """
from types import SimpleNamespace as NS
from eyelume.analysis.tracking.evaluate import failure_causes
def frame(*failures):
    return NS(detection=NS(ok=False, failures=list(failures)))
frames = [
    frame("glint 3 (LED 2) is broken up: x", "glint 1 (LED 0) is broken up: y"),
    frame("glint 0 (LED 0) is broken up: z", "glint 2 (LED 2) is broken up: w"),
    frame("pupil cut or hidden: a", "glint lost: b"),
    frame("warning: not counted"),
]
print(list(failure_causes(frames).items()))
"""


def _run(seed: str) -> str:
    env = {**os.environ, "PYTHONHASHSEED": seed}
    out = subprocess.run(
        [sys.executable, "-c", SNIPPET], env=env, capture_output=True, text=True, check=True
    )
    return out.stdout.strip()


def test_causes_in_the_same_order_whatever_the_hash_seed():
    runs = {_run(str(seed)) for seed in range(6)}
    assert len(runs) == 1, runs
    got = eval(runs.pop())  # noqa: S307 — our own subprocess's repr of a list of tuples
    counts = [n for _, n in got]
    assert counts == sorted(counts, reverse=True)
    for (a, n), (b, m) in zip(got, got[1:], strict=False):
        assert n > m or a < b, got
    assert ("no detection", 1) in got  # a frame with only warnings is lost without a cause
