"""Is the default render bit-identical to the one recorded before the issue-10 refactor?

    python benchmarks/bit_identity.py

Renders ``eyelume.render(load_scene("paper2005"), RenderOptions(seed=1))`` and compares the SHA-256
of its ``eye_image``, ``eye_image_variance`` and ``eye_plane`` (float64, C order) with
``results/bit_identity.json``, recorded on this project's 2-vCPU machine by the commit that made
the camera samples' stop aim take Broyden-updated steps (a deliberate change of the samples at
rounding level), before it by the commit that gave the specular connections an analytic Jacobian (a
deliberate change of the samples at rounding level), before it by the commit that aimed light paths
at the glints, before it by the commit that made the first vertex's continuation skip its free cone
(a deliberate change of the samples), before it by the commit that made a later vertex's connection
through the cornea draw one LED (a deliberate change of the samples), before it by the commit that
made the fast camera paths continue in stratified directions and draw a later vertex's LED by its
unshadowed irradiance (likewise), by the commit that added the iris root (issue 12) and at commit
3b58b61.
Prints MATCH or DIFFER per array and exits 1 on any difference. (The test suite's
``tests/test_bit_identity.py`` checks the same arrays to 1e-9 relative, portable across CPUs.)
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

import eyelume

RESULTS = Path(__file__).parent / "results" / "bit_identity.json"


def main() -> int:
    want = json.loads(RESULTS.read_text())["sha256"]
    r = eyelume.render(eyelume.load_scene("paper2005"), eyelume.RenderOptions(seed=1))
    got = {
        "eye_image": r.eye_image,
        "eye_image_variance": r.eye_image_variance,
        "eye_plane": r.eye_plane,
    }
    bad = 0
    for name, arr in got.items():
        h = hashlib.sha256(np.ascontiguousarray(arr, dtype=np.float64).tobytes()).hexdigest()
        ok = h == want[name]
        bad += not ok
        print(f"{name:20s} {'MATCH' if ok else 'DIFFER'}  {h[:16]}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
