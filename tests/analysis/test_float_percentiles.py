"""pupil.float_percentiles: np.percentile's floats to the bit (float32 and float64 arrays, a
float q in the array's precision, a list in float64), without its overhead."""

import numpy as np
import pytest

from eyelume.analysis.tracking.pupil import float_percentiles


def test_float_percentiles_are_numpys():
    rng = np.random.default_rng(4)
    for t in range(600):
        n = int(rng.integers(1, 2000))
        v = rng.normal(50.0, 10.0, n) if t % 2 else rng.integers(0, 255, n) / 7.0
        v = v.astype(np.float32 if t % 3 else np.float64)
        if t % 5 == 0:
            v = np.round(v)  # ties between order statistics
        for q in (0.0, 1.0, 5.0, 50.0, 95.0, 99.0, 100.0, [95.0, 99.0], (1.0, 50.0, 100.0)):
            want = np.percentile(v, q)
            want = float(want) if np.ndim(want) == 0 else [float(x) for x in want]
            assert float_percentiles(v, q) == want


def test_float_percentiles_refuses_what_it_does_not_mimic():
    with pytest.raises(ValueError, match="float array"):
        float_percentiles(np.arange(5), 50.0)
    with pytest.raises(ValueError, match="float array"):
        float_percentiles(np.zeros(0, np.float32), 50.0)
