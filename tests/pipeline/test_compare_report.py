"""relightnet.pipeline.compare_report: strict JSON, the staged-then-published report folder, the summary means."""

import json
import math

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.pipeline.compare_report import json_safe, publish, staging_dir, summarize, to_uint8_seq, write_json


def test_json_is_strict(tmp_path):
    data = {"a": math.inf, "b": [np.float32("nan"), -math.inf, 1.5], 3: {"c": (1, 2)}}
    assert json_safe(data) == {"a": "inf", "b": ["nan", "-inf", 1.5], "3": {"c": [1, 2]}}
    write_json(tmp_path / "m.json", data)
    assert json.loads((tmp_path / "m.json").read_text())["b"][0] == "nan"


def test_stage_then_publish_replaces_only_what_the_run_made(tmp_path):
    out = tmp_path / "new" / "report"
    stage = staging_dir(out)
    assert stage.is_dir() and stage.parent == tmp_path and stage.name.startswith(".")
    (stage / "plots").mkdir()
    (stage / "report.md").write_text("ok")
    (stage / "plots" / "clip0.png").write_bytes(b"png")
    (out / "plots").mkdir(parents=True)
    (out / "plots" / "clip7.png").write_bytes(b"stale")  # a clip of an earlier, longer run
    (out / "notes.txt").write_text("the user's")
    files = publish(stage, out)
    assert set(files) == {"report.md", "plots/clip0.png"} and not stage.exists()
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()) == [
        "notes.txt", "plots/clip0.png", "report.md"]
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="exists and is not a folder"):
        staging_dir(tmp_path / "file")


def _clip(rmse, temporal, err):
    row = {"path": "2d", "light": "smoothed", "per_frame": {"rmse": rmse, "psnr": [30.0] * len(rmse),
                                                             "ssim": [0.9] * len(rmse)}, "temporal": temporal}
    light = {n: {"error": err, "relative": err / 2, "jitter": 0.1} for n in ("raw", "smoothed")}
    return {"rows": [row], "light": {**light, "true": {"jitter": 0.0}}}


def test_summary_means_over_all_frames_and_clips():
    s = summarize([_clip([0.1, 0.3], 0.02, 1.0), _clip([0.2], math.nan, 3.0)])
    row = s["rows"][0]
    assert (row["path"], row["light"]) == ("2d", "smoothed")
    assert row["rmse"] == pytest.approx(0.2) and row["temporal"] == pytest.approx(0.02)  # frames weigh equally
    assert s["light"]["raw"]["error"] == pytest.approx(2.0) and s["light"]["true"]["jitter"] == 0.0


def test_uint8_sequence_is_each_frame_written_as_srgb():
    from relightnet.io import to_uint8

    x = torch.rand(3, 5, 4, 3, generator=torch.Generator().manual_seed(0)) * 1.2  # some above white
    u = to_uint8_seq(x)
    assert u.dtype == torch.uint8 and u.shape == x.shape
    assert all(torch.equal(u[t], torch.as_tensor(to_uint8(x[t]))) for t in range(3))
    assert u[x >= 1].min() == 255 and to_uint8_seq(torch.zeros(1, 1, 1, 3)).max() == 0
