"""eyelume: near-infrared illumination design for eye trackers in head-mounted displays.

>>> import eyelume
>>> scene = eyelume.load_scene("paper2005")
>>> scene.leds.count
4

The public names are loaded on first use (PEP 562), so importing a low layer of the package, or
running ``eyelume --help``, does not load the estimators. Before anything imports Numba, the
Numba cache is pointed out of the source tree (:func:`_numba_cache_dir`).
"""

from __future__ import annotations

import importlib
import os
import sys
import tempfile
import types
from pathlib import Path

__all__ = [
    "EyelumeError",
    "RenderOptions",
    "RenderResult",
    "SceneError",
    "apply_overrides",
    "load_scene",
    "render",
    "save_scene",
]
__version__ = "0.1.0"

_HOMES = {
    "EyelumeError": "eyelume.errors",
    "SceneError": "eyelume.errors",
    "RenderOptions": "eyelume.render",
    "RenderResult": "eyelume.render",
    "render": "eyelume.render",
    "apply_overrides": "eyelume.scene.io",
    "load_scene": "eyelume.scene.io",
    "save_scene": "eyelume.scene.io",
}


class _Facade(types.ModuleType):
    """The package module. Importing the submodule ``eyelume.render`` binds it as an attribute
    of the package; ``eyelume.render`` stays the function :func:`eyelume.render.render`, as it
    was when the package imported it eagerly."""

    def __setattr__(self, name: str, value) -> None:
        if name == "render" and isinstance(value, types.ModuleType):
            value = value.render
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Facade


def __getattr__(name: str):
    if name in _HOMES:
        value = getattr(importlib.import_module(_HOMES[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'eyelume' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])


def _writable_dir(path: Path) -> bool:
    """Whether ``path`` exists or can be made, and a file can be created in it."""
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=path, prefix=".probe-")
        os.close(fd)
        os.unlink(probe)
        return True
    except OSError:
        return False


def _sources_digest(root: Path | None = None) -> str:
    """A digest of every module of the package under ``root`` (default: this package): its
    ``.py`` files' paths and bytes.

    Numba keys a cached kernel on its own file's timestamp only: a kernel that inlines a
    function from another file (every estimator inlines the kernels') is not recompiled when
    only that other file changes, and would run stale code. The cache directory is therefore
    named by the sources as a whole (hashing them takes about a millisecond)."""
    import hashlib

    root = root or Path(__file__).parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _numba_cache_candidates() -> list[Path]:
    """Where the compiled kernels may be cached, best first: the user's cache directory
    (``$XDG_CACHE_HOME`` or ``~/.cache``), then the system's temporary directory; named by the
    Python version and :func:`_sources_digest`."""
    tag = f"numba-py{sys.version_info.major}{sys.version_info.minor}-{_sources_digest()}"
    out = []
    xdg = os.environ.get("XDG_CACHE_HOME")
    home = os.path.expanduser("~")
    if xdg:
        out.append(Path(xdg) / "eyelume" / tag)
    if home and home != "~":
        out.append(Path(home) / ".cache" / "eyelume" / tag)
    user = getattr(os, "getuid", lambda: "user")()
    out.append(Path(tempfile.gettempdir()) / f"eyelume-{user}" / tag)
    return out


def _numba_cache_dir(candidates: list[Path] | None = None) -> Path | None:
    """Point Numba's cache (``NUMBA_CACHE_DIR``) at a per-user directory out of ``src/``.

    A ``NUMBA_CACHE_DIR`` already set is kept. Otherwise the first writable directory of
    :func:`_numba_cache_candidates`; if none is writable (installed by one user and run by
    another whose home and temporary directory are read-only) the kernels run uncached, with a
    one-line note on stderr, rather than failing on import. Returns the directory, or None.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    for path in _numba_cache_candidates() if candidates is None else candidates:
        if _writable_dir(path):
            os.environ["NUMBA_CACHE_DIR"] = str(path)
            if "numba" in sys.modules:  # imported before eyelume: its config is already read
                sys.modules["numba"].config.CACHE_DIR = str(path)
            return path
    _run_uncached()
    return None


def _run_uncached() -> None:
    """Compile the kernels on every run: ``cache=True`` is ignored (no cache file is read or
    written), so no directory needs to be writable."""
    from numba.core.dispatcher import Dispatcher

    Dispatcher.enable_caching = lambda self: None
    sys.stderr.write(
        "eyelume: no writable cache directory (home, XDG_CACHE_HOME, temp): the Numba kernels "
        "compile on every run; set NUMBA_CACHE_DIR to a writable folder to cache them\n"
    )


_numba_cache_dir()
