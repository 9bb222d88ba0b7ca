"""Running a study on a local process pool, committing each finished run to the store at once.

Runs are independent and each is a pure function of its inputs (fixed seeds), so results do not
depend on the number of workers or the order runs finish; the table is read back in plan order.
Workers are fresh processes (``spawn``) with one Numba thread each, so N workers use N cores.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

from eyelume.optimize.store import ResultStore
from eyelume.optimize.study import Study, plan_runs, run_key, run_metrics
from eyelume.scene.io import load_scene
from eyelume.scene.model import Scene

__all__ = ["run_study"]


def _init_worker() -> None:
    import numba

    numba.set_num_threads(1)


def _one(scene_json: dict, overrides: dict, study_json: dict) -> tuple[dict, float]:
    t0 = time.perf_counter()
    base = Scene.model_validate(scene_json)
    metrics = run_metrics(base, overrides, Study.model_validate(study_json))
    return metrics, time.perf_counter() - t0


def run_study(
    study: Study,
    out: str | Path,
    workers: int | None = None,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> list[dict]:
    """Run every planned run not yet in ``out``'s store; returns the store's rows.

    Without ``resume`` a folder that already holds runs is refused (ValueError); with it, the
    finished runs are skipped. ``progress(done, total)`` after each commit.
    """
    base = load_scene(study.scene)
    runs = plan_runs(study)
    keys = [run_key(base, r, study) for r in runs]
    store = ResultStore(out)
    try:
        done = store.done()
        if done and not resume:
            raise ValueError(f"{out}: holds {len(done)} finished runs; use --resume or a new --out")
        others = store.studies() - {study.name}
        if others:
            raise ValueError(f"{out}: holds runs of another study ({', '.join(sorted(others))})")
        todo = [(i, r, k) for i, (r, k) in enumerate(zip(runs, keys, strict=True)) if k not in done]
        finished = len(runs) - len(todo)
        if progress:
            progress(finished, len(runs))
        workers = workers or os.cpu_count() or 1
        scene_json = base.model_dump(mode="json")
        study_json = study.model_dump(mode="json")
        ctx = mp.get_context("spawn")
        with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init_worker) as pool:
            pending = {pool.submit(_one, scene_json, r, study_json): (i, r, k) for i, r, k in todo}
            while pending:
                ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in ready:
                    i, r, k = pending.pop(fut)
                    metrics, seconds = fut.result()
                    store.put(k, i, study.name, r, metrics, seconds)
                    finished += 1
                    if progress:
                        progress(finished, len(runs))
        return store.rows()
    finally:
        store.close()
