"""People (issue 15 part 2): sampled moments against the stated distributions, the same
people whatever the chunking, order or thread, each sample applied to its scene, and bad
population input as one line naming the field (exit 2 through the CLI)."""

from __future__ import annotations

import math
import tomllib
from concurrent.futures import ThreadPoolExecutor
from importlib import resources

import numpy as np
import pytest
from scipy import stats
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.errors import SceneError
from eyelume.optimize.study import load_study
from eyelume.scene.io import load_scene
from eyelume.scene.population import (
    AMBIENT_LEVELS,
    PARAMETERS,
    Population,
    parse_population,
    resolved_distributions,
    sample_people,
    watson_yellott_pupil_mm,
)

N = 10_000


@pytest.fixture(scope="module")
def scene():
    return load_scene("vr-offaxis")


@pytest.fixture(scope="module")
def big(scene):
    return sample_people(scene, N, 2026, build_scenes=False)


def _file():
    path = resources.files("eyelume.scene.presets.eyes") / "population.toml"
    return tomllib.loads(path.read_text(encoding="utf-8"))


def _reference(d):
    """The distribution as scipy states it (an independent implementation)."""
    if d.kind == "uniform":
        return stats.uniform(loc=d.low, scale=d.high - d.low)
    a, b = (d.low - d.mean) / d.sd, (d.high - d.mean) / d.sd
    return stats.truncnorm(a, b, loc=d.mean, scale=d.sd)


@pytest.mark.parametrize("name", PARAMETERS)
def test_sampled_moments_match_the_distribution(big, scene, name):
    d = resolved_distributions(scene, Population())[name]
    ref = _reference(d)
    mean, var, kurt = (float(x) for x in ref.stats(moments="mvk"))
    sd = math.sqrt(var)
    x = np.array([p.values[name] for p in big])
    assert x.min() >= d.low and x.max() <= d.high
    # standard errors of the sample mean and sample SD (the latter from the fourth moment:
    # Var(s²) ≈ (μ₄ − σ⁴)/n, μ₄ = (kurt + 3) σ⁴, delta method for s)
    se_mean = sd / math.sqrt(N)
    se_sd = math.sqrt((kurt + 2.0) * sd**4 / N) / (2.0 * sd)
    assert abs(x.mean() - mean) < 4 * se_mean, (name, x.mean(), mean)
    assert abs(x.std(ddof=1) - sd) < 4 * se_sd, (name, x.std(ddof=1), sd)


@pytest.mark.parametrize("name", PARAMETERS)
def test_truncated_moments_closed_form(scene, name):
    for ambient in AMBIENT_LEVELS:
        d = resolved_distributions(scene, Population(ambient=ambient))[name]
        mean, var = (float(v) for v in _reference(d).stats(moments="mv"))
        assert d.moments() == pytest.approx((mean, math.sqrt(var)), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("name", PARAMETERS)
def test_truncation_keeps_the_stated_mean_and_sd(scene, name):
    """The file's mean and SD are what a person draws: the bounds cut < 1 % of either (the
    pupil's at the dim level, where its bounds lie far from Watson & Yellott's mean)."""
    entry = _file()[name]
    d = resolved_distributions(scene, Population(ambient="dim"))[name]
    if entry["distribution"] != "normal":
        return
    mean, var = (float(v) for v in _reference(d).stats(moments="mv"))
    stated_mean = d.mean  # the pupil's from Watson & Yellott, the others the file's
    if entry["mean"] != "watson_yellott_2012":
        assert stated_mean == entry["mean"]
    assert abs(mean - stated_mean) < 0.01 * entry["sd"]
    assert abs(math.sqrt(var) - entry["sd"]) < 0.01 * entry["sd"]


def test_issue_values(scene):
    d = resolved_distributions(scene, Population())
    assert (d["corneal_radius_mm"].mean, d["corneal_radius_mm"].sd) == (7.8, 0.25)
    assert (d["corneal_asphericity_q"].mean, d["corneal_asphericity_q"].sd) == (-0.25, 0.15)
    assert (d["kappa_horizontal_deg"].mean, d["kappa_horizontal_deg"].sd) == (5.0, 2.0)
    assert (d["iris_reflectance"].low, d["iris_reflectance"].high) == (0.03, 0.07)
    # skin: Cooksey et al.'s range at the scene's wavelength
    at = {
        w: resolved_distributions(scene.model_copy(update={"wavelength_nm": w}), Population())
        for w in (853.0, 940.0, 896.5)
    }
    assert (at[853.0]["skin_reflectance"].low, at[853.0]["skin_reflectance"].high) == (0.49, 0.66)
    assert (at[940.0]["skin_reflectance"].low, at[940.0]["skin_reflectance"].high) == (0.47, 0.58)
    assert at[896.5]["skin_reflectance"].low == pytest.approx(0.48)
    assert at[896.5]["skin_reflectance"].high == pytest.approx(0.62)
    for name in PARAMETERS:
        assert _file()[name]["source"]


def test_watson_yellott_formula():
    # Stanley & Davies at F = 846 cd/m²·deg²: (F/846)^0.41 = 1, D = 7.75 − 5.75/3
    d846 = math.sqrt(846.0 / math.pi) * 2.0  # the field diameter whose area is 846 deg²
    assert watson_yellott_pupil_mm(1.0, d846) == pytest.approx(7.75 - 5.75 / 3.0, abs=1e-12)
    assert watson_yellott_pupil_mm(0.0) == pytest.approx(7.75)
    # one eye adapted: a tenth of the flux
    assert watson_yellott_pupil_mm(10.0, 30.0, eyes=1) == pytest.approx(
        watson_yellott_pupil_mm(1.0, 30.0)
    )
    # the age term: +40 years at D_SD
    dsd = watson_yellott_pupil_mm(100.0, 60.0)
    assert watson_yellott_pupil_mm(100.0, 60.0, 68.58) == pytest.approx(
        dsd + 40.0 * (0.02132 - 0.009562 * dsd)
    )
    # brighter → smaller, and the named levels drive the distribution's mean
    levels = sorted(AMBIENT_LEVELS.values())
    sizes = [watson_yellott_pupil_mm(v) for v in levels]
    assert sizes == sorted(sizes, reverse=True)
    sc = load_scene("vr-offaxis")
    for name, lum in AMBIENT_LEVELS.items():
        d = resolved_distributions(sc, Population(ambient=name))["pupil_diameter_mm"]
        assert d.mean == pytest.approx(watson_yellott_pupil_mm(lum, 100.0))
    with pytest.raises(ValueError, match="luminance"):
        watson_yellott_pupil_mm(-1.0)


def _same(a, b):
    return [(p.index, p.values, p.overrides) for p in a] == [
        (p.index, p.values, p.overrides) for p in b
    ]


def test_same_seed_same_people_in_any_chunking_order_or_thread(scene):
    whole = sample_people(scene, 30, 7)
    chunks = [sample_people(scene, 10, 7, start=s) for s in (20, 0, 10)]  # out of order
    assert _same(whole, chunks[1] + chunks[2] + chunks[0])
    with ThreadPoolExecutor(3) as ex:
        threaded = list(ex.map(lambda s: sample_people(scene, 1, 7, start=s), range(29, -1, -1)))
    assert _same(whole, [p for c in reversed(threaded) for p in c])
    assert _same(whole[:5], sample_people(scene, 5, 7))  # a smaller draw: the same first people
    assert not _same(whole, sample_people(scene, 30, 8))
    assert [p.scene for p in whole] == [p.scene for p in sample_people(scene, 30, 7)]


def test_a_value_does_not_depend_on_the_other_parameters(scene):
    every = sample_people(scene, 20, 3, build_scenes=False)
    some = sample_people(scene, 20, 3, Population(parameters=["pupil_diameter_mm"]))
    assert [p.values for p in every] == [p.values for p in some]
    assert all(set(p.overrides) == {"eye.pupil_diameter_mm"} for p in some)
    for p in some:
        assert p.scene.eye.pupil_diameter_mm == p.values["pupil_diameter_mm"]
        assert p.scene.eye.surfaces[0].radius_mm == scene.eye.surfaces[0].radius_mm


def test_each_sample_reaches_its_scene(scene):
    up, lo = (
        next(t for t in scene.face.tissues if t.name == n) for n in ("upper eyelid", "lower eyelid")
    )
    for p in sample_people(scene, 20, 11):
        e, v = p.scene.eye, p.values
        # the sampled radius is the mean-power one (K = 337.5/R), split by the astigmatism
        flat, steep = e.surfaces[0].radius_mm, e.cornea.radius_steep_mm
        assert 2 / (1 / flat + 1 / steep) == pytest.approx(v["corneal_radius_mm"], rel=1e-12)
        cyl, axis = 337.5 / steep - 337.5 / flat, math.radians(2 * e.cornea.axis_deg)
        j0, j45 = v["corneal_astigmatism_j0_d"], v["corneal_astigmatism_j45_d"]
        assert (cyl / 2 * math.cos(axis), cyl / 2 * math.sin(axis)) == pytest.approx((j0, j45))
        assert e.surfaces[0].conic == v["corneal_asphericity_q"]
        assert e.pupil_diameter_mm == v["pupil_diameter_mm"]
        assert e.rotation_centre_mm == v["rotation_centre_mm"]
        assert e.iris_reflectance == v["iris_reflectance"]
        assert e.sclera_reflectance == v["sclera_reflectance"]
        assert p.scene.face.skin_reflectance == v["skin_reflectance"]
        assert p.scene.head_offset_mm == pytest.approx(
            tuple(b + v[f"slip_{c}_mm"] for b, c in zip(scene.head_offset_mm, "xyz", strict=True))
        )
        up2, lo2 = (
            next(t for t in p.scene.face.tissues if t.name == n)
            for n in ("upper eyelid", "lower eyelid")
        )
        assert up2.clip_z_mm[0] + lo2.clip_z_mm[0] == pytest.approx(v["lid_aperture_mm"])
        assert up2.clip_z_mm[0] / lo2.clip_z_mm[0] == pytest.approx(
            up.clip_z_mm[0] / lo.clip_z_mm[0]
        )
        assert e.kappa_deg == (v["kappa_horizontal_deg"], scene.eye.kappa_deg[1])
        lashes = p.scene.face.lashes
        assert lashes.enabled and lashes.count == round(v["lash_count"])
        assert lashes.length_mm == v["lash_length_mm"]
        assert p.not_applied == ()
    # a scene without the lashes' lid: they are not applied
    bare = scene.model_copy(update={"face": scene.face.model_copy(update={"enabled": False})})
    p = sample_people(bare, 1, 11, build_scenes=False)[0]
    assert {"lash_count", "lash_length_mm"} <= set(p.not_applied)


def test_impossible_corneas_are_redrawn(scene):
    """A steep, oblate cornea has no limbus in front of the iris: such draws are redrawn;
    bounds that allow only such corneas are refused, naming the fields."""
    from eyelume.scene.population import _conic_sag

    both = ["corneal_radius_mm", "corneal_asphericity_q"]
    steep = {"corneal_radius_mm": {"bounds": [6.8, 7.0], "mean": 6.9, "sd": 0.25}}
    pop = Population(
        parameters=both,
        distributions={**steep, "corneal_asphericity_q": {"bounds": [-0.85, 0.25], "mean": 0.2}},
    )
    z_iris = sum(x.thickness_mm for x in scene.eye.surfaces[:2])
    people = sample_people(scene, 200, 5, pop)
    sags = [_conic_sag(p.values[both[0]], p.values[both[1]], 6.0) for p in people]
    assert all(s < z_iris for s in sags)
    assert max(s for s in sags) > z_iris - 0.3  # the edge was approached, not avoided
    assert [p.values for p in people] == [p.values for p in sample_people(scene, 200, 5, pop)]
    never = Population(
        parameters=both,
        distributions={**steep, "corneal_asphericity_q": {"bounds": [0.2, 0.25], "mean": 0.22}},
    )
    with pytest.raises(SceneError, match="corneal_radius_mm / corneal_asphericity_q"):
        sample_people(scene, 1, 0, never)


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (
            {"distributions": {"corneal_radius_mm": {"sd": -0.1}}},
            ["corneal_radius_mm", "sd", "-0.1"],
        ),
        (
            {"parameters": ["corneal_radius_mm", "nose_length_mm"]},
            ["parameters.1", "nose_length_mm"],
        ),
        ({"distributions": {"nose_length_mm": {"sd": 1.0}}}, ["distributions.nose_length_mm"]),
        (
            {"distributions": {"iris_reflectance": {"bounds": [0.02, 1.2]}}},
            ["iris_reflectance.bounds", "1.2", "physical"],
        ),
        (
            {"distributions": {"corneal_radius_mm": {"mean": 30.0}}},
            ["corneal_radius_mm.mean", "30"],
        ),
        ({"ambient": "moonlight"}, ["ambient", "moonlight"]),
        ({"size": 0}, ["size", "0"]),
        ({"sd": 1.0}, ["sd", "unknown"]),
    ],
)
def test_bad_population_is_one_line_naming_the_field(data, words):
    with pytest.raises(SceneError) as exc:
        parse_population(data)
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


def test_mean_outside_bounds_and_lids_missing(scene):
    pop = Population(distributions={"corneal_radius_mm": {"bounds": [7.0, 7.5]}})
    with pytest.raises(SceneError, match=r"population.distributions.corneal_radius_mm.*7\.8"):
        sample_people(scene, 1, 0, pop)
    no_lids = scene.model_copy(update={"face": scene.face.model_copy(update={"tissues": []})})
    with pytest.raises(SceneError, match="lid_aperture_mm"):
        sample_people(no_lids, 1, 0, Population(parameters=["lid_aperture_mm"]))
    (p,) = sample_people(no_lids, 1, 0)  # every parameter by default: the lids are skipped, said
    assert "lid_aperture_mm" in p.not_applied


_STUDY = """name = "people"
scene = "vr-offaxis"
metrics = ["safety", "tracking"]
[population]
size = 5
seed = 3
{extra}
"""


def test_study_file_population(tmp_path):
    good = tmp_path / "good.toml"
    good.write_text(_STUDY.format(extra='ambient = "dim"'), encoding="utf-8")
    st = load_study(good)
    assert st.population.size == 5 and st.population.luminance_cd_m2 == AMBIENT_LEVELS["dim"]
    bad = tmp_path / "bad.toml"
    bad.write_text(
        _STUDY.format(extra="[population.distributions.kappa_horizontal_deg]\nsd = -2.0"),
        encoding="utf-8",
    )
    with pytest.raises(SceneError, match=r"kappa_horizontal_deg.*sd = -2\.0"):
        load_study(bad)
    res = CliRunner().invoke(app, ["study", str(bad), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "kappa_horizontal_deg" in res.output and "-2.0" in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "o").exists()
