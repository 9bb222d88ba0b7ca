"""A dataset folder's outputs (eyelume.report.dataset_outputs): the OpenEDS-layout copy, the
contact sheet and the distributions, the report's dataset page and ``eyelume dataset-export``.

The folder is ``dataset_fixture.write_fake_dataset``'s: the layout ``eyelume dataset`` writes,
drawn with OpenCV (pictures, segmentations and labels from the same ellipses), so these tests
need no render.
"""

from __future__ import annotations

import html
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from eyelume.cli import app
from eyelume.errors import InputFileError
from eyelume.report.dataset_outputs import (
    distribution_values,
    export_openeds,
    openeds_view,
    read_dataset,
    read_picture,
    save_contact_sheet,
    save_distributions,
)
from eyelume.report.html import write_report
from eyelume.report.plots import observe_figures

sys.path.insert(0, os.path.dirname(__file__))
from dataset_fixture import write_fake_dataset  # noqa: E402
from test_figures import Caught, _check  # noqa: E402
from test_html import _browser  # noqa: E402

CAPTION = ("vr-offaxis", 7)  # the fixture's dataset.json: scene and seed


def _to_export(x: float, scale: float, offset: float) -> int:
    """A label-file pixel coordinate on the exported canvas (eyelume_export.json's mapping)."""
    return round(scale * (x + 0.5) - 0.5 + offset)


def test_openeds_view_maps_skin_and_lids_to_background_and_glints_to_what_is_under_them():
    seg = np.array(
        [
            [4, 4, 5, 5, 1, 1],
            [4, 1, 2, 2, 2, 1],
            [1, 2, 3, 6, 3, 2],
            [1, 2, 3, 3, 3, 2],
            [7, 2, 2, 2, 7, 1],
        ],
        np.uint8,
    )
    view = openeds_view(seg)
    assert view.dtype == np.uint8
    assert view[0].tolist() == [0, 0, 0, 0, 1, 1]  # skin 4 and eyelid 5 -> background
    assert view[2, 3] == 3  # a glint inside the pupil -> pupil
    assert view[4, 0] in (1, 2) and view[4, 4] in (2, 3)  # reflections -> a neighbour's class
    keep = seg <= 3
    assert np.array_equal(view[keep], seg[keep])  # classes 0..3 are left alone
    assert not openeds_view(np.full((3, 3), 6, np.uint8)).any()  # only glints: background
    with pytest.raises(ValueError, match="0..7"):
        openeds_view(np.full((2, 2), 8, np.uint8))


@pytest.mark.parametrize("bits", [8, 16])
def test_export_writes_openeds_names_dtypes_shapes_and_ids(tmp_path, bits):
    labels = write_fake_dataset(tmp_path / "set", n=3, bits=bits)
    summary = export_openeds(tmp_path / "set", tmp_path / "eds")
    assert summary.pictures == 3
    root = tmp_path / "eds" / "train"
    assert sorted(p.name for p in (root / "images").iterdir()) == [
        "000000.png", "000001.png", "000002.png"]  # fmt: skip
    assert sorted(p.name for p in (root / "labels").iterdir()) == [
        "000000.npy", "000001.npy", "000002.npy"]  # fmt: skip
    manifest = json.loads((tmp_path / "eds" / "eyelume_export.json").read_text())
    for lab, rec in zip(labels, manifest["pictures"], strict=True):
        with Image.open(tmp_path / "eds" / rec["image"]) as im:
            assert im.mode == "L" and im.size == (640, 400)  # 8-bit grey, OpenEDS' size
            pic = np.asarray(im)
        ids = np.load(tmp_path / "eds" / rec["label"])
        assert ids.dtype == np.uint8 and ids.shape == (400, 640)
        assert set(np.unique(ids).tolist()) == {0, 1, 2, 3}
        # 96 x 72 fitted to 400 rows: scale 400/72, centred: black padding is background
        s, (ox, oy) = rec["scale"], rec["offset_px"]
        assert s == pytest.approx(400 / 72) and oy == 0 and ox == (640 - round(96 * s)) // 2
        assert not ids[:, : ox - 1].any() and not pic[:, : ox - 1].any()
        # the label file's pupil centre and glints land on pupil / iris-or-pupil pixels
        cx, cy = lab["pupil"]["ellipse"]["center_px"]
        assert ids[_to_export(cy, s, oy), _to_export(cx, s, ox)] == 3
        for g in lab["glints"]:
            if g["position_px"] is not None:
                gx, gy = g["position_px"]
                assert ids[_to_export(gy, s, oy), _to_export(gx, s, ox)] in (2, 3)
                assert pic[_to_export(gy, s, oy), _to_export(gx, s, ox)] > 200  # a bright glint
        # the picture's own grey levels: the pupil dark, scaled from 16 bits when stored so
        assert pic[_to_export(cy, s, oy), _to_export(cx, s, ox)] < 60


def test_export_native_size_keeps_each_picture(tmp_path):
    write_fake_dataset(tmp_path / "set", n=2)
    export_openeds(tmp_path / "set", tmp_path / "eds", size=None, split="validation")
    ids = np.load(tmp_path / "eds" / "validation" / "labels" / "000001.npy")
    seg = np.asarray(Image.open(tmp_path / "set" / "segmentation" / "000001.png"))
    assert ids.shape == seg.shape == (72, 96)
    assert np.array_equal(ids, openeds_view(seg))


def test_contact_sheet_and_distributions_pass_the_figure_checks(tmp_path):
    write_fake_dataset(tmp_path / "set", n=6)
    ds = read_dataset(tmp_path / "set")
    drawn = []
    _check(lambda: drawn.append(save_contact_sheet(ds, tmp_path / "sheet.png", n=5)), CAPTION)
    assert drawn == [[0, 1, 2, 4, 5]]  # evenly spread over the indices
    panels = []
    _check(lambda: panels.append(save_distributions(ds, tmp_path / "dist.png")), CAPTION)
    values = distribution_values(ds.labels)
    assert panels[0] == [*values, "glasses"]
    assert "eye_pose.head_offset_mm[y] (mm)" in values  # a vector path: one panel per component
    assert "person kappa_horizontal_deg (°)" in values and "sensor.exposure_ms (ms)" in values
    assert len(values["gaze horizontal (°)"]) == 6


def test_report_writes_the_dataset_page_with_its_figures(tmp_path):
    write_fake_dataset(tmp_path / "set", n=4)
    caught = Caught(CAPTION)
    with observe_figures(caught):
        page = write_report(tmp_path / "set")
    assert not caught.defects, caught.defects
    assert page == tmp_path / "set" / "report.html"
    text = page.read_text(encoding="utf-8")
    assert text.count("<img ") == text.count("<figcaption>") == len(caught.names) == 2
    assert "<h1>Dataset fake-set</h1>" in text and "<th>pictures</th><td>4</td>" in text
    captions = [html.unescape(c) for c in re.findall(r"<figcaption>(.*?)</figcaption>", text)]
    assert all("dataset fake-set: scene vr-offaxis, seed 7" in c for c in captions)


@pytest.mark.slow
def test_dataset_page_renders_in_headless_chromium(tmp_path):
    browser = _browser()
    write_fake_dataset(tmp_path / "set", n=4)
    page = write_report(tmp_path / "set")
    args = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            "--window-size=1280,1600", "--virtual-time-budget=5000", "--dump-dom",
            page.as_uri()]  # fmt: skip
    dom = subprocess.run(args, capture_output=True, text=True, timeout=120, check=True).stdout
    assert re.search(r'data-figures="(\d+)"', dom).group(1) == "2"  # both figures decoded
    assert re.search(r'data-overflow-px="(\d+)"', dom).group(1) == "0"


def test_bad_label_files_name_the_file_and_line(tmp_path):
    write_fake_dataset(tmp_path / "set", n=2)
    path = tmp_path / "set" / "labels.jsonl"
    lines = path.read_text().splitlines()
    path.write_text(lines[0] + "\n{not json\n")
    with pytest.raises(InputFileError, match=r"labels\.jsonl.*line 2 is not JSON"):
        read_dataset(tmp_path / "set")
    path.write_text(lines[0] + "\n" + lines[0] + "\n")
    with pytest.raises(InputFileError, match="line 2: picture 0 is listed twice"):
        read_dataset(tmp_path / "set")
    path.write_text("\n".join(lines) + "\n")
    Image.fromarray(np.full((72, 96), 9, np.uint8)).save(tmp_path / "set/segmentation/000001.png")
    with pytest.raises(InputFileError, match=r"000001\.png.*class id 9"):
        export_openeds(tmp_path / "set", tmp_path / "eds")


def test_cli_dataset_export(tmp_path):
    write_fake_dataset(tmp_path / "set", n=2)
    runner = CliRunner()
    res = runner.invoke(app, ["dataset-export", str(tmp_path / "set"), "--out",
                              str(tmp_path / "eds"), "--size", "320x200"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert np.load(tmp_path / "eds/train/labels/000001.npy").shape == (200, 320)
    for bad, said in ((["--size", "640"], "--size '640'"), (["--to", "coco"], "--to 'coco'")):
        res = runner.invoke(app, ["dataset-export", str(tmp_path / "set"), "--out",
                                  str(tmp_path / "x"), *bad])  # fmt: skip
        assert res.exit_code == 2 and said in res.output, res.output
        assert len(res.output.strip().splitlines()) == 1
    res = runner.invoke(app, ["dataset-export", str(tmp_path), "--out", str(tmp_path / "y")])
    assert res.exit_code == 2 and "labels.jsonl" in res.output, res.output


def test_detector_benchmark_scores_against_the_labels(tmp_path):
    """benchmarks/dataset_detect.py's scoring: on the drawn pictures (their labels exact by
    construction) the detector's pupil centre is within half a pixel and every glint is paired;
    a label moved by 3 px reads as a 3 px error, a glint moved out of reach as one missed and
    one false."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    import dataset_detect as bench

    write_fake_dataset(tmp_path / "set", n=3)
    ds = read_dataset(tmp_path / "set")
    pics = [read_picture(ds, lab) for lab in ds.labels]
    rows = [bench.score_picture(p, lab, None, None) for p, lab in zip(pics, ds.labels, strict=True)]
    s = bench.summarise(rows)
    assert s["ok_share"] == 1.0 and s["pupil_share_within_1px"] == 1.0
    assert s["pupil_error_px_p95"] < 0.5
    assert s["glints_true"] == s["glints_matched"] == 12 and s["glints_false"] == 0
    lab = json.loads(json.dumps(ds.labels[0]))
    cx, cy = lab["pupil"]["ellipse"]["center_px"]
    lab["pupil"]["ellipse"]["center_px"] = [cx + 3.0, cy]
    lab["glints"][1]["position_px"][0] += 10.0  # out of the 3 px reach
    r = bench.score_picture(pics[0], lab, None, None)
    assert r["pupil_error_px"] == pytest.approx(3.0, abs=0.5)
    one = bench.summarise([r])
    assert (one["glints_matched"], one["glints_missed"], one["glints_false"]) == (3, 1, 1)


def test_cli_report_on_a_dataset_folder(tmp_path):
    write_fake_dataset(tmp_path / "set", n=2)
    runner = CliRunner()
    res = runner.invoke(app, ["report", str(tmp_path / "set"), "--out", str(tmp_path / "p.html")])
    assert res.exit_code == 0, res.output
    assert "<h1>Dataset fake-set</h1>" in (tmp_path / "p.html").read_text(encoding="utf-8")
    res = runner.invoke(app, ["report", str(tmp_path / "set"), "--scene", "vr-offaxis"])
    assert res.exit_code == 2 and "is a dataset's folder" in res.output, res.output


@pytest.mark.parametrize("kind", ["missing", "file", "render", "empty"])
def test_cli_report_on_what_is_no_study_or_dataset_folder_says_what_it_takes(tmp_path, kind):
    """A fresh user's `eyelume report nosuchdir` was told to run a study: the one line says
    what the path is (missing, a file, a render's folder, neither) and what report takes."""
    folder = tmp_path / "nosuchdir"
    if kind == "file":
        folder.write_text("x", encoding="utf-8")
    elif kind != "missing":
        folder.mkdir()
    if kind == "render":
        (folder / "summary.json").write_text("{}", encoding="utf-8")
    res = CliRunner().invoke(app, ["report", str(folder)])
    assert res.exit_code == 2, res.output
    lines = [x for x in res.output.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"error: {folder}: "), res.output
    said = {"missing": "no such folder", "file": "is a file", "render": "a render's folder",
            "empty": "neither a study's nor a dataset's folder"}  # fmt: skip
    assert said[kind] in lines[0]
    assert "study's folder" in lines[0] and "dataset's" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nosuchdir"] or kind == "missing"


@pytest.mark.slow
def test_a_tiny_dataset_made_by_eyelume_dataset_is_read_exported_and_scored(tmp_path):
    """`eyelume dataset` itself (vr-offaxis at 64 × 64 px over the same field, 2 pictures, 2
    samples per pixel) read back: its pictures and segmentations export to OpenEDS' layout, the
    label's pupil-ellipse centre falls on OpenEDS' pupil class there (ds-labels' ellipse and
    segmentation agree through the export's pixel mapping), the page is written and the
    detector benchmark scores every picture."""
    from eyelume.scene.io import load_scene, save_scene

    small = load_scene("vr-offaxis", {"sensor.cols": 64, "sensor.rows": 64,
                                      "sensor.pixel_pitch_um": 3.0 * 400 / 64})  # fmt: skip
    save_scene(small, tmp_path / "small.toml")
    (tmp_path / "tiny.toml").write_text(
        'name = "tiny"\nscene = "small.toml"\nseed = 2\npictures = 2\nimage_bits = 8\n'
        'irradiance = false\nsamples_per_pixel = 2\n[gaze]\ndistribution = "uniform"\n'
        "horizontal = [-10.0, 10.0]\nvertical = [-5.0, 5.0]\n",
        encoding="utf-8",
    )
    res = CliRunner().invoke(app, ["dataset", str(tmp_path / "tiny.toml"), "--out",
                                   str(tmp_path / "set"), "--workers", "1"])  # fmt: skip
    assert res.exit_code == 0, res.output
    ds = read_dataset(tmp_path / "set")
    assert (ds.name, ds.seed, len(ds.labels)) == ("tiny", 2, 2)
    summary = export_openeds(tmp_path / "set", tmp_path / "eds")
    manifest = json.loads((tmp_path / "eds" / "eyelume_export.json").read_text())
    assert summary.pictures == 2 and all(summary.class_pixels[k] > 0 for k in (1, 2, 3))
    for lab, rec in zip(ds.labels, manifest["pictures"], strict=True):
        ids = np.load(tmp_path / "eds" / rec["label"])
        assert ids.dtype == np.uint8 and ids.shape == (400, 640) and ids.max() <= 3
        if lab["pupil"]["visible_share"] > 0.9:
            cx, cy = lab["pupil"]["ellipse"]["center_px"]
            s, (ox, oy) = rec["scale"], rec["offset_px"]
            assert ids[_to_export(cy, s, oy), _to_export(cx, s, ox)] == 3
    page = write_report(tmp_path / "set")
    assert page.read_text(encoding="utf-8").count("<img ") == 2
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    import dataset_detect as bench

    rows = [bench.score_picture(read_picture(ds, lab), lab, None, None) for lab in ds.labels]
    assert bench.summarise(rows)["pictures"] == 2
