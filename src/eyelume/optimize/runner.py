"""Running independent tasks — a study's runs, a dataset's pictures — on a local process pool or
a Dask cluster, committing each finished task at once; and running a study with them.

Tasks are independent and each is a pure function of its inputs (fixed seeds), so results do not
depend on the number of workers or the order tasks finish; a study's table is read back in plan
order. Workers are fresh processes (``spawn``) with one Numba thread each, so N workers use N
cores. ``dask="local"`` starts a ``distributed.LocalCluster`` of ``workers`` single-threaded
worker processes; any other value is a scheduler address. The same tasks, the same results.

At most a few tasks per worker are in flight (:func:`run_tasks`: ``window``): the next task is
taken from the caller's iterator only as one finishes, so the parent holds no per-task state for
the tasks still to come (a dataset of a million pictures costs the parent what ten cost).

Workers end with their parent: each asks the kernel for SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``, Linux) and watches its parent's pid once a second (elsewhere), so a
study killed with ``kill -9`` leaves no worker behind. When the run stops — Ctrl-C, SIGTERM (the
command line turns it into the same interrupt), a commit that cannot be made — the queue is
dropped and the workers are terminated at once: no task is computed only to be thrown away.
"""

from __future__ import annotations

import ctypes
import multiprocessing as mp
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from eyelume.errors import OptionError, StoreError
from eyelume.json_files import write_json
from eyelume.optimize.store import LOCK_TIMEOUT_S, ResultStore
from eyelume.optimize.study import Study, plan_runs, run_key, run_metrics
from eyelume.scene.io import load_scene
from eyelume.scene.model import Scene

__all__ = ["check_scheduler", "run_study", "run_tasks"]


def _init_worker(parent: int | None = None) -> None:
    import numba

    numba.set_num_threads(1)
    if parent is not None:
        _die_with_parent(parent)


def _die_with_parent(parent: int) -> None:
    """End this worker when the process ``parent`` ends, however it ends (module docstring)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # 1 = PR_SET_PDEATHSIG
    except (AttributeError, OSError):
        pass  # not Linux: the watcher below

    def watch() -> None:
        while True:
            if os.getppid() != parent:
                os._exit(1)
            time.sleep(1.0)

    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)
    threading.Thread(target=watch, name="eyelume-parent-watch", daemon=True).start()


def _end_pool(pool: ProcessPoolExecutor) -> None:
    """Drop the queue and terminate the workers now (their runs in flight are lost; what is
    committed stays)."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.terminate()
    for proc in procs:
        proc.join(timeout=5)
        if proc.is_alive():
            proc.kill()


def _in_worker(fn: Callable, args: tuple):
    """``fn(*args)`` with one Numba thread in the calling thread (a Dask worker runs its tasks
    in a thread of its own, which the pool's initializer never saw)."""
    import numba

    if numba.get_num_threads() != 1:
        numba.set_num_threads(1)
    return fn(*args)


def _one(scene_json: dict, overrides: dict, study_json: dict) -> tuple[dict, float]:
    t0 = time.perf_counter()
    base = Scene.model_validate(scene_json)
    metrics = run_metrics(base, overrides, Study.model_validate(study_json))
    return metrics, time.perf_counter() - t0


#: What :func:`run_study` records of the study in its folder, for the report's captions: the
#: study's name, the base scene's name and file, seed, samples per pixel, δ and metrics.
STUDY_FILE = "study.json"


def run_study(
    study: Study,
    out: str | Path,
    workers: int | None = None,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
    dask: str | None = None,
    lock_timeout_s: float = LOCK_TIMEOUT_S,
    note: Callable[[str], None] | None = None,
) -> list[dict]:
    """Run every planned run not yet in ``out``'s store; returns the store's rows.

    The study's scene, seed and budget are written to ``out/study.json`` (:data:`STUDY_FILE`).
    Without ``resume`` a folder that already holds runs is refused (ValueError); with it, the
    finished runs are skipped. ``progress(done, total)`` after each commit; ``note(message)``
    when a commit waits for another program's write lock (up to ``lock_timeout_s``, then
    :class:`~eyelume.optimize.store.StoreLocked`). KeyboardInterrupt (Ctrl-C, or SIGTERM via the
    command line) and any error stop the workers at once; what is committed stays.
    """
    base = load_scene(study.scene)
    runs = plan_runs(study)
    keys = [run_key(base, r, study) for r in runs]
    store = ResultStore(out, lock_timeout_s)
    store.on_wait = note
    try:
        done = store.done()
        if done and not resume:
            raise StoreError(f"{out}: holds {len(done)} finished runs; use --resume or a new --out")
        others = store.studies() - {study.name}
        if others:
            raise StoreError(f"{out}: holds runs of another study ({', '.join(sorted(others))})")
        write_json(
            Path(out) / STUDY_FILE,
            {"study": study.name, "scene": base.name, "scene_file": study.scene,
             "seed": study.seed, "samples_per_pixel": study.samples_per_pixel,
             "delta": study.delta, "metrics": list(study.metrics),
             "population": None if study.population is None
             else study.population.model_dump(mode="json")},
        )  # fmt: skip
        todo = [(i, r, k) for i, (r, k) in enumerate(zip(runs, keys, strict=True)) if k not in done]
        finished = len(runs) - len(todo)
        if progress:
            progress(finished, len(runs))
        scene_json = base.model_dump(mode="json")
        study_json = study.model_dump(mode="json")

        def commit(tag: tuple[int, dict, str], result: tuple[dict, float]) -> None:
            nonlocal finished
            i, r, k = tag
            store.put(k, i, study.name, r, result[0], result[1])
            finished += 1
            if progress:
                progress(finished, len(runs))

        tasks = (((i, r, k), (scene_json, r, study_json)) for i, r, k in todo)
        run_tasks(_one, tasks, commit, workers, dask)
        return store.rows()
    finally:
        store.close()


#: Tasks in flight per worker (:func:`run_tasks`): enough that a worker never waits for the
#: parent's commit, few enough that the parent holds almost nothing per task.
TASKS_PER_WORKER = 2


def run_tasks(
    fn: Callable,
    tasks: Iterable[tuple[object, tuple]],
    commit: Callable[[object, object], None],
    workers: int | None = None,
    dask: str | None = None,
    window: int | None = None,
) -> None:
    """Run ``fn(*args)`` for each ``(tag, args)`` of ``tasks`` on worker processes and call
    ``commit(tag, result)`` in this process as each finishes (in the order they finish).

    ``fn`` must be a module-level function (it is pickled by name) and each task a pure
    function of its arguments. ``workers``: processes of the local pool, or of a Dask
    LocalCluster with ``dask="local"`` (default: every core); ``dask``: None for the local pool,
    ``"local"``, or a scheduler's address (its own workers). ``window``: most tasks in flight
    (default :data:`TASKS_PER_WORKER` per worker); ``tasks`` is read lazily, one task as another
    finishes. KeyboardInterrupt (Ctrl-C, SIGTERM via the command line), a worker dying, or an
    error in ``fn`` or ``commit`` stops every worker at once and is raised; what was committed
    stays."""
    workers = workers or os.cpu_count() or 1
    if dask is not None:
        _run_on_dask(dask, workers, fn, iter(tasks), commit, window)
    else:
        _run_on_pool(workers, fn, iter(tasks), commit, window or TASKS_PER_WORKER * workers)


def _submit_some(submit: Callable, tasks: Iterator, pending: dict, window: int) -> None:
    """Submit tasks from ``tasks`` until ``window`` are pending (or none is left)."""
    while len(pending) < window:
        try:
            tag, args = next(tasks)
        except StopIteration:
            return
        pending[submit(tag, args)] = tag


def _run_on_pool(workers, fn, tasks, commit, window) -> None:
    """The tasks on a local pool of ``spawn`` worker processes that end with this one; each
    result is committed as it arrives; an interrupt or error ends the workers at once."""
    ctx = mp.get_context("spawn")
    pool = ProcessPoolExecutor(
        workers, mp_context=ctx, initializer=_init_worker, initargs=(os.getpid(),)
    )
    try:
        pending: dict = {}

        def submit(tag, args):
            return pool.submit(_in_worker, fn, args)

        _submit_some(submit, tasks, pending, window)
        while pending:
            ready, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in ready:
                commit(pending.pop(fut), fut.result())
            _submit_some(submit, tasks, pending, window)
    except (KeyboardInterrupt, BrokenProcessPool):
        # Ctrl-C / SIGTERM (a worker hit by Ctrl-C breaks the pool): what is committed stays;
        # drop the queue and end the workers instead of waiting for them
        _end_pool(pool)
        raise KeyboardInterrupt from None
    except BaseException:
        _end_pool(pool)  # e.g. StoreLocked: compute nothing that cannot be kept
        raise
    pool.shutdown()


#: Seconds to reach a Dask scheduler (:func:`_connect`) before the address is refused; a
#: scheduler that is up answers in well under a second, even across a network.
DASK_CONNECT_TIMEOUT_S = 5.0


def _connect(client_cls, address: str):
    """A ``dask.distributed.Client`` of the scheduler at ``address``; OptionError naming
    ``--dask`` and the address when it is malformed or nothing answers there within
    :data:`DASK_CONNECT_TIMEOUT_S` (Dask's own default waits 30 s and more)."""
    try:
        return client_cls(address, timeout=DASK_CONNECT_TIMEOUT_S)
    except (OSError, ValueError, TypeError) as exc:  # TimeoutError is an OSError
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise OptionError(
            f"--dask {address}: no Dask scheduler reached there ({reason}); give 'local' or "
            "a running scheduler's address, e.g. tcp://host:8786"
        ) from None


def check_scheduler(address: str | None) -> None:
    """Refuse a ``dask`` scheduler address that is malformed or where nothing answers, before
    any work (:func:`_connect`; OptionError); None and "local" need no check."""
    if address is None or address == "local":
        return
    from dask.distributed import Client

    _connect(Client, address).close()


def _run_on_dask(address, workers, fn, tasks, commit, window) -> None:
    """The same tasks on a Dask cluster: a new LocalCluster for "local", else the scheduler at
    ``address``; each result is committed by this process as it arrives."""
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if address == "local":
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        client = _connect(Client, address)
    try:
        client.run(_init_worker)
        if window is None:
            window = TASKS_PER_WORKER * max(1, sum(client.nthreads().values()))
        pending: dict = {}

        def submit(tag, args):
            return client.submit(_in_worker, fn, args, pure=False)  # a random key each

        _submit_some(submit, tasks, pending, window)
        done = as_completed(list(pending))
        for fut in done:
            commit(pending.pop(fut), fut.result())
            before = set(pending)
            _submit_some(submit, tasks, pending, window)
            for new in set(pending) - before:
                done.add(new)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
