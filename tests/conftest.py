"""Shared fixtures: a seeded random generator, the default scene and seeded renders reused
across test modules."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene

#: Rays for the full default-scene render the image tests share. At 80 M rays a skin pixel
#: collects ~10 rays and each glint ~110 over its ~3 px blur disc: the glints' top-hat
#: contrast (~12 ± 1.3) then clears the largest skin-noise spot (~3.7σ of a 3 × 3 mean of ~10
#: counts above a ~7 background: ~7) by ~4σ.
FIG6B_RAYS = 80_000_000


@pytest.fixture
def rng(request) -> np.random.Generator:
    """A NumPy generator seeded from the test's name (after Mitsuba's ``src/conftest.py``): each
    test draws its own numbers, the same on every run and whatever runs before it."""
    return np.random.default_rng(zlib.crc32(request.node.name.encode("utf-8")))


@pytest.fixture(scope="session")
def paper_scene():
    return eyelume.load_scene("paper2005")


@pytest.fixture(scope="session")
def paper_compiled(paper_scene):
    return compile_scene(paper_scene)


@pytest.fixture(scope="session")
def fig6b_render(paper_compiled):
    return eyelume.render(paper_compiled, eyelume.RenderOptions(rays=FIG6B_RAYS, seed=2005))
