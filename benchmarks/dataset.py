"""Labelled datasets (issue 17): labelled vr-offaxis 400 × 400 pictures per hour at the sensor's
noise (render_noise = "sensor") on the local pool with 1 and 2 workers and on a 2-worker Dask
LocalCluster, CPU-seconds per picture, and peak memory against the number of pictures.

    python benchmarks/dataset.py                       # ~30 min on 2 shared cores
    python benchmarks/dataset.py --pictures 8 --memory 2,8   # quicker

Each configuration runs ``eyelume.optimize.dataset.run_dataset`` in a fresh child process (so its
peak RSS is its own) into an empty folder, with the Numba cache warmed first (not timed). Per
configuration it records: the wall time of the whole run (worker start-up and kernel loading
included) and the steady rate between the commit of picture ``workers`` and the last one; the CPU
seconds of the run's whole process tree (parent, workers, Dask's nannies) per picture, overall
and steady; the load average and the CPU the rest of the machine used meanwhile (this machine is
shared: the wall figures are what the run got, the CPU figures what it cost); the labels'
samples per pixel and how often the render's median skin error was below the shot noise; the
parent's peak RSS and the largest worker RSS seen. "projected_uncontended_per_hour" is 2 cores ×
3600 / steady CPU-s per picture: what the CPU cost allows on 2 idle cores, a projection, not a
measurement.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
import _common as C  # noqa: E402

RESULTS = "dataset"

DATASET = """
name = "bench-vr-offaxis"
scene = "vr-offaxis"
seed = 1
pictures = {pictures}
image_bits = 8
irradiance = true
render_noise = "sensor"
[gaze]
horizontal = [-25.0, 25.0]
vertical = [-20.0, 20.0]
[[vary]]
path = "eye.pupil_diameter_mm"
range = [2.0, 7.0]
[[vary]]
path = "head_offset_mm"
range = [[-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0]]
"""


def _tree_cpu(proc) -> float:
    """CPU seconds (user + system) of ``proc`` and its living descendants."""
    import psutil

    total = 0.0
    for p in [proc, *proc.children(recursive=True)]:
        try:
            t = p.cpu_times()
            total += t.user + t.system
        except psutil.Error:
            pass
    return total


def _worker_rss(proc) -> int:
    import psutil

    most = 0
    for p in proc.children(recursive=True):
        try:
            most = max(most, p.memory_info().rss)
        except psutil.Error:
            pass
    return most


def child(pictures: int, workers: int, dask: str | None) -> dict:
    """One run in this (fresh) process; its figures as a dict."""
    import psutil

    from eyelume.optimize.dataset import load_dataset, run_dataset

    me = psutil.Process()
    hz = os.sysconf("SC_CLK_TCK")
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "ds.toml"
        p.write_text(DATASET.format(pictures=pictures), encoding="utf-8")
        ds = load_dataset(p)
        commits: list[tuple[float, float]] = []  # (time, tree CPU) at each commit
        rss = [0]

        def progress(done: int, total: int) -> None:
            if done:
                commits.append((time.perf_counter(), _tree_cpu(me)))
                rss[0] = max(rss[0], _worker_rss(me))

        k0, c0, t0 = C.cpu_ticks(), _tree_cpu(me), time.perf_counter()
        load0 = C.loadavg()
        run_dataset(ds, Path(tmp) / "out", workers=workers, dask=dask, progress=progress)
        wall = time.perf_counter() - t0
        k1 = C.cpu_ticks()
        tree_cpu = commits[-1][1] - c0
        lines = (Path(tmp) / "out" / "labels.jsonl").read_text(encoding="utf-8").splitlines()
        renders = [json.loads(x)["render"] for x in lines]
    k = min(workers, len(commits) - 1)
    steady_n = len(commits) - 1 - k
    (ta, ca), (tb, cb) = commits[k], commits[-1]
    below = [r["median_skin_rel_error"] <= r["skin_shot_noise"] for r in renders]
    out = {
        "pictures": pictures,
        "workers": workers,
        "dask": dask,
        "wall_s": wall,
        "per_hour": pictures / wall * 3600,
        "cpu_s_per_picture": tree_cpu / pictures,
        "steady_pictures": steady_n,
        "steady_per_hour": steady_n / (tb - ta) * 3600 if steady_n else None,
        "steady_cpu_s_per_picture": (cb - ca) / steady_n if steady_n else None,
        "load_start": load0,
        "load_end": C.loadavg(),
        "others_cpu_s": None if not (k0 and k1) else (k1[0] - k0[0]) / hz - tree_cpu,
        "samples_per_pixel": sorted({r["samples_per_pixel"] for r in renders}),
        "median_skin_rel_error_median": statistics.median(
            r["median_skin_rel_error"] for r in renders
        ),
        "skin_shot_noise_median": statistics.median(r["skin_shot_noise"] for r in renders),
        "share_render_below_shot_noise": sum(below) / len(below),
        "parent_peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "worker_peak_rss_mib_seen": rss[0] / 2**20,
    }
    if out["steady_cpu_s_per_picture"]:
        out["projected_uncontended_per_hour"] = 2 * 3600 / out["steady_cpu_s_per_picture"]
    return out


def run_child(pictures: int, workers: int, dask: str | None) -> dict:
    cmd = [sys.executable, __file__, "--child", f"{pictures},{workers},{dask or ''}"]
    env = {**os.environ, "NUMBA_CACHE_DIR": str(C.WARM_CACHE)}
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    if res.returncode != 0:
        raise RuntimeError(f"child {cmd} failed:\n{res.stderr[-3000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pictures", type=int, default=24, help="pictures per throughput run")
    ap.add_argument("--memory", default="4,16,48", help="pictures of the memory runs (2 workers)")
    ap.add_argument("--only", default="pool1,pool2,dask2,memory")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        n, w, d = a.child.split(",")
        print(json.dumps(child(int(n), int(w), d or None)))
        return
    info = {"machine": C.machine(), "command": C.command_line()}
    title = "labelled datasets: vr-offaxis 400 x 400, render_noise = sensor"
    C.print_header(title, info["machine"])
    print("   warming the Numba cache (one picture, not timed)…", flush=True)
    run_child(1, 1, None)
    only = set(a.only.split(","))
    out: dict = {"runs": []}  # one line per run in results/dataset.jsonl
    plan = [(a.pictures, 1, None, "pool1"), (a.pictures, 2, None, "pool2"),
            (a.pictures, 2, "local", "dask2")]  # fmt: skip
    plan = [x for x in plan if x[3] in only]
    if "memory" in only:
        plan += [(int(n), 2, None, "memory") for n in a.memory.split(",")]
    for pictures, workers, dask, tag in plan:
        r = run_child(pictures, workers, dask)
        r["config"] = tag
        out["runs"].append(r)
        C.append_result(RESULTS, {**info, "run": r})  # each run kept as it finishes
        steady = r["steady_per_hour"]
        print(
            f"   {tag:7s} {pictures:3d} pictures, {workers} workers{' (dask)' if dask else ''}: "
            f"{r['wall_s']:7.1f} s wall = {r['per_hour']:6.0f}/h overall"
            + (f", {steady:6.0f}/h steady" if steady else "")
            + f"; {r['cpu_s_per_picture']:.1f} CPU-s/picture"
            + (f" ({r['steady_cpu_s_per_picture']:.1f} steady)" if steady else "")
            + f"; load {r['load_start'][0]:.1f}→{r['load_end'][0]:.1f}, others used "
            f"{r['others_cpu_s'] or 0:.0f} CPU-s; parent peak {r['parent_peak_rss_mib']:.0f} MiB,"
            f" worker {r['worker_peak_rss_mib_seen']:.0f} MiB; spp {r['samples_per_pixel']}, "
            f"render < shot noise in {r['share_render_below_shot_noise']:.0%}",
            flush=True,
        )
    best = [r.get("projected_uncontended_per_hour") for r in out["runs"]
            if r["workers"] == 2 and r["steady_pictures"] >= 4]  # fmt: skip
    best = [x for x in best if x]
    if best:
        print(f"   projection on 2 idle cores from the steady CPU cost: {max(best):.0f}/h "
              "(target ≥ 1000 labelled pictures per hour)")  # fmt: skip


if __name__ == "__main__":
    main()
