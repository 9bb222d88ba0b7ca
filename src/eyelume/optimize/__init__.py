"""Optimisation: LED sweeps and refinement (the paper's generator), studies and their executors."""

from eyelume.optimize.sweep import SweepResult, refine, sweep_leds

__all__ = ["SweepResult", "refine", "sweep_leds"]
