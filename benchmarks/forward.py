"""Forward Monte Carlo tracer on the default scene ``paper2005``: speed, start-up, memory.

Run from the repository root::

    python benchmarks/forward.py            # full run, a few minutes on 2 cores
    python benchmarks/forward.py --quick    # smoke run
    python benchmarks/forward.py --only throughput,anatomy

Every figure is measured in a fresh subprocess of this script (``--worker``), so the thread count
(``NUMBA_NUM_THREADS``), the Numba cache (``NUMBA_CACHE_DIR``) and the peak RSS belong to that
measurement alone. Warm figures use a Numba cache under the temp dir (not ``src/``); the cold
start-up uses an empty cache each time. Prints the figures and how they were run, and appends one
JSON line to ``benchmarks/results/forward.jsonl``.

Figures
-------
throughput  rays/s and surface interactions/s of
            ``eyelume.render(compiled, RenderOptions(rays=N, seed=S))`` after compilation, per
            thread count; best of ``--repeats`` plus spread; the wall time of the paper's 1.5 M-ray
            run (LightTools: ~20 min on a 3.2 GHz Pentium 4).
startup     ``python -c "import eyelume"``; process start → first 1000-ray render done with an
            empty Numba cache (compile) and with the cache that run filled.
memory      max RSS (``resource.getrusage``) and the tracemalloc peak of one render of 10⁶, 10⁷,
            3·10⁷ rays: flat in the ray count because rays are traced in batches.
anatomy     where the time goes: face on/off, interactions per ray, the non-sequential table size,
            and the cost of one non-sequential nearest-hit search on emission rays.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402

SCENE = "paper2005"
PAPER_RAYS = 1_500_000
PAPER_LIGHTTOOLS_S = 20 * 60.0
RESULT_TAG = "RESULT "


# ------------------------------------------------------------------------------------------------
# workers (run in a subprocess)
# ------------------------------------------------------------------------------------------------


def _overrides(face: bool) -> dict:
    return {} if face else {"face.enabled": "false"}


def worker_throughput(a: argparse.Namespace) -> dict:
    import numba

    import eyelume
    from eyelume.compile import compile_scene

    threads = numba.get_num_threads()
    cs = compile_scene(eyelume.load_scene(SCENE, _overrides(not a.face_off)))
    batch = cs.scene.run.batch_size
    eyelume.render(cs, eyelume.RenderOptions(rays=1000, seed=a.seed))  # JIT (from the warm cache)
    eyelume.render(
        cs, eyelume.RenderOptions(rays=min(a.rays, batch), seed=a.seed)
    )  # thread pool, first touch
    traced: list[float] = []

    def once():
        r = eyelume.render(cs, eyelume.RenderOptions(rays=a.rays, seed=a.seed))
        traced.append(r.wall_time_s)
        return r

    t = C.timed(once, a.repeats, threads)
    r = t.pop("last")
    best = min(traced)
    ledger = {k: v / r.emitted_w for k, v in r.ledger.items() if v > 0}
    return {
        "threads": threads,
        "face": not a.face_off,
        "rays": a.rays,
        "seed": a.seed,
        "batch_size": batch,
        "render_call": t,
        "trace_wall_s": traced,
        "trace_best_s": best,
        "trace_spread_pct": 100.0 * (max(traced) - best) / best,
        "rays_per_s": a.rays / best,
        "interactions": r.interactions,
        "interactions_per_ray": r.interactions / a.rays,
        "interactions_per_s": r.interactions / best,
        "ns_per_interaction_per_thread": 1e9 * best * threads / r.interactions,
        "ns_per_ray_per_thread": 1e9 * best * threads / a.rays,
        "ns_surfaces": int(cs.sf.shape[0]),
        "surface_names": cs.surface_names,
        "lens_surfaces": int(cs.lf.shape[0]),
        "ledger_fraction": ledger,
    }


def worker_startup(a: argparse.Namespace) -> dict:
    # time.time() first: the parent compares it with its own clock read before the spawn
    t_entry = time.time()
    t0 = time.perf_counter()
    import eyelume
    from eyelume.compile import compile_scene

    t1 = time.perf_counter()
    scene = eyelume.load_scene(SCENE)
    t2 = time.perf_counter()
    cs = compile_scene(scene)
    t3 = time.perf_counter()
    r = eyelume.render(cs, eyelume.RenderOptions(rays=1000, seed=a.seed))
    t4 = time.perf_counter()
    t_done = time.time()
    return {
        "t_entry_epoch": t_entry,
        "t_done_epoch": t_done,
        "import_s": t1 - t0,
        "load_scene_s": t2 - t1,
        "compile_scene_s": t3 - t2,
        "first_render_s": t4 - t3,
        "first_render_trace_s": r.wall_time_s,
        "cache_dir": os.environ.get("NUMBA_CACHE_DIR"),
    }


def worker_memory(a: argparse.Namespace) -> dict:
    import resource
    import tracemalloc

    import numba

    import eyelume
    from eyelume.compile import compile_scene

    cs = compile_scene(eyelume.load_scene(SCENE))
    eyelume.render(cs, eyelume.RenderOptions(rays=1000, seed=a.seed))
    rss_warm = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    tracemalloc.start()
    t0 = time.perf_counter()
    r = eyelume.render(cs, eyelume.RenderOptions(rays=a.rays, seed=a.seed))
    wall = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss_end = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "threads": numba.get_num_threads(),
        "rays": a.rays,
        "rss_warm_mib": rss_warm / 1024,
        "max_rss_mib": rss_end / 1024,
        "rss_growth_mib": (rss_end - rss_warm) / 1024,
        "tracemalloc_peak_mib": peak / 2**20,
        "wall_s": wall,
        "rays_done": r.rays,
    }


def _anatomy_kernels():
    """The three timed kernels of :func:`worker_anatomy`: emission, nearest-hit search, and the
    LED profile's inverse-CDF search (compiled here, after the worker has set its threads)."""
    from numba import njit

    from eyelume.estimators.forward import emit_ray
    from eyelume.kernels.geometry import nearest_hit
    from eyelume.kernels.sampling import profile_polar_angle

    @njit
    def emission_rays(n, seed, leds, out):
        # the first segment of every ray, drawn by the forward estimator's own emission kernel
        for i in range(n):
            _, x, y, z, dx, dy, dz = emit_ray(i, seed, leds)
            out[i, 0], out[i, 1], out[i, 2] = x, y, z
            out[i, 3], out[i, 4], out[i, 5] = dx, dy, dz

    @njit
    def search_all(sf, si, rays, hits):
        acc = 0.0
        for i in range(rays.shape[0]):
            s, t = nearest_hit(
                sf, si, rays[i, 0], rays[i, 1], rays[i, 2], rays[i, 3], rays[i, 4], rays[i, 5]
            )
            hits[i] = s
            if s >= 0:
                acc += t
        return acc

    @njit
    def polar_only(u, alpha_grid, cdf_grid):
        # the inverse-CDF search of the LED profile alone (part of the emission sampling)
        acc = 0.0
        for i in range(u.shape[0]):
            acc += profile_polar_angle(u[i], alpha_grid, cdf_grid)
        return acc

    return emission_rays, search_all, polar_only


def worker_anatomy(a: argparse.Namespace) -> dict:
    """Cost of one non-sequential nearest-hit search on the scene's emission rays (1 thread)."""
    import numpy as np

    import eyelume
    from eyelume.compile import compile_scene

    emission_rays, search_all, polar_only = _anatomy_kernels()
    out = {}
    for face in (True, False):
        cs = compile_scene(eyelume.load_scene(SCENE, _overrides(face)))
        n = a.rays
        uu = np.random.default_rng(a.seed).random(n)
        polar_only(uu[:1000], cs.led.alpha_grid, cs.led.cdf_grid[0])
        t_polar = []
        rays = np.empty((n, 6))
        hits = np.empty(n, dtype=np.int64)
        emission_rays(1000, a.seed, cs.led, rays)
        search_all(cs.sf, cs.si, rays[:1000], hits[:1000])
        eyelume.render(cs, eyelume.RenderOptions(rays=min(n, cs.scene.run.batch_size), seed=a.seed))
        # interleaved, so the three costs see the same machine conditions
        t_render, t_emit, t_search, res = [], [], [], None
        for _ in range(a.repeats):
            res = eyelume.render(cs, eyelume.RenderOptions(rays=n, seed=a.seed))
            t_render.append(res.wall_time_s)
            t0 = time.perf_counter()
            emission_rays(n, a.seed, cs.led, rays)
            t_emit.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            search_all(cs.sf, cs.si, rays, hits)
            t_search.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            polar_only(uu, cs.led.alpha_grid, cs.led.cdf_grid[0])
            t_polar.append(time.perf_counter() - t0)
        counts = np.bincount(hits + 1, minlength=cs.sf.shape[0] + 1)
        first = {"(escape)": int(counts[0])}
        first.update(
            {
                cs.surface_names[j]: int(counts[j + 1])
                for j in range(cs.sf.shape[0])
                if counts[j + 1]
            }
        )

        def spread(ts):
            return 100.0 * (max(ts) - min(ts)) / min(ts)

        out["face" if face else "no_face"] = {
            "surfaces": int(cs.sf.shape[0]),
            "rays": n,
            "render_s": t_render,
            "emission_s": t_emit,
            "search_s": t_search,
            "ns_per_ray": 1e9 * min(t_render) / n,
            "ns_per_emission": 1e9 * min(t_emit) / n,
            "ns_per_search": 1e9 * min(t_search) / n,
            "ns_per_polar_search": 1e9 * min(t_polar) / n,
            "cdf_grid_size": int(cs.led.cdf_grid.shape[1]),
            "spread_pct": {
                "render": spread(t_render),
                "emission": spread(t_emit),
                "search": spread(t_search),
            },
            "interactions_per_ray": res.interactions / n,
            "ledger_fraction": {k: v / res.emitted_w for k, v in res.ledger.items() if v > 0},
            "first_hit_fraction": {k: v / n for k, v in first.items()},
        }
    return out


WORKERS = {
    "throughput": worker_throughput,
    "startup": worker_startup,
    "memory": worker_memory,
    "anatomy": worker_anatomy,
}


def run_worker(kind: str, env_extra: dict, args: list[str], timeout: float = 1800) -> dict:
    """Run ``--worker kind`` in a fresh interpreter; returns its result and the spawn times."""
    env = {**os.environ, **{k: str(v) for k, v in env_extra.items()}}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", kind, *args]
    t_spawn = time.time()
    p0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    p1 = time.perf_counter()
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise RuntimeError(f"worker {kind} failed ({proc.returncode})")
    line = next(ln for ln in proc.stdout.splitlines()[::-1] if ln.startswith(RESULT_TAG))
    res = json.loads(line[len(RESULT_TAG) :])
    res["_spawn_epoch"] = t_spawn
    res["_process_wall_s"] = p1 - p0
    res["_env"] = env_extra
    return res


def quote_env(env: dict) -> str:
    return " ".join(f"{k}={v}" for k, v in env.items())


# ------------------------------------------------------------------------------------------------
# parent
# ------------------------------------------------------------------------------------------------


def bench_throughput(a: argparse.Namespace, out: dict) -> None:
    print(f"\n-- throughput: render(compiled, RenderOptions(rays={a.rays:_}, seed={a.seed})), warm")
    rows = {}
    for th in a.threads:
        env = {"NUMBA_NUM_THREADS": th, "NUMBA_CACHE_DIR": C.WARM_CACHE}
        args = ["--rays", str(a.rays), "--repeats", str(a.repeats), "--seed", str(a.seed)]
        r = run_worker("throughput", env, args)
        rows[str(th)] = r
        warn = C.disturbed(r["render_call"])
        print(
            f"   threads={th}: {C.fmt_rate(r['rays_per_s'])}rays/s, "
            f"{C.fmt_rate(r['interactions_per_s'])}interactions/s "
            f"(trace best {r['trace_best_s']:.3f} s, spread {r['trace_spread_pct']:.1f} %, "
            f"walls {[round(w, 4) for w in r['trace_wall_s']]}, cpu_util "
            f"{r['render_call']['cpu_util']}, others {r['render_call']['others_cpu_s']} CPU-s, "
            f"steal {r['render_call']['steal_s']} s){warn}"
        )
        print(
            f"      [{quote_env(env)} python benchmarks/forward.py --worker throughput "
            f"{' '.join(args)}]"
        )
    first = rows[str(a.threads[0])]
    print(
        f"   interactions/ray = {first['interactions_per_ray']:.3f}, "
        f"non-sequential surfaces = {first['ns_surfaces']}, lens surfaces = "
        f"{first['lens_surfaces']}"
    )
    if len(a.threads) > 1:
        lo, hi = rows[str(a.threads[0])], rows[str(a.threads[-1])]
        print(
            f"   scaling {a.threads[0]}→{a.threads[-1]} threads: "
            f"{hi['rays_per_s'] / lo['rays_per_s']:.2f}×"
        )
    out["throughput"] = rows
    if a.rays == PAPER_RAYS:
        top = rows[str(max(a.threads))]
        print(
            f"   paper run, {PAPER_RAYS:_} rays at {max(a.threads)} threads: "
            f"{top['trace_best_s']:.3f} s (target ≤ 1 s; LightTools ~{PAPER_LIGHTTOOLS_S:.0f} s "
            f"→ {PAPER_LIGHTTOOLS_S / top['trace_best_s']:.0f}× faster)"
        )
        out["paper_run_s"] = top["trace_best_s"]


IMPORT_WATCH = (
    "eyelume",
    "numba",
    "scipy",
    "pydantic",
    "eyelume.scene.model",
    "eyelume.kernels.rng",
    "eyelume.kernels.geometry",
)


def import_profile(env_extra: dict) -> dict:
    """``python -X importtime -c "import eyelume"``: cumulative time of a few modules and the
    largest self times (seconds)."""
    env = {**os.environ, **{k: str(v) for k, v in env_extra.items()}}
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import eyelume"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    self_t, cum_t = {}, {}
    for ln in proc.stderr.splitlines():
        if not ln.startswith("import time:") or "self [us]" in ln:
            continue
        s_us, c_us, name = (f.strip() for f in ln[len("import time:") :].split("|"))
        self_t[name] = int(s_us) / 1e6
        cum_t[name] = int(c_us) / 1e6
    top = dict(sorted(self_t.items(), key=lambda kv: -kv[1])[:6])
    return {
        "cumulative_s": {k: cum_t[k] for k in IMPORT_WATCH if k in cum_t},
        "top_self_s": top,
    }


def bench_startup(a: argparse.Namespace, out: dict) -> None:
    th = max(a.threads)
    print(f"\n-- start-up (NUMBA_NUM_THREADS={th}): process start → first 1000-ray render done")
    res: dict = {"import": [], "cold": [], "warm": []}
    base_env = {"NUMBA_NUM_THREADS": th}
    for _ in range(a.import_repeats):
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-c", "import eyelume"],
            check=True,
            env={**os.environ, **{k: str(v) for k, v in base_env.items()}},
        )
        res["import"].append(time.perf_counter() - t0)
    py = []
    for _ in range(a.import_repeats):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        py.append(time.perf_counter() - t0)
    res["python_bare"] = py
    res["importtime"] = import_profile(base_env)
    print(
        f"   python -c 'import eyelume': best {min(res['import']):.3f} s "
        f"(all {[round(x, 3) for x in res['import']]}); bare 'python -c pass' {min(py):.3f} s"
    )
    prof = res["importtime"]
    print(
        "   python -X importtime -c 'import eyelume' (one run), cumulative: "
        + ", ".join(f"{k} {v:.3f}" for k, v in prof["cumulative_s"].items())
    )
    print(
        "      largest self times: "
        + ", ".join(f"{k} {v:.3f}" for k, v in prof["top_self_s"].items())
    )
    keep = None
    made = []
    for i in range(a.cold_repeats):
        tmp = tempfile.mkdtemp(prefix="eyelume-cold-numba-")
        made.append(tmp)
        env = {**base_env, "NUMBA_CACHE_DIR": tmp}
        r = run_worker("startup", env, ["--seed", str(a.seed)])
        r["start_to_render_s"] = r["t_done_epoch"] - r["_spawn_epoch"]
        res["cold"].append(r)
        print(
            f"   cold #{i}: {r['start_to_render_s']:.2f} s  (import {r['import_s']:.2f}, "
            f"compile_scene {r['compile_scene_s']:.2f}, first render {r['first_render_s']:.2f}) "
            f"[{quote_env(env)} python benchmarks/forward.py --worker startup]"
        )
        keep = tmp
    for i in range(a.warm_repeats):
        env = {**base_env, "NUMBA_CACHE_DIR": keep}
        r = run_worker("startup", env, ["--seed", str(a.seed)])
        r["start_to_render_s"] = r["t_done_epoch"] - r["_spawn_epoch"]
        res["warm"].append(r)
        print(
            f"   warm #{i}: {r['start_to_render_s']:.3f} s  (import {r['import_s']:.3f}, "
            f"load_scene {r['load_scene_s']:.3f}, compile_scene {r['compile_scene_s']:.3f}, "
            f"first render {r['first_render_s']:.3f}) [cache of the last cold run]"
        )
    for tmp in made:  # the empty-cache directories this run made
        shutil.rmtree(tmp, ignore_errors=True)
    cold = [r["start_to_render_s"] for r in res["cold"]]
    warm = [r["start_to_render_s"] for r in res["warm"]]
    res["summary"] = {
        "import_best_s": min(res["import"]),
        "python_bare_best_s": min(py),
        "cold_best_s": min(cold),
        "cold_all_s": cold,
        "warm_best_s": min(warm),
        "warm_all_s": warm,
    }
    print(
        f"   → cold best {min(cold):.2f} s of {[round(x, 2) for x in cold]}; "
        f"warm best {min(warm):.3f} s of {[round(x, 3) for x in warm]} (target ≤ 1 s)"
    )
    out["startup"] = res


def bench_memory(a: argparse.Namespace, out: dict) -> None:
    th = max(a.threads)
    print(f"\n-- memory (NUMBA_NUM_THREADS={th}): one render per fresh process")
    rows = []
    for n in a.memory_rays:
        env = {"NUMBA_NUM_THREADS": th, "NUMBA_CACHE_DIR": C.WARM_CACHE}
        r = run_worker("memory", env, ["--rays", str(n), "--seed", str(a.seed)])
        rows.append(r)
        print(
            f"   rays={n:>12_}: max RSS {r['max_rss_mib']:.1f} MiB (after warm-up "
            f"{r['rss_warm_mib']:.1f}, growth {r['rss_growth_mib']:.1f}), tracemalloc peak "
            f"{r['tracemalloc_peak_mib']:.2f} MiB, {r['wall_s']:.1f} s"
        )
    out["memory"] = rows


def bench_anatomy(a: argparse.Namespace, out: dict) -> None:
    print("\n-- where the time goes (1 thread unless stated)")
    args = ["--rays", str(a.rays), "--repeats", str(a.repeats), "--seed", str(a.seed)]
    rows = {}
    for th in sorted({1, max(a.threads)}):
        env = {"NUMBA_NUM_THREADS": th, "NUMBA_CACHE_DIR": C.WARM_CACHE}
        on = out.get("throughput", {}).get(str(th)) or run_worker("throughput", env, args)
        off = run_worker("throughput", env, [*args, "--face-off"])
        rows[th] = (on, off)
        for lab, r in (("face on ", on), ("face off", off)):
            warn = C.disturbed(r["render_call"])
            print(
                f"   {th} thr, {lab}: {r['ns_surfaces']} non-sequential surfaces, "
                f"{r['interactions_per_ray']:.3f} interactions/ray, "
                f"{C.fmt_rate(r['rays_per_s'])}rays/s, "
                f"{C.fmt_rate(r['interactions_per_s'])}interactions/s, "
                f"{r['ns_per_ray_per_thread']:.0f} ns/ray/thread "
                f"(trace best {r['trace_best_s']:.3f} s, spread {r['trace_spread_pct']:.1f} %)"
                + warn
            )
    n_an = a.rays
    an = run_worker(
        "anatomy",
        {"NUMBA_NUM_THREADS": 1, "NUMBA_CACHE_DIR": C.WARM_CACHE},
        ["--rays", str(n_an), "--seed", str(a.seed), "--repeats", str(a.repeats)],
    )
    f = an["face"]
    lf = f["ledger_fraction"]
    ends = sorted(lf.items(), key=lambda kv: -kv[1])
    print("   ends (share of rays): " + ", ".join(f"{k} {v:.3%}" for k, v in ends))
    print(
        f"   one process, 1 thread, {n_an:_} rays, best of {a.repeats} interleaved repeats "
        "[NUMBA_NUM_THREADS=1 python benchmarks/forward.py --worker anatomy ...]:"
    )
    for key in ("face", "no_face"):
        s = an[key]
        top = sorted(s["first_hit_fraction"].items(), key=lambda kv: -kv[1])[:4]
        sp = s["spread_pct"]
        print(
            f"   {key:>7}: render {s['ns_per_ray']:.0f} ns/ray (spread {sp['render']:.0f} %), "
            f"emission sampling {s['ns_per_emission']:.0f} ns/ray ({sp['emission']:.0f} %; "
            f"its inverse-CDF search over {s['cdf_grid_size']} entries "
            f"{s['ns_per_polar_search']:.0f} ns), "
            f"nearest_hit over {s['surfaces']} surfaces on the emission rays "
            f"{s['ns_per_search']:.0f} ns/search ({sp['search']:.0f} %); first hits: "
            + ", ".join(f"{k} {v:.1%}" for k, v in top)
        )
    # searches per ray: one per event-loop turn = non-sequential interactions + the final
    # escape or lens entry; lens surfaces (≤ 11 per lens entry) are not searches.
    n_lens = rows[1][0]["lens_surfaces"]
    through = sum(lf.get(k, 0.0) for k in ("sensor", "image plane outside the sensor"))
    stopped = sum(
        lf.get(k, 0.0) for k in ("lens (total internal reflection)", "lens mount (vignetted)")
    )
    entries = through + stopped
    base = f["interactions_per_ray"] + lf.get("escaped", 0.0) + entries
    lo = base - n_lens * (through + stopped)
    hi = base - n_lens * through - stopped
    ns_ray, ns_s, ns_e = f["ns_per_ray"], f["ns_per_search"], f["ns_per_emission"]
    share = (lo * ns_s / ns_ray, hi * ns_s / ns_ray)
    rest = ns_ray - ns_e - 0.5 * (lo + hi) * ns_s
    print(
        f"   → face on: {ns_ray:.0f} ns/ray ≈ emission sampling {ns_e:.0f} ({ns_e / ns_ray:.0%}) "
        f"+ {lo:.2f}–{hi:.2f} searches × {ns_s:.0f} ns ({share[0]:.0%}–{share[1]:.0%}) + the rest "
        f"{rest:.0f} ns (interaction physics, scattering, eye-plane test, the lens for "
        f"{entries:.2%} of rays)"
    )
    out["anatomy"] = {
        "by_threads": {str(k): {"face_on": v[0], "face_off": v[1]} for k, v in rows.items()},
        "same_process_1_thread": an,
        "searches_per_ray_range": [lo, hi],
        "nearest_hit_share_range": list(share),
        "emission_share": ns_e / ns_ray,
    }


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="smoke run: small ray counts, 2 repeats")
    p.add_argument("--only", default="throughput,startup,memory,anatomy")
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    p.add_argument("--rays", type=int, default=PAPER_RAYS)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument(
        "--memory-rays", type=int, nargs="+", default=[1_000_000, 10_000_000, 30_000_000]
    )
    p.add_argument("--cold-repeats", type=int, default=3)
    p.add_argument("--warm-repeats", type=int, default=5)
    p.add_argument("--import-repeats", type=int, default=5)
    p.add_argument("--worker", choices=sorted(WORKERS), help=argparse.SUPPRESS)
    p.add_argument("--face-off", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args(argv)

    if a.worker:
        res = WORKERS[a.worker](a)
        print(RESULT_TAG + json.dumps(res, default=C._jsonable))
        return

    if a.quick:
        a.rays, a.repeats = 200_000, 2
        a.memory_rays = [100_000, 1_000_000]
        a.cold_repeats, a.warm_repeats, a.import_repeats = 1, 2, 2
    info = C.machine()
    C.print_header("eyelume forward tracer, scene paper2005", info)
    out: dict = {
        "machine": info,
        "command": C.command_line(),
        "quick": a.quick,
        "args": {k: v for k, v in vars(a).items() if k not in ("worker", "face_off")},
    }
    only = set(a.only.split(","))
    t0 = time.perf_counter()
    if "throughput" in only:
        bench_throughput(a, out)
    if "startup" in only:
        bench_startup(a, out)
    if "memory" in only:
        bench_memory(a, out)
    if "anatomy" in only:
        bench_anatomy(a, out)
    out["loadavg_at_end"] = C.loadavg()
    out["total_s"] = time.perf_counter() - t0
    path = C.append_result("forward", out)
    print(
        f"\nloadavg at end {out['loadavg_at_end']}; total {out['total_s']:.0f} s; "
        f"appended to {path.relative_to(C.REPO)}"
    )


if __name__ == "__main__":
    main()
