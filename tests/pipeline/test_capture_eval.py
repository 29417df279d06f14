"""The capture's evaluation: a tiny real run (generated people, two captures each) against its truth."""

import json
import math

import pytest

from relightnet.cli import main
from relightnet.pipeline.capture_eval import CAPTURE_METRICS, evaluate_capture

#: figures that are shares or similarities, in [0, 1]
UNIT = ("albedo_rmse", "albedo_rmse_raw", "seen", "iou_bare", "iou_offset", "iou_relit", "ssim", "ssim_bare",
        "ssim_raw")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """One person of 12 frames at 128², texture 256² (seed 9100: none of the evaluation's)."""
    from relightnet.pipeline.backends import make_predictor

    out = tmp_path_factory.mktemp("capture_eval") / "report"
    return out, evaluate_capture(make_predictor("torch", None, "cpu"), out, clips=1, frames=12, res=128,
                                 texture_size=256, seed=9100)


@pytest.mark.slow  # two real captures: ~20 s alone on 2 cores, minutes on a loaded machine
def test_the_report_is_written_and_its_figures_are_in_range(run):
    out, result = run
    assert (out / "capture_report.md").is_file() and not list(out.glob(".*.tmp"))
    saved = json.loads((out / "capture_metrics.json").read_text())
    row = saved["clips"][0]
    assert saved["frames"] == 12 and saved["res"] == 128 and len(saved["clips"]) == 1 and row["seed"] == 9100
    assert all(math.isfinite(row[k]) for k in CAPTURE_METRICS), row
    assert all(0 <= row[k] <= 1 for k in UNIT), row
    assert 0 <= row["invariance"] < 3 and 0 < row["psnr"] < 60 and 0 < row["psnr_raw"] < 60
    assert row["ms_per_frame"] > 0 and row["peak_rss_mb"] > 100
    assert row["iou_offset"] >= row["iou_bare"] - 0.02  # the offsets do not make the silhouette worse
    text = (out / "capture_report.md").read_text()
    assert "| albedo_rmse |" in text and "≤ 0.12" in text and "| mean |" in text


def test_the_cli_refuses_other_modes_options(tmp_path, capsys):
    out = tmp_path / "r"
    with pytest.raises(SystemExit):
        main(["evaluate", "capture", "--data", str(tmp_path), "--out", str(out)])
    assert "unrecognized arguments: --data" in capsys.readouterr().err and not out.exists()
