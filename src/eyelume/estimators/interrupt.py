"""Ctrl-C (SIGINT) and SIGTERM as a request: finish the chunk of work in flight, keep what is
done.

The first signal sets ``requested`` (and ``signum``, so a command can exit with 128 + signum:
130 after Ctrl-C, 143 after SIGTERM); a second one raises KeyboardInterrupt at once.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["interrupt_between_batches", "last_signal", "sigterm_as_interrupt"]

_last: list[int | None] = [None]


def last_signal() -> int | None:
    """The signal (SIGINT or SIGTERM) that last asked a run in this process to stop, or None."""
    return _last[0]


class _StopFlag:
    requested = False
    signum: int | None = None


@contextmanager
def interrupt_between_batches():
    """Turn the first SIGINT or SIGTERM into a request to stop after the current batch."""
    flag = _StopFlag()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def handler(signum, frame):
        if flag.requested:
            raise KeyboardInterrupt
        flag.requested = True
        flag.signum = _last[0] = signum

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield flag
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def sigterm_as_interrupt() -> None:
    """Make SIGTERM act as Ctrl-C in this process (KeyboardInterrupt, recorded by
    :func:`last_signal`), so a terminated command cleans up as an interrupted one does: it
    keeps what is finished, ends its workers and exits 143 instead of dying mid-write."""
    if threading.current_thread() is not threading.main_thread():
        return

    def handler(signum, frame):
        _last[0] = signum
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, handler)
