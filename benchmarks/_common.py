"""Shared helpers for the benchmark scripts: machine description, timing, results files.

Not a package module: the scripts put ``benchmarks/`` on ``sys.path`` themselves (it is the
script's directory when run as ``python benchmarks/<name>.py``).
"""

from __future__ import annotations

import json
import os
import platform
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
RESULTS = HERE / "results"


def _warm_cache() -> Path:
    """Numba cache for the warm measurements, kept outside ``src/`` (``cache=True`` would
    otherwise write index files beside the sources) and reused between runs of the scripts;
    named by the sources (``eyelume._sources_digest``: Numba would otherwise reuse a kernel
    compiled against an older version of a file it inlines)."""
    from eyelume import _sources_digest

    digest = _sources_digest(REPO / "src" / "eyelume")
    return Path(tempfile.gettempdir()) / f"eyelume-bench-numba-cache-{digest}"


WARM_CACHE = _warm_cache()


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def cpu_mhz() -> float | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("cpu MHz"):
                return float(line.split(":", 1)[1])
    except (OSError, ValueError):
        pass
    return None


def loadavg() -> list[float]:
    try:
        return [float(v) for v in Path("/proc/loadavg").read_text().split()[:3]]
    except OSError:
        return []


def git_state() -> dict:
    """Commit and whether ``src/`` differs from it (others edit the sources concurrently)."""

    def run(*args: str) -> str:
        try:
            return subprocess.run(
                ["git", *args], cwd=REPO, capture_output=True, text=True, timeout=10
            ).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""

    return {
        "commit": run("rev-parse", "--short", "HEAD"),
        "src_dirty": bool(run("status", "--porcelain", "--", "src")),
    }


def machine() -> dict:
    """Everything that says where and with what a figure was measured."""
    import numba
    import numpy

    return {
        "nproc": os.cpu_count(),
        "nproc_cmd": subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip(),
        "cpu_model": cpu_model(),
        "cpu_mhz": cpu_mhz(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "numba": numba.__version__,
        "NUMBA_NUM_THREADS": os.environ.get(
            "NUMBA_NUM_THREADS", f"unset ({numba.config.NUMBA_NUM_THREADS})"
        ),
        "numba_threading_layer_config": numba.config.THREADING_LAYER,
        "loadavg_at_start": loadavg(),
        **git_state(),
    }


def command_line() -> str:
    return " ".join(shlex.quote(a) for a in [Path(sys.executable).name, *sys.argv])


def print_header(title: str, info: dict) -> None:
    print(f"== {title}")
    print(f"   command : {command_line()}   (cwd {os.getcwd()})")
    print(
        f"   machine : nproc={info['nproc_cmd']}  CPU={info['cpu_model']}"
        f"  ({info['cpu_mhz']} MHz)  loadavg={info['loadavg_at_start']}"
    )
    print(
        f"   software: Python {info['python']}  NumPy {info['numpy']}  Numba {info['numba']}"
        f"  NUMBA_NUM_THREADS={info['NUMBA_NUM_THREADS']}"
    )
    print(f"   source  : commit {info['commit']}  src dirty={info['src_dirty']}")


def cpu_ticks() -> tuple[int, int] | None:
    """System-wide (busy, steal) clock ticks from /proc/stat; busy = user+nice+system+(soft)irq."""
    try:
        f = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    except (OSError, ValueError):
        return None
    return f[0] + f[1] + f[2] + f[5] + f[6], f[7] if len(f) > 7 else 0


def timed(fn: Callable[[], object], repeats: int, threads: int = 1) -> dict:
    """Run ``fn`` ``repeats`` times; best, median, spread of wall time, and disturbance per repeat.

    ``cpu_util`` = process CPU time / (wall time × threads): near 1 when the run had its cores to
    itself, well below 1 when something else took them. ``others_cpu_s`` = CPU seconds the rest of
    the machine used meanwhile (system-wide busy ticks − this process, 10 ms resolution) and
    ``steal_s`` the time the hypervisor took from this VM: both near 0 for a clean repeat.
    """
    hz = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    walls, utils, others, steals, out = [], [], [], [], None
    for _ in range(repeats):
        k0 = cpu_ticks()
        c0, t0 = time.process_time(), time.perf_counter()
        out = fn()
        t1, c1 = time.perf_counter(), time.process_time()
        k1 = cpu_ticks()
        walls.append(t1 - t0)
        utils.append((c1 - c0) / ((t1 - t0) * threads))
        if k0 and k1:
            others.append(max(0.0, (k1[0] - k0[0]) / hz - (c1 - c0)))
            steals.append((k1[1] - k0[1]) / hz)
    return {
        "best_s": min(walls),
        "median_s": statistics.median(walls),
        "worst_s": max(walls),
        "spread_pct": 100.0 * (max(walls) - min(walls)) / min(walls),
        "walls_s": [round(w, 6) for w in walls],
        "cpu_util": [round(u, 3) for u in utils],
        "others_cpu_s": [round(v, 2) for v in others],
        "steal_s": [round(v, 2) for v in steals],
        "last": out,
    }


def disturbed(t: dict) -> str:
    """A warning for a timing whose repeats shared the machine, else ''."""
    flags = []
    if min(t["cpu_util"]) < 0.9:
        flags.append("cpu_util < 0.9")
    if t.get("others_cpu_s") and max(t["others_cpu_s"]) > 0.05 * t["worst_s"] + 0.02:
        flags.append(f"other processes used {max(t['others_cpu_s']):.2f} CPU-s")
    if t.get("steal_s") and max(t["steal_s"]) > 0.02:
        flags.append(f"steal {max(t['steal_s']):.2f} s")
    return f"  (DISTURBED? {'; '.join(flags)})" if flags else ""


def append_result(name: str, record: dict) -> Path:
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.jsonl"
    record = {"time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **record}
    with path.open("a") as fh:
        fh.write(json.dumps(record, default=_jsonable) + "\n")
    return path


def _jsonable(obj):
    try:
        import numpy

        if isinstance(obj, numpy.generic):
            return obj.item()
        if isinstance(obj, numpy.ndarray):
            return obj.tolist()
    except ImportError:
        pass
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj)}")


def fmt_rate(x: float) -> str:
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(x) >= scale:
            return f"{x / scale:.3g} {unit}"
    return f"{x:.3g} "


def parse_sets(sets: list[str], option: str = "--set") -> dict:
    """``key=value`` options as scene overrides (a JSON value where it parses as one, else the
    text); one line naming the option and exit 2 for an item without ``=``."""
    out = {}
    for item in sets:
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            print(f"{option} {item!r}: must be key=value (a scene field's dotted path)",
                  file=sys.stderr)  # fmt: skip
            sys.exit(2)
        try:
            out[key.strip()] = json.loads(value)
        except ValueError:
            out[key.strip()] = value
    return out
