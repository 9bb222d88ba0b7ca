"""Studies at scale (issue 6): throughput of a 1000-run study of eye-plane sweeps on the local
pool with 1 and 2 workers and on a 2-worker local Dask cluster, and the store's cost per run.

    python benchmarks/study.py            # ~2 min on 2 cores
    python benchmarks/study.py --runs 200 # quicker

The study: the paper2005 LEDs at 1000 placements (Y 20–40 × Z 20–70 × θ 0–30 over a 10 × 10 ×
10 grid), metrics eye_plane_merit (closed form against the δ = 0.3 target) and safety. Each
runner starts from an empty folder; worker start-up is included (it is part of a study).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _common import command_line, loadavg, machine, print_header  # noqa: E402

RESULTS = Path(__file__).parent / "results" / "study.jsonl"


def study_text(n_side: int) -> str:
    return f"""
name = "bench"
scene = "paper2005"
seed = 1
metrics = ["eye_plane_merit", "safety"]
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, {n_side}]
[[vary]]
path = "leds.distance_mm"
grid = [20.0, 70.0, {n_side}]
[[vary]]
path = "leds.pitch_deg"
grid = [0.0, 30.0, {n_side}]
"""


def main() -> None:
    from eyelume.optimize.runner import run_study
    from eyelume.optimize.store import ResultStore
    from eyelume.optimize.study import load_study, plan_runs

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000, help="about this many (a cube)")
    a = ap.parse_args()
    n_side = max(2, round(a.runs ** (1 / 3)))
    info = {"machine": machine(), "command": command_line(), "load_start": loadavg()}
    print_header("studies at scale", info["machine"])
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "study.toml"
        p.write_text(study_text(n_side), encoding="utf-8")
        st = load_study(p)
        n = len(plan_runs(st))
        out["runs"] = n
        for label, kw in (
            ("pool, 1 worker", {"workers": 1}),
            ("pool, 2 workers", {"workers": 2}),
            ("dask LocalCluster, 2 workers", {"workers": 2, "dask": "local"}),
        ):
            t0 = time.perf_counter()
            run_study(st, Path(tmp) / label.replace(" ", "_").replace(",", ""), **kw)
            wall = time.perf_counter() - t0
            out[label] = {"wall_s": wall, "runs_per_s": n / wall}
            print(f"   {label:30s}: {wall:6.2f} s, {n / wall:7.1f} runs/s ({n} runs)")
        # the store's own cost: 1000 committed inserts of a typical row
        store = ResultStore(Path(tmp) / "store_only")
        row = {"eye_plane_merit": 0.01, "corneal_margin": 9.7, "retinal_margin": 23.0}
        t0 = time.perf_counter()
        for i in range(1000):
            store.put(f"k{i}", i, "bench", {"leds.height_mm": 20.0 + i}, row, 0.01)
        per = (time.perf_counter() - t0) / 1000 * 1e3
        store.close()
        out["store_ms_per_run"] = per
    one, two = out["pool, 1 worker"]["wall_s"], out["pool, 2 workers"]["wall_s"]
    dask = out["dask LocalCluster, 2 workers"]["wall_s"]
    print(f"   store: {per:.3f} ms per committed run  [{'PASS' if per <= 5 else 'FAIL'} ≤ 5 ms]")
    print(f"   speed-up: pool 2 vs 1 worker {one / two:.2f}×; dask 2 workers vs 1 process "
          f"{one / dask:.2f}×")  # fmt: skip
    info["load_end"] = loadavg()
    RESULTS.parent.mkdir(exist_ok=True)
    with open(RESULTS, "a", encoding="utf-8") as f:
        f.write(json.dumps({**info, **out}) + "\n")


if __name__ == "__main__":
    main()
