"""Datasets (issue 17): the dataset file's checks, each picture's draws from (seed, index) alone,
a picture re-rendered alone bit-identical to the dataset's, a dataset killed with kill -9 and
resumed byte-identical to an uninterrupted one (and 1 worker to 2), the render budget against
the sensor's shot noise, and the parent holding nothing per picture.

Pictures are vr-offaxis sampled by a 40 × 40 grid over the same 1.2 mm field of its 3 µm
photosites (the same optics, eye and photo-electrons per pixel, 100 times fewer pixels), a
second or two each."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from eyelume.errors import SceneError, StoreError
from eyelume.optimize import dataset as D
from eyelume.optimize.runner import run_tasks
from eyelume.scene.io import apply_overrides, load_scene, save_scene

BASE = """
name = "tiny"
scene = "tiny.toml"
seed = 7
pictures = {pictures}
samples_per_pixel = 1
[[vary]]
path = "eye.pupil_diameter_mm"
range = [2.0, 7.0]
[[vary]]
path = "head_offset_mm"
range = [[-1.0, 1.0], [-1.0, 1.0], [-0.5, 0.5]]
[[vary]]
path = "sensor.exposure_ms"
range = [2.0, 8.0]
"""


def tiny_scene(folder: Path) -> Path:
    sc = load_scene("vr-offaxis", {"sensor.cols": 40, "sensor.rows": 40, "sensor.width_mm": 1.2,
                                   "sensor.height_mm": 1.2})  # fmt: skip
    path = folder / "tiny.toml"
    save_scene(sc, path)
    return path


def write(folder: Path, text: str = BASE, pictures: int = 4, name: str = "ds.toml") -> Path:
    tiny_scene(folder)
    p = folder / name
    p.write_text(text.format(pictures=pictures), encoding="utf-8")
    return p


def top(text: str, line: str) -> str:
    """``text`` with a top-level ``line`` (before its first table)."""
    return text.replace("samples_per_pixel = 1\n", f"samples_per_pixel = 1\n{line}\n")


def folder_bytes(out: Path) -> dict[str, bytes]:
    """Every file of a dataset folder but the store (whose pages differ with its history)."""
    skip = {"results.sqlite", "results.sqlite-wal", "results.sqlite-shm", ".lock"}
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.name not in skip}  # fmt: skip


# --- the dataset file ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda t: top(t, "colour = 1"), ["colour"]),
        (lambda t: t.replace("pictures = 4", "pictures = 0"), ["pictures", "0"]),
        (lambda t: top(t, "image_bits = 12"), ["image_bits", "12"]),
        (lambda t: t.replace("samples_per_pixel = 1", "render_noise = 2.0"), ["render_noise"]),
        (lambda t: top(t, "render_noise = 0.01"), ["render_noise", "samples_per_pixel"]),
        (lambda t: t + "[gaze]\nhorizontal = [-40.0, 10.0]\n", ["gaze", "-40"]),
        (lambda t: t + "[gaze]\ndistribution = 'normal'\n", ["sd"]),
        (lambda t: t.replace("eye.pupil_diameter_mm", "eye.pupil_size"), ["vary[0]", "pupil_size"]),
        (lambda t: t.replace("[2.0, 7.0]", "[7.0, 2.0]"), ["pupil_diameter_mm", "low > high"]),
        (lambda t: t.replace("[2.0, 7.0]", "[2.0, 70.0]"), ["vary[0]", "70"]),
        (lambda t: t.replace("[-0.5, 0.5]]", "[-0.5, 0.5], [0, 1]]"), ["head_offset_mm"]),
        (lambda t: t.replace("tiny.toml", "nowhere.toml"), ["scene", "nowhere"]),
        (lambda t: t + "[glasses]\nshare = 0.5\nscene = 'tiny.toml'\n", ["glasses.scene"]),
        (lambda t: t + "[glasses]\nshare = 1.5\n", ["glasses.share", "1.5"]),
        (lambda t: t + "[population]\nsize = 0\n", ["population.size"]),
        (lambda t: t.replace("seed = 7", "seed = -1"), ["seed", "-1"]),
        (lambda t: t.replace("name = \"tiny\"", "name = \"\""), ["name"]),
    ],
)  # fmt: skip
def test_a_bad_dataset_file_is_one_line_naming_the_field(tmp_path, edit, words):
    p = tmp_path / "ds.toml"
    tiny_scene(tmp_path)
    p.write_text(edit(BASE.format(pictures=4)), encoding="utf-8")
    with pytest.raises(SceneError) as exc:
        D.load_dataset(p)
    text = str(exc.value)
    assert len(text.splitlines()) == 1 and str(p) in text, text
    for w in words:
        assert w in text, (w, text)


NOISE = "samples_per_pixel = 1"


@pytest.mark.parametrize(
    ("old", "new", "field", "value"),
    [
        (NOISE, 'render_noise = "senzor"', "render_noise", "'senzor'"),
        (NOISE, "render_noise = -0.1", "render_noise", "-0.1"),
        ("[2.0, 7.0]", '[2.0, "x"]', "vary[0].range[1]", "'x'"),
        ("[-0.5, 0.5]]", '[-0.5, "a"]]', "vary[1].range[2][1]", "'a'"),
        ("eye.pupil_diameter_mm", "eye.pupil_size", "vary[0].path", "'eye.pupil_size'"),
        ("eye.pupil_diameter_mm", "iris.size", "vary[0].path", "'iris.size'"),
        ("eye.pupil_diameter_mm", "eye..x", "vary[0].path", "'eye..x'"),
    ],
)  # fmt: skip
def test_a_bad_field_is_named_as_the_user_wrote_it_with_the_value_given(
    tmp_path, old, new, field, value
):
    """A fresh user read pydantic's paths (``render_noise.literal['sensor']``,
    ``vary.0.range.tuple[float, float].1``), ``render_noise = -0.1`` as a top-level problem and
    a bad [[vary]] path quoted with its range's value: the line names the field as the TOML has
    it and the value given there (the scene files' formatter, eyelume.scene.io)."""
    p = write(tmp_path)
    p.write_text(p.read_text(encoding="utf-8").replace(old, new, 1), encoding="utf-8")
    with pytest.raises(SceneError) as exc:
        D.load_dataset(p)
    text = str(exc.value)
    assert text.startswith(f"dataset {p}: field '{field}' = {value}: "), text
    assert "literal[" not in text and "tuple[" not in text and "top level" not in text


def test_a_study_vary_path_that_is_no_field_is_named_with_the_path(tmp_path):
    from eyelume.optimize.study import load_study

    p = tmp_path / "study.toml"
    p.write_text(
        'name = "s"\nscene = "paper2005"\nmetrics = ["safety"]\n[[vary]]\npath = "leds.hight_mm"\n'
        "values = [20.0, 30.0]\n",
        encoding="utf-8",
    )
    with pytest.raises(SceneError) as exc:
        load_study(p)
    assert str(exc.value).startswith(f"study {p}: field 'vary[0].path' = 'leds.hight_mm': ")
    p.write_text(p.read_text(encoding="utf-8").replace("[20.0, 30.0]", "[20.0, [1]]"), "utf-8")
    with pytest.raises(SceneError) as exc:
        load_study(p)
    assert "vary[0].values[1]" in str(exc.value) and "list[" not in str(exc.value)


def test_not_toml_and_missing_file_are_one_line(tmp_path):
    p = tmp_path / "ds.toml"
    p.write_text("name = [", encoding="utf-8")
    with pytest.raises(SceneError, match="not valid TOML"):
        D.load_dataset(p)
    with pytest.raises(SceneError, match="dataset"):
        D.load_dataset(tmp_path / "absent.toml")


# --- draws ----------------------------------------------------------------------------------------


def test_each_pictures_draws_depend_on_the_seed_and_its_index_only(tmp_path):
    text = BASE + "[population]\nsize = 3\nseed = 2\n[glasses]\nshare = 0.5\n"
    small = D.load_dataset(write(tmp_path, text, pictures=5))
    large = D.load_dataset(write(tmp_path, text, pictures=400, name="large.toml"))
    assert [D.plan_picture(small, i) for i in range(5)] == [D.plan_picture(large, i) for i in
                                                            range(5)]  # fmt: skip
    plans = [D.plan_picture(large, i) for i in range(400)]
    assert len({p.seed for p in plans}) == 400
    assert [p.person for p in plans[:7]] == [0, 1, 2, 0, 1, 2, 0]
    h = np.array([p.gaze_deg[0] for p in plans])
    v = np.array([p.gaze_deg[1] for p in plans])
    assert h.min() >= -25 and h.max() <= 25 and v.min() >= -20 and v.max() <= 20
    # uniform on [-25, 25]: mean 0 ± 3σ of the mean (σ = 50/√12/√400 = 0.72°)
    assert abs(h.mean()) < 3 * 50 / np.sqrt(12) / 20
    pupil = np.array([p.varied["eye.pupil_diameter_mm"] for p in plans])
    assert 2.0 <= pupil.min() and pupil.max() <= 7.0
    offsets = np.array([p.varied["head_offset_mm"] for p in plans])
    assert offsets.shape == (400, 3) and np.abs(offsets[:, 2]).max() <= 0.5
    share = np.mean([p.glasses for p in plans])
    assert abs(share - 0.5) < 3 * 0.5 / 20  # binomial: 3σ
    other = D.load_dataset(write(tmp_path, text.replace("seed = 7", "seed = 8"), 5, "o.toml"))
    assert D.plan_picture(other, 0).gaze_deg != plans[0].gaze_deg


def test_a_normal_gaze_is_truncated_to_its_ranges(tmp_path):
    text = BASE + "[gaze]\ndistribution = 'normal'\nsd = [10.0, 5.0]\nhorizontal = [-5.0, 20.0]\n"
    ds = D.load_dataset(write(tmp_path, text, pictures=2000))
    h = np.array([D.plan_picture(ds, i).gaze_deg[0] for i in range(2000)])
    assert h.min() >= -5.0 and h.max() <= 20.0
    # the truncated normal's mean: σ (φ(a) − φ(b)) / (Φ(b) − Φ(a)), a = −0.5, b = 2
    from scipy.stats import truncnorm

    mean, sd = truncnorm.mean(-0.5, 2.0, scale=10.0), truncnorm.std(-0.5, 2.0, scale=10.0)
    assert abs(h.mean() - mean) < 4 * sd / np.sqrt(2000)


# --- pictures -----------------------------------------------------------------------------------


def test_the_picture_skips_the_eye_plane_bit_for_bit(tmp_path):
    from eyelume.render import RenderOptions, render

    sc = load_scene(str(tiny_scene(tmp_path)))
    opts = RenderOptions(estimator="fast", samples_per_pixel=8, seed=3)
    a = render(sc, opts)
    b = render(apply_overrides(sc, D._NO_EYE_PLANE), opts)
    assert np.array_equal(a.eye_image, b.eye_image)
    assert all(np.array_equal(a.regions[k], b.regions[k]) for k in a.regions)


def test_render_noise_sensor_keeps_the_render_below_the_shot_noise(tmp_path):
    text = BASE.replace("samples_per_pixel = 1", "render_noise = 'sensor'")
    ds = D.load_dataset(write(tmp_path, text, pictures=3))
    for i in (0, 1):
        render = D.make_picture(ds, i).label["render"]
        assert render["budget"] == "sensor"
        assert render["median_skin_rel_error"] <= render["skin_shot_noise"], render
        # the pilot's coarse pixels read the median skin electrons of the picture within 10 %
        final_e = render["skin_shot_noise"] ** -2
        assert abs(render["pilot_skin_electrons"] / final_e - 1) < 0.10, render
        target = D.SENSOR_NOISE_MARGIN / np.sqrt(render["pilot_skin_electrons"])
        assert render["target_rel_error"] == pytest.approx(target)


def test_a_picture_label_holds_its_draws_and_truth(tmp_path):
    ds = D.load_dataset(write(tmp_path, BASE + "[population]\nsize = 2\nseed = 3\n"))
    pic = D.make_picture(ds, 1)
    lab = pic.label
    plan = D.plan_picture(ds, 1)
    assert lab["index"] == 1 and lab["seed"] == plan.seed
    assert lab["image"] == "images/000001.png" and lab["size_px"] == [40, 40]
    assert lab["varied"] == plan.varied and lab["person"]["index"] == 1
    assert pic.scene.eye.pupil_diameter_mm == plan.varied["eye.pupil_diameter_mm"]
    assert pic.scene.sensor.exposure_ms == plan.varied["sensor.exposure_ms"]
    assert lab["gaze_deg"]["horizontal"] == pytest.approx(plan.gaze_deg[0], abs=1e-6)
    assert lab["gaze_deg"]["vertical"] == pytest.approx(plan.gaze_deg[1], abs=1e-6)
    assert pic.image.dtype == np.uint8 and pic.counts.dtype == np.uint16
    # 8 bits: DN × 255 / (2^10 − 1), rounded
    assert np.array_equal(pic.image, np.rint(pic.counts * (255 / 1023)).astype(np.uint8))
    assert len(lab["glints"]) == 8
    assert lab["segmentation"] == "segmentation/000001.png"
    assert pic.segmentation.shape == (40, 40) and pic.segmentation.dtype == np.uint8
    json.dumps(lab, allow_nan=False)
    jsonschema = pytest.importorskip("jsonschema")
    from importlib import resources

    schema = json.loads((resources.files("eyelume.analysis") / "dataset_label.schema.json")
                        .read_text(encoding="utf-8"))  # fmt: skip
    jsonschema.validate(json.loads(D.dumps(lab, indent=None)), schema)


def test_the_openeds_map_is_exact_under_the_glints_and_the_export_copies_it(tmp_path):
    """The folder stores the OpenEDS view with the class under each glint from the scene
    (openeds_map with the primary surface map), so dataset-export is exact instead of taking
    the nearest pixel's class (a fresh user's finding). (This 40 × 40 picture at 1 sample per
    pixel has no glint region: test_labels' synthetic map checks the class under a glint.)"""
    from eyelume.analysis.labels import _CLASS, openeds_map, primary_classes
    from eyelume.compile import compile_scene
    from eyelume.report.dataset_outputs import export_openeds

    ds = D.load_dataset(write(tmp_path, pictures=1))
    pic = D.make_picture(ds, 0)
    under = primary_classes(compile_scene(pic.scene))
    assert np.array_equal(pic.openeds, openeds_map(pic.segmentation, under))
    # every pixel, glints and reflections included (test_labels: openeds_map with the primary
    # map puts the class under a glint), is the primary surface's class, skin and lids as 0
    shown = np.where(under >= _CLASS["skin"], 0, under)
    assert np.array_equal(pic.openeds, shown)
    assert pic.label["segmentation_openeds"] == "segmentation_openeds/000000.png"
    out = tmp_path / "set"
    out.mkdir()
    D._prepare(ds, D.bases(ds), out, resume=False)
    D.write_picture(pic, out)
    (out / D.LABELS_FILE).write_text(D.dumps(pic.label, indent=None) + "\n", encoding="utf-8")
    export_openeds(out, tmp_path / "export", size=None)
    got = np.load(tmp_path / "export" / "train" / "labels" / "000000.npy")
    assert np.array_equal(got, pic.openeds)


@pytest.mark.slow
def test_killed_then_resumed_equals_an_uninterrupted_run_and_one_picture_alone(tmp_path):
    """kill -9 of the command and its worker mid-dataset, then --resume (1 worker): the same
    files and labels.jsonl, byte for byte, as an uninterrupted run on 2 workers; and a picture
    made alone in this process (its own Numba threads) is the dataset's, bit for bit."""
    p = write(tmp_path, BASE, pictures=6)
    ds = D.load_dataset(p)
    clean = tmp_path / "clean"
    assert D.run_dataset(ds, clean, workers=2) == 6
    killed = tmp_path / "killed"
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", "dataset", str(p),
           "--out", str(killed), "--workers", "1"]  # fmt: skip
    proc = subprocess.Popen(cmd, start_new_session=True, stderr=subprocess.DEVNULL)
    db, n, deadline = killed / "results.sqlite", 0, time.time() + 300
    try:
        while time.time() < deadline and proc.poll() is None and n < 2:
            try:
                with sqlite3.connect(f"{db.absolute().as_uri()}?mode=ro", uri=True) as con:
                    n = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
            except sqlite3.OperationalError:
                n = 0
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the command and its worker, mid-picture
        proc.wait()
    assert 2 <= n < 6, n
    with pytest.raises(StoreError, match="--resume"):
        D.run_dataset(ds, killed, workers=1)
    assert D.run_dataset(ds, killed, workers=1, resume=True) == 6
    a, b = folder_bytes(clean), folder_bytes(killed)
    assert sorted(a) == sorted(b)
    for name in a:
        assert a[name] == b[name], name
    lines = (clean / "labels.jsonl").read_text(encoding="utf-8").splitlines()
    assert [json.loads(x)["index"] for x in lines] == list(range(6))
    assert sum(name.startswith("segmentation/") for name in a) == 6
    assert "schema.json" in a and "dataset.json" in a
    # one picture alone, in this process
    pic = D.make_picture(ds, 4)
    assert D._png(pic.image) == a["images/000004.png"]
    assert D._png(pic.segmentation) == a["segmentation/000004.png"]
    assert np.array_equal(pic.irradiance, np.load(clean / "irradiance/000004.npy"))
    assert json.loads(D.dumps(pic.label, indent=None)) == json.loads(lines[4])


@pytest.mark.slow
def test_a_resume_of_another_dataset_is_refused(tmp_path):
    ds = D.load_dataset(write(tmp_path, BASE, pictures=1))
    out = tmp_path / "out"
    assert D.run_dataset(ds, out, workers=1) == 1
    other = D.load_dataset(write(tmp_path, BASE.replace("seed = 7", "seed = 8"), 1, "b.toml"))
    with pytest.raises(StoreError, match="differs in seed"):
        D.run_dataset(other, out, workers=1, resume=True)
    more = D.load_dataset(write(tmp_path, BASE, pictures=2, name="c.toml"))
    before = (out / "images" / "000000.png").read_bytes()
    assert D.run_dataset(more, out, workers=1, resume=True) == 2  # extended: one more picture
    assert (out / "images" / "000000.png").read_bytes() == before


# --- the parent holds nothing per picture -------------------------------------------------------


def test_the_executor_takes_tasks_as_others_finish(tmp_path):
    """run_tasks reads its task iterator lazily: never more than its window of tasks taken and
    not yet committed, so the parent's memory does not grow with the number of pictures."""
    taken, committed, most = [0], [0], [0]

    def tasks():
        for i in range(40):
            taken[0] += 1
            most[0] = max(most[0], taken[0] - committed[0])
            yield i, (-i,)

    results = {}

    def commit(tag, value):
        committed[0] += 1
        results[tag] = value

    run_tasks(abs, tasks(), commit, workers=1, window=3)
    assert results == {i: i for i in range(40)}
    assert most[0] <= 3


def test_labels_are_streamed_from_the_store(tmp_path):
    """labels.jsonl is written from a cursor over the store (each_row), sorted by index."""
    from eyelume.optimize.store import ResultStore

    store = ResultStore(tmp_path)
    try:
        for i in (2, 0, 1):
            store.put(f"k:{i}", i, "d", {}, {"index": i}, 1.0)
        rows = store.each_row()
        assert next(rows)["index"] == 0  # a generator: one row at a time
        ds = D.load_dataset(write(tmp_path, BASE, pictures=3))
        assert D.write_labels(store, ds, "k", tmp_path) == 3
    finally:
        store.close()
    lines = (tmp_path / "labels.jsonl").read_text(encoding="utf-8").splitlines()
    assert lines == ['{"index": 0}', '{"index": 1}', '{"index": 2}']


def test_glasses_add_the_glasses_scenes_elements_to_their_share_of_pictures(tmp_path):
    text = BASE + "[glasses]\nshare = 0.5\nscene = 'vr-offaxis-glasses'\n"
    ds = D.load_dataset(write(tmp_path, text, pictures=8))
    plans = [D.plan_picture(ds, i) for i in range(8)]
    on = next(p.index for p in plans if p.glasses)
    off = next(p.index for p in plans if not p.glasses)
    lens = load_scene("vr-offaxis-glasses").elements
    b = D.bases(ds)
    assert D.picture_scene(b, plans[on])[0].elements == lens
    assert D.picture_scene(b, plans[off])[0].elements == []
    pic = D.make_picture(ds, on, b)
    assert pic.label["glasses"] is True and pic.image.shape == (40, 40)


# --- the folder's lock ----------------------------------------------------------------------------


@pytest.mark.parametrize("end", ["finished", "interrupted"])
def test_no_lock_file_is_left_after_a_run_finished_or_interrupted(tmp_path, monkeypatch, end):
    """The store's ``.lock`` is held while a run writes (a second writer is refused) and
    removed when the run ends, also by Ctrl-C/SIGTERM (the interrupt run_tasks raises)."""
    from eyelume.optimize import runner
    from eyelume.optimize.store import ResultStore, StoreBusy

    ds = D.load_dataset(write(tmp_path, pictures=2))
    out = tmp_path / "out"
    seen = []

    def tasks_here(fn, tasks, commit, workers=None, dask=None, window=None):
        seen.append((out / ".lock").is_file())
        with pytest.raises(StoreBusy):
            ResultStore(out)  # another writer, while this run holds the folder
        if end == "interrupted":
            raise KeyboardInterrupt

    monkeypatch.setattr(runner, "run_tasks", tasks_here)
    if end == "interrupted":
        with pytest.raises(KeyboardInterrupt):
            D.run_dataset(ds, out, workers=1)
    else:
        assert D.run_dataset(ds, out, workers=1) == 0
    assert seen == [True]
    assert not (out / ".lock").exists(), sorted(p.name for p in out.iterdir())
    ResultStore(out).close()  # the folder takes a writer again
    assert not (out / ".lock").exists()
