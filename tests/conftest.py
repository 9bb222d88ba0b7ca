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

#: Session fixtures too costly to build once per pytest-xdist worker (the 80 M-ray render is
#: ~40 s of one core): their tests, and every test of a module that shares a module fixture with
#: them, run on one worker.
COSTLY_SESSION_FIXTURES = frozenset({"fig6b_render"})


def _shared_fixture_keys(item) -> list[str]:
    """What a test shares with others: ``module:<file>`` for a module-, class- or package-scoped
    fixture, ``session:<name>`` for one of :data:`COSTLY_SESSION_FIXTURES`."""
    keys = []
    info = getattr(item, "_fixtureinfo", None)  # doctests of src/ have none
    for name, defs in (info.name2fixturedefs if info else {}).items():
        scope = defs[-1].scope
        if scope in ("module", "class", "package"):
            keys.append(f"module:{item.nodeid.split('::')[0]}")
        elif scope == "session" and name in COSTLY_SESSION_FIXTURES:
            keys.append(f"session:{name}")
    return keys


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under ``pytest -n N --dist loadgroup`` (the README's test command), keep together on one
    worker the tests that share a costly fixture, so that it is built once, as in a serial run:
    a module's tests that use a module- (or class-, package-) scoped fixture, and the tests of
    :data:`COSTLY_SESSION_FIXTURES`; modules linked by such a fixture form one group. Other tests
    are dealt out one by one. Without xdist the ``xdist_group`` marks are inert."""
    if not config.pluginmanager.hasplugin("xdist"):  # the mark is xdist's (--strict-markers)
        return
    parent: dict[str, str] = {}

    def find(k: str) -> str:
        while parent.setdefault(k, k) != k:
            k = parent[k]
        return k

    keys_of = {}
    for item in items:
        keys = _shared_fixture_keys(item)
        for k in keys[1:]:
            parent[find(k)] = find(keys[0])
        keys_of[item] = keys
    for item, keys in keys_of.items():
        if keys and not any(m.name == "xdist_group" for m in item.iter_markers()):
            item.add_marker(pytest.mark.xdist_group(find(keys[0]).split(":", 1)[1]))


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
