"""Ctrl-C (SIGINT) and SIGTERM as a request: finish the chunk of work in flight, keep what is
done.

The first signal sets ``requested`` (and ``signum``, so a command can exit with 128 + signum:
130 after Ctrl-C, 143 after SIGTERM); a second one raises KeyboardInterrupt at once.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = [
    "PartialRun",
    "interrupt_between_batches",
    "last_signal",
    "run_unit",
    "sigterm_as_interrupt",
]

_last: list[int | None] = [None]
_count = [0]  # SIGINT/SIGTERM received in this process by the handlers below


class PartialRun(KeyboardInterrupt):
    """A run of units of work (δ values, gazes, placements) stopped by Ctrl-C or SIGTERM.

    ``done`` holds what finished (whole units only; the unit in flight is dropped), ``total``
    the planned number of units, ``what`` names them ("δ values", "test gazes", …). A caller
    that does not catch it sees the KeyboardInterrupt it is."""

    def __init__(self, done, count: int, total: int, what: str) -> None:
        super().__init__(f"interrupted after {count} of {total} {what}")
        self.done, self.count, self.total, self.what = done, count, total, what


def run_unit(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` as one unit of work that Ctrl-C or SIGTERM cancels whole:
    KeyboardInterrupt if a signal arrived while it ran — also one that a render inside took as
    a request to stop early (:func:`interrupt_between_batches`), whose result is then partial
    and must not be used as a whole unit's. An error raised by the unit after such a signal is
    that partial result's consequence (``evaluate-tracking`` stopped by SIGTERM mid-render: the
    sensor refused the irradiance's unfinished NaN pixels with a ValueError and a traceback)
    and is KeyboardInterrupt too."""
    mark = _count[0]
    try:
        value = fn(*args, **kwargs)
    except Exception:
        if _count[0] != mark:
            raise KeyboardInterrupt from None
        raise
    if _count[0] != mark:
        raise KeyboardInterrupt
    return value


def last_signal() -> int | None:
    """The signal (SIGINT or SIGTERM) that last asked a run in this process to stop, or None."""
    return _last[0]


class _StopFlag:
    requested = False
    signum: int | None = None


@contextmanager
def _flagged(raise_first: bool):
    """SIGINT and SIGTERM recorded on the yielded :class:`_StopFlag` (and :func:`last_signal`)
    while the block runs, the previous handlers restored after it; KeyboardInterrupt on the
    first signal with ``raise_first``, else on the second only. Off the main thread (where no
    handler can be set) the flag is yielded and never set."""
    flag = _StopFlag()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def handler(signum, frame):
        _count[0] += 1
        if flag.requested and not raise_first:
            raise KeyboardInterrupt
        flag.requested = True
        flag.signum = _last[0] = signum
        if raise_first:
            raise KeyboardInterrupt

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield flag
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def interrupt_between_batches():
    """Turn the first SIGINT or SIGTERM into a request to stop after the current batch (a
    context manager yielding the flag; the second signal raises KeyboardInterrupt)."""
    return _flagged(raise_first=False)


def signal_seen():
    """SIGINT and SIGTERM raise KeyboardInterrupt as usual and are recorded on the yielded
    flag (``requested``, ``signum``; :func:`last_signal` too), so that code whose library turns
    a KeyboardInterrupt into another error (Numba's compiler: "no compiled object yet" after
    Ctrl-C inside an LLVM callback) can tell an interrupted call from a failed one."""
    return _flagged(raise_first=True)


def sigterm_as_interrupt() -> None:
    """Make SIGTERM act as Ctrl-C in this process (KeyboardInterrupt, recorded by
    :func:`last_signal`), so a terminated command cleans up as an interrupted one does: it
    keeps what is finished, ends its workers and exits 143 instead of dying mid-write.
    Called as a command starts, it forgets the signal an earlier command in the same process
    took (a test runner's, or an API user's loop): a later Ctrl-C exits 130, not 143."""
    _last[0] = None
    if threading.current_thread() is not threading.main_thread():
        return

    def handler(signum, frame):
        _count[0] += 1
        _last[0] = signum
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, handler)
