import json

import pytest

from relightnet.cli import main
from relightnet.io import read_video, video_info
from relightnet.light import preset_names


@pytest.mark.slow
def test_demo_runs_on_embedded_defaults(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--size", "64", "--frames", "5", "--n-dirs", "8",
                 "--compare-clips", "1", "--compare-size", "32", "--compare-frames", "4"]) == 0
    printed = capsys.readouterr().out
    assert "where to look" in printed and str(out / "avatar.mp4") in printed
    assert sorted(p.stem for p in (out / "lights").iterdir()) == sorted(preset_names())
    for name in ("target", "target_masks", "plate", "avatar"):
        info = video_info(out / f"{name}.mp4")
        assert info.n_frames == 5 and info.size == (64, 64), name
    sbs = list(read_video(out / "side_by_side.mp4"))
    assert len(sbs) == 5 and sbs[0].shape == (64, 128, 3)
    # The avatar half differs from the target half (the avatar was composited over the plate).
    assert abs(sbs[0][:, 64:].astype(int) - sbs[0][:, :64].astype(int)).mean() > 1
    assert (out / "lights.png").stat().st_size > 1000
    summary = json.loads((out / "summary.json").read_text())
    assert summary["light_error"]["raw"] >= 0 and summary["target_clip"]["frames"] == 5
    replaced = summary["replaced_person"]
    assert replaced["plate_psnr_db"] > 25 and 0 <= replaced["never_uncovered_share"] < 1
    assert video_info(out / "replace" / "avatar.mp4").n_frames == 5 and (out / "replace" / "avatar.plate.png").is_file()
    # motion transfer: the source (rendered at the pose model's 256 px) beside the avatar in the 64² target
    assert video_info(out / "motion" / "source.mp4").size == (256, 256)
    assert video_info(out / "motion" / "avatar.mp4").n_frames == 5
    moved = list(read_video(out / "motion" / "side_by_side.mp4"))
    assert len(moved) == 5 and moved[0].shape == (256, 512, 3)
    assert 0 < summary["motion_transfer"]["fit_pa_mpjpe_mm"] < 150  # a fit, not noise: a person's scale is ~1 m
    # capture: the generated person captured under one light, walking in the target beside the truth
    cap = list(read_video(out / "capture" / "side_by_side.mp4"))
    assert len(cap) == 5 and cap[0].shape == (256, 768, 3)
    assert 0.3 < summary["capture"]["capture_seen_share"] <= 1 and summary["capture"]["capture_albedo_error"] < 1
    assert summary["capture"]["capture_psnr_db"] > 15
    report = (out / "compare" / "report.md").read_text()
    assert "| 3D | true L_t |" in report and video_info(out / "compare" / "side_by_side.mp4").n_frames == 4
