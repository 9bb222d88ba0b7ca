"""Ctrl-C as a request: finish the batch in flight, keep what is done."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["interrupt_between_batches"]


class _StopFlag:
    requested = False


@contextmanager
def interrupt_between_batches():
    """Turn the first SIGINT into a request to stop after the current batch."""
    flag = _StopFlag()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def handler(signum, frame):
        if flag.requested:
            raise KeyboardInterrupt
        flag.requested = True

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)
