"""The paper scene's 87 × 65 fast render, timed as a user calls it, in whatever tree is on the
path: for comparing two commits interleaved on the same machine state (issue 10's "no slower").

    git worktree add --detach /tmp/old c7cc679
    B=benchmarks/paper_render_calls.py
    for i in 1 2; do
      TREE=old PYTHONPATH=/tmp/old/src NUMBA_CACHE_DIR=/tmp/nb-old python $B
      TREE=new PYTHONPATH=$PWD/src NUMBA_CACHE_DIR=/tmp/nb-new python $B
    done

The scene is compiled once, outside the timing; one tiny warm-up render loads the kernels; then
three calls each of ``rel_error=0.01`` and of the default budget (32 samples per pixel), their
wall and CPU times. Works with the keyword API of commits before issue 10 and with
``RenderOptions`` after it. Prints one JSON line (best wall and CPU seconds, the load average).
"""

import json
import os
import time

import eyelume
from eyelume.compile import compile_scene
from eyelume.scene.io import load_scene

cs = compile_scene(load_scene("paper2005"))


def _run(**kw):
    if hasattr(eyelume, "RenderOptions"):
        return eyelume.render(cs, eyelume.RenderOptions(**kw))
    return eyelume.render(cs, **kw)  # the keyword API before issue 10


_run(estimator="fast", samples_per_pixel=2, seed=9)  # loads (or compiles) the kernels
out: dict = {"tree": os.environ.get("TREE", "")}
for name, kw in (("rel_error_0.01", {"estimator": "fast", "rel_error": 0.01, "seed": 1}),
                 ("default", {"seed": 1})):  # fmt: skip
    walls, cpus = [], []
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        _run(**kw)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    out[name] = {"best_wall_s": round(min(walls), 3), "walls_s": [round(w, 3) for w in walls],
                 "best_cpu_s": round(min(cpus), 3)}  # fmt: skip
out["loadavg"] = os.getloadavg()
print(json.dumps(out))
