"""Shared fixtures: the default scene and seeded renders reused across test modules."""

from __future__ import annotations

import pytest

import eyelume
from eyelume.compile import compile_scene

#: Rays for the full default-scene render the image tests share. At 40 M rays a skin pixel
#: collects ~5 rays and each glint ~100, enough for the region tests' 4σ margins.
FIG6B_RAYS = 40_000_000


@pytest.fixture(scope="session")
def paper_scene():
    return eyelume.load_scene("paper2005")


@pytest.fixture(scope="session")
def paper_compiled(paper_scene):
    return compile_scene(paper_scene)


@pytest.fixture(scope="session")
def fig6b_render(paper_compiled):
    return eyelume.render(paper_compiled, rays=FIG6B_RAYS, seed=2005)
