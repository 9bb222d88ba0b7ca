"""Optimisation: LED sweeps and refinement (the paper's generator), studies and their executors.

The names below load on first use, so reading a study's store (:mod:`.store`) does not load the
estimators.
"""

from __future__ import annotations

import importlib

__all__ = ["SweepResult", "refine", "sweep_leds"]


def __getattr__(name: str):
    if name in __all__:
        return getattr(importlib.import_module("eyelume.optimize.sweep"), name)
    raise AttributeError(f"module 'eyelume.optimize' has no attribute {name!r}")
