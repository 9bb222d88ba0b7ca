"""run_unit: a unit of work that a signal arrived during is cancelled whole — also when the
unit, handed a partial render, then fails (evaluate-tracking under SIGTERM: digitize refused
the unfinished NaN pixels with a ValueError traceback instead of the interrupted run's
partial output and exit 143)."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from eyelume.estimators.interrupt import interrupt_between_batches, run_unit


def _render_then_digitize():
    """A render that takes SIGTERM as a request to stop (its rows left NaN), then a step
    that refuses NaN, as the sensor does."""
    with interrupt_between_batches() as flag:
        os.kill(os.getpid(), signal.SIGTERM)
        assert flag.requested
        image = np.full(4, np.nan)
    if np.isnan(image).any():
        raise ValueError("irradiance has 4 NaN or infinite value(s) out of 4")
    return image


def test_an_error_after_a_signal_is_the_interruption():
    with pytest.raises(KeyboardInterrupt):
        run_unit(_render_then_digitize)


def test_an_error_without_a_signal_stays_the_error():
    def fails():
        raise ValueError("a real error")

    with pytest.raises(ValueError, match="a real error"):
        run_unit(fails)


def test_a_unit_without_a_signal_returns_its_value():
    assert run_unit(lambda x: 2 * x, 21) == 42
