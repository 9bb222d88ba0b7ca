"""A rel_error run that stops below the least fixed budget keeps that budget's light paths.

The glints are formed by the light paths alone (LEDs are points: a camera path never meets
one), and the stopping rule looks at the skin, so without a floor a run stopping at 2 samples
per pixel traced a quarter of the light paths of the least fixed render (8 samples per pixel),
and a dataset picture (issue 17) had two visible glints with no light at all.
"""

import numpy as np
import pytest

from eyelume.analysis.regions import region_masks
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene
from eyelume.estimators.fast_run import PILOT_ABOVE, planned_sets, trace_fast
from eyelume.scene.io import load_scene


@pytest.mark.slow
def test_a_run_stopping_at_few_samples_keeps_the_light_paths_of_eight():
    sc = load_scene("vr-offaxis")
    cs = compile_scene(sc)
    pixels = sc.sensor.cols * sc.sensor.rows
    assert pixels > PILOT_ABOVE  # the pilot may choose fewer than 8 samples per pixel
    least = int(np.prod(planned_sets(1)))
    light = int(round(sc.run.light_paths_per_pixel * pixels * least / 16))
    skin = region_masks(cs)["skin"]
    est = trace_fast(cs, least, light, 1, rel_error=0.2, target_pixels=skin)
    assert est.samples_per_pixel < least  # the loose target stops early ...
    assert est.light_paths == light  # ... with the light paths of the 8-sample budget
    visible = [g["led"] for g in eye_truth(cs)["glints"] if g["visible"]]
    assert visible
    flux = est.glint_images.sum(axis=(1, 2))
    assert all(flux[k] > 0 for k in visible), flux
