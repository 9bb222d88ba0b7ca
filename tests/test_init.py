"""The package facade: public names load lazily; the Numba cache stays out of src/ and a user
whose home is not writable can still run eyelume (``--help`` always works)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import eyelume

SRC = Path(__file__).resolve().parents[1] / "src"


def _env(tmp_path: Path, **extra: str) -> dict[str, str]:
    """A user whose home cannot be written: HOME lies under a regular file, so nothing can be
    created there even by root (permission bits do not stop root)."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("", encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(HOME=str(blocker / "home"), PYTHONPATH=str(SRC), **extra)
    return env


def test_help_works_when_home_is_not_writable(tmp_path):
    env = _env(tmp_path)
    out = subprocess.run(
        [sys.executable, "-c", "from eyelume.cli import app; app()", "--help"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert "render" in out.stdout and "Traceback" not in out.stderr


def test_kernels_cache_in_temp_when_home_is_not_writable(tmp_path):
    """The cache falls back to a per-user folder in the temporary directory, never src/."""
    env = _env(tmp_path, TMPDIR=str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    code = (
        "import os, eyelume\n"
        "from eyelume.kernels.rng import stream_start\n"
        "stream_start(1, 2)\n"
        "print(os.environ['NUMBA_CACHE_DIR'])\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr
    cache = Path(out.stdout.strip())
    assert cache.is_relative_to(tmp_path / "tmp") and cache.name.startswith("numba-py")
    assert any(cache.rglob("*.nbi")), "the kernel was not cached there"


def test_runs_uncached_with_one_note_when_nothing_is_writable(tmp_path):
    """Home and the temporary directory both unwritable: the kernels compile uncached, and one
    line on stderr says so."""
    env = _env(tmp_path)
    code = (
        "import tempfile; tempfile.gettempdir = lambda: " + repr(env["HOME"]) + "\n"
        "import eyelume\n"
        "from eyelume.kernels.rng import stream_start\n"
        "print(stream_start(1, 2))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr
    notes = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(notes) == 1 and "NUMBA_CACHE_DIR" in notes[0], out.stderr


def _keep_numba_config(monkeypatch) -> None:
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored after


def test_a_set_cache_dir_is_kept(tmp_path, monkeypatch):
    _keep_numba_config(monkeypatch)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert eyelume._numba_cache_dir() == tmp_path / "mine"


def test_first_writable_candidate_wins(tmp_path, monkeypatch):
    _keep_numba_config(monkeypatch)
    monkeypatch.setenv("NUMBA_CACHE_DIR", "")  # restored after
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    blocker = tmp_path / "file"
    blocker.write_text("", encoding="utf-8")
    chosen = eyelume._numba_cache_dir([blocker / "a", tmp_path / "b"])
    assert chosen == tmp_path / "b" and os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "b")


def test_public_names_load_lazily():
    code = (
        "import sys, eyelume\n"
        "assert not any(m.startswith('eyelume.estimators') for m in sys.modules)\n"
        "assert eyelume.load_scene('paper2005').leds.count == 4\n"
        "assert callable(eyelume.render) and 'eyelume.estimators.fast_run' in sys.modules\n"
    )
    env = dict(os.environ, PYTHONPATH=str(SRC))
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=600)
    assert set(eyelume.__all__) <= set(dir(eyelume))


def test_kernel_cache_is_named_by_the_sources(tmp_path):
    """A change to any module (a kernel another file inlines) gives a new cache directory, so
    no stale compiled kernel is reused (Numba keys a cache on the kernel's own file only)."""
    import shutil

    src = Path(eyelume.__file__).parent
    copy = tmp_path / "eyelume"
    shutil.copytree(src, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = eyelume._sources_digest(copy)
    assert before == eyelume._sources_digest(src)
    seq = copy / "kernels" / "sequential.py"
    seq.write_text(seq.read_text(encoding="utf-8") + "\n# changed\n", encoding="utf-8")
    assert eyelume._sources_digest(copy) != before
    assert all(before in c.name for c in eyelume._numba_cache_candidates())
