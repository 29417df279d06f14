import json
import math
import shutil

import numpy as np
import pytest
import torch

from relightnet.checks import InputError
from relightnet.cli import main
from relightnet.data import SynthConfig, load_manifest, read_shard, run_synth
from relightnet.data.render_sample import clip_geometry
from relightnet.data.shards import dataset_config
from relightnet.io import read_image, read_video, video_info
from relightnet.model import NetConfig, RelightNet, load_model, save_checkpoint
from relightnet.pipeline.compare import CLIP_FIELDS, LIGHTS, PATHS, ClipOutputs, clip_metrics, compare, compare_clip
from relightnet.pipeline.compare_report import json_safe
from relightnet.raster import rasterize

T = 3
RES = 32


@pytest.fixture(scope="module")
def seq_dir(tmp_path_factory, anny_body):
    """2 test clips of 3 frames at 32², one clip per shard."""
    out = tmp_path_factory.mktemp("seq") / "clips"
    cfg = SynthConfig(seed=4, res=RES, n_dirs=16, shard_size=1, counts={"train": 0, "val": 0, "test": 2},
                      sequence_frames=T)
    run_synth(out, cfg, workers=0, progress=False, body=anny_body)
    return out


@pytest.fixture(scope="module")
def clip0(seq_dir, anny_body):
    cfg = dataset_config(load_manifest(seq_dir))
    a = read_shard(seq_dir / "test-00000.npz")
    n = torch.get_num_threads()
    torch.set_num_threads(1)  # as the generator ran
    try:
        geo = clip_geometry(cfg, "test", 0, T, anny_body)
    finally:
        torch.set_num_threads(n)
    return cfg, a["meta"][0], {k: a[k][0] for k in CLIP_FIELDS}, geo


@pytest.fixture(scope="module")
def model():
    return load_model()


def _no_leftovers(parent, name):
    return not (parent / name).exists() and not list(parent.glob(f".{name}.*"))


def test_clip_geometry_reproduces_the_generated_clip(clip0, anny_body):
    cfg, meta, clip, geo = clip0
    assert geo.verts.shape[0] == T and geo.verts.shape == geo.normals.shape
    for t in range(T):
        fr = rasterize(geo.camera.transform(geo.verts[t]), geo.faces, geo.camera.size)
        np.testing.assert_array_equal(fr.mask[0].float().numpy(), clip["mask"][t])
    # A still's geometry is a single frame.
    assert clip_geometry(cfg, "test", 0, None, anny_body).verts.shape[0] == 1
    with pytest.raises(InputError, match="n_frames"):
        clip_geometry(cfg, "test", 0, 0)


def test_3d_path_with_the_truths_prt_reproduces_the_ground_truth(clip0, model):
    # With the ground truth's own directions (count and seed), the 3D path is the generator's renderer.
    _, meta, clip, geo = clip0
    out = compare_clip(model, clip, geo, n_dirs=meta["prt"]["n_dirs"], prt_seed=meta["prt"]["direction_seed"])
    np.testing.assert_array_equal(out.alpha_3d.numpy(), clip["mask"])
    np.testing.assert_allclose(out.renders[("3d", "true")].numpy(), clip["image"], atol=1e-5, rtol=0)
    # With other directions it differs only by quadrature noise.
    other = compare_clip(model, clip, geo, n_dirs=64, prt_seed=0, smoothing="none")
    m = clip["mask"] > 0
    d = np.abs(other.renders[("3d", "true")].numpy() - clip["image"])[m]
    assert 0 < d.mean() < 0.03


def test_compare_clip_outputs(clip0, model):
    _, _, clip, geo = clip0
    ticks = []
    out = compare_clip(model, clip, geo, n_dirs=16, smoothing="none", tick=lambda: ticks.append(1))
    assert len(ticks) == T
    assert set(out.renders) == {(p, n) for p in PATHS for n in LIGHTS}
    m = clip["mask"] > 0
    for (path, _), r in out.renders.items():
        assert r.shape == (T, RES, RES, 3) and torch.isfinite(r).all()
        assert (r.numpy()[~m] == 0).all(), path  # both paths are 0 off the person
    torch.testing.assert_close(out.lights["true"], torch.from_numpy(clip["light"]))
    assert out.lights["raw"].shape == (T, 9, 3)
    assert torch.equal(out.lights["smoothed"], out.lights["raw"]) and not out.outliers.any()
    torch.testing.assert_close(out.renders[("2d", "smoothed")], out.renders[("2d", "raw")])
    # The 2D path's input is the subject under the fixed source light: albedo ⊙ (T · L_src).
    from relightnet.pipeline.compare import source_light

    src = np.einsum("thwk,kc->thwc", clip["transport"], source_light("studio").numpy()) * clip["albedo"]
    np.testing.assert_allclose(out.source.numpy(), src, atol=1e-5)
    # The video frames: target frame | 2D | 3D | ground truth over the clip's background.
    from relightnet.io import to_uint8
    from relightnet.pipeline.compare_report import side_by_side

    frames = side_by_side(clip, out)
    assert frames.shape == (T, RES, 4 * RES, 3) and frames.dtype == np.uint8
    np.testing.assert_array_equal(frames[:, :, :RES], clip["image_composite"])
    mk = clip["mask"][..., None]
    for t in range(T):
        gt_panel = to_uint8(torch.from_numpy(clip["image"][t] * mk[t] + clip["background"][t] * (1 - mk[t])))
        np.testing.assert_array_equal(frames[t, :, 3 * RES:], gt_panel.numpy())
    # The Hermite smoother returns a sequence of the same shape.
    sm = compare_clip(model, clip, geo, n_dirs=16, smoothing="hermite")
    assert sm.lights["smoothed"].shape == (T, 9, 3) and torch.isfinite(sm.lights["smoothed"]).all()
    # The 2D path relights the photo's albedo by default; cnn_albedo relights the CNN's. The 3D path
    # does not change.
    cnn = compare_clip(model, clip, geo, n_dirs=16, smoothing="none", cnn_albedo=True)
    torch.testing.assert_close(cnn.renders[("3d", "true")], out.renders[("3d", "true")])
    assert not torch.allclose(cnn.renders[("2d", "true")], out.renders[("2d", "true")])


def test_clip_metrics_are_exact_for_a_perfect_output(clip0):
    _, _, clip, _ = clip0
    gt = torch.from_numpy(clip["image"])
    mask = torch.from_numpy(clip["mask"])
    light = torch.from_numpy(clip["light"])
    renders = {(p, n): gt.clone() for p in PATHS for n in LIGHTS}
    renders[("3d", "raw")] = gt + 0.5 * mask[..., None]  # a known error (after clipping and sRGB encoding)
    no = torch.zeros(T, dtype=torch.bool)
    out = ClipOutputs({"true": light, "raw": light * 1.1, "smoothed": light.clone()}, renders, mask, gt, no, no)
    rec = clip_metrics(out, gt, mask)
    rows = {(r["path"], r["light"]): r for r in rec["rows"]}
    assert len(rows) == 6
    r = rows[("2d", "true")]
    assert r["rmse"] == 0 and math.isinf(r["psnr"]) and r["ssim"] == 1 and r["temporal"] == 0
    assert len(r["per_frame"]["rmse"]) == T and len(r["per_frame"]["temporal"]) == T - 1
    from relightnet.io import linear_to_srgb

    err = linear_to_srgb((gt + 0.5).clamp(0, 1)) - linear_to_srgb(gt.clamp(0, 1))
    per_frame = [math.sqrt(float((err[t][mask[t] > 0] ** 2).mean())) for t in range(T)]
    assert rows[("3d", "raw")]["per_frame"]["rmse"] == pytest.approx(per_frame, rel=1e-5)
    assert rows[("3d", "raw")]["rmse"] == pytest.approx(np.mean(per_frame), rel=1e-5)
    assert rec["light"]["smoothed"]["error"] == 0 and rec["light"]["raw"]["error"] > 0
    assert rec["light"]["raw"]["relative"] == pytest.approx(0.1, rel=1e-6)
    assert rec["light"]["true"]["jitter"] >= 0 and rec["mask_iou_3d"] == 1.0
    # JSON: +inf is written as the string "inf" (strict JSON, no Infinity token).
    text = json.dumps(json_safe(rec), allow_nan=False)
    assert json.loads(text)["rows"][0]["psnr"] == "inf" and float("inf") == float(json.loads(text)["rows"][0]["psnr"])


def test_command_writes_the_report(seq_dir, tmp_path):
    out = tmp_path / "report"
    assert main(["-q", "compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "16"]) == 0
    text = (out / "report.md").read_text()
    assert "| 3D | smoothed L̃_t |" in text and "| 2D | true L_t |" in text and "relightnet_small.pt" in text
    m = json.loads((out / "metrics.json").read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert len(m["summary"]["rows"]) == 6 and m["settings"]["clips"] == [0, 1] and len(m["clips"]) == 2
    assert m["settings"]["albedo_2d"] == "photo" and "the photo's albedo" in text
    for c in m["clips"]:
        assert len(c["rows"]) == 6 and all(len(r["per_frame"]["ssim"]) == T for r in c["rows"])
        assert c["mask_iou_3d"] == 1.0 and len(c["light"]["raw"]["per_frame"]) == T
    for r in m["summary"]["rows"]:
        assert 0 < r["rmse"] < 0.5 and 0 < r["ssim"] <= 1 and r["temporal"] >= 0
    for name in ("errors", "light_error", "clip00000_errors", "clip00000_light", "clip00001_light"):
        assert read_image(out / "plots" / f"{name}.png").shape[-1] == 3
    info = video_info(out / "side_by_side.mp4")
    frames = list(read_video(out / "side_by_side.mp4"))
    assert len(frames) == 2 * T and frames[0].shape == (RES, 4 * RES, 3) and info.size == (RES, 4 * RES)
    lights = np.load(out / "lights.npz")
    assert lights["clip1_smoothed"].shape == (T, 9, 3) and lights["clip0_outliers"].dtype == bool
    assert not list(tmp_path.glob(".report.*"))  # the staging folder is gone

    # Another checkpoint (a fresh tiny network) at another working size, one clip, no smoothing: same files.
    ckpt = tmp_path / "tiny.pt"
    cfg = NetConfig(width=8, max_width=16, levels=2, light_hidden=16)
    save_checkpoint(ckpt, RelightNet(cfg).eval(), cfg)
    assert main(["-q", "compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "8", "--checkpoint",
                 str(ckpt), "--clips", "1", "--smoothing", "none", "--size", "32"]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["settings"]["clips"] == [0] and m["settings"]["checkpoint"] == str(ckpt)
    assert m["settings"]["size"] == 32 and m["settings"]["smoothing"] == "none"
    assert len(list(read_video(out / "side_by_side.mp4"))) == T
    assert not (out / "plots" / "clip00001_light.png").exists()  # the earlier run's clip plots are dropped


def test_bad_inputs_write_nothing(seq_dir, tiny_dataset, tmp_path, capsys):
    out = tmp_path / "rep"

    def fails(args, words):
        assert main(["compare", "--out", str(out), "--n-dirs", "8", *args]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err, err
        assert _no_leftovers(tmp_path, "rep")

    fails(["--data", str(tmp_path / "nope")], "nope: not found (expected a dataset folder of clips")
    fails(["--data", str(tiny_dataset)], "still samples")
    fails(["--data", str(seq_dir), "--split", "val"], "has no clips")
    bad = tmp_path / "bad.pt"
    bad.write_text("not a checkpoint")
    fails(["--data", str(seq_dir), "--checkpoint", str(bad)], "unreadable checkpoint")
    fails(["--data", str(seq_dir), "--checkpoint", str(tmp_path / "missing.pt")], "checkpoint not found")
    fails(["--data", str(seq_dir), "--source-light", "moon"], "preset")
    with pytest.raises(SystemExit):  # refused by the option parser, before anything runs
        main(["compare", "--out", str(out), "--data", str(seq_dir), "--size", "40"])
    assert "multiple of 16" in capsys.readouterr().err and _no_leftovers(tmp_path, "rep")
    out.write_text("a file")
    assert main(["compare", "--data", str(seq_dir), "--out", str(out)]) == 1
    assert "rep: is a file; expected a folder" in capsys.readouterr().err and out.read_text() == "a file"
    out.unlink()
    with pytest.raises(InputError, match="smoothing"):
        compare(seq_dir, out, smoothing="kalman")
    with pytest.raises(InputError, match="n_dirs"):
        compare(seq_dir, out, n_dirs=0)
    assert _no_leftovers(tmp_path, "rep")


def test_failure_mid_run_leaves_nothing(seq_dir, tmp_path, anny_body):
    # The second clip's shard is corrupt: the first clip is done by then, yet nothing may remain.
    data = tmp_path / "clips"
    shutil.copytree(seq_dir, data)
    (data / "test-00001.npz").write_bytes(b"PK\x03\x04 truncated")
    out = tmp_path / "deep" / "rep"
    with pytest.raises(InputError, match="test-00001.npz"):
        compare(data, out, n_dirs=8, progress=False, body=anny_body)
    assert not (tmp_path / "deep").exists() and not list(tmp_path.glob(".rep.*"))


def test_onnx_backend_matches_torch(seq_dir, tmp_path, anny_body):
    from relightnet.model.onnx_export import export_onnx

    torch.manual_seed(0)
    cfg = NetConfig(width=8, max_width=16, levels=2, light_hidden=16)
    net = RelightNet(cfg).eval()
    save_checkpoint(tmp_path / "tiny.pt", net, cfg)
    export_onnx(net, tmp_path / "tiny.onnx", smoothing="none", example_size=32)
    kw = dict(clips=1, n_dirs=8, size=32, progress=False, body=anny_body)
    a = compare(seq_dir, tmp_path / "torch", checkpoint=tmp_path / "tiny.pt", **kw).metrics
    b = compare(seq_dir, tmp_path / "onnx", checkpoint=tmp_path / "tiny.onnx", backend="onnx", **kw).metrics
    assert b["settings"]["backend"] == "onnx" and b["settings"]["size"] == 32
    la, lb = a["clips"][0]["light"], b["clips"][0]["light"]
    assert lb["raw"]["per_frame"] == pytest.approx(la["raw"]["per_frame"], rel=1e-3, abs=1e-5)
    for ra, rb in zip(a["summary"]["rows"], b["summary"]["rows"], strict=True):
        assert rb["rmse"] == pytest.approx(ra["rmse"], rel=1e-3, abs=1e-5), (ra["path"], ra["light"])
    with pytest.raises(InputError, match="backend"):
        compare(seq_dir, tmp_path / "x", backend="tensorrt", **kw)
    with pytest.raises(InputError, match="needs --backend onnx"):
        compare(seq_dir, tmp_path / "x", checkpoint=tmp_path / "tiny.onnx", **kw)
    assert _no_leftovers(tmp_path, "x")


def test_killed_compare_leaves_no_staging_folder_after_a_rerun(seq_dir, tmp_path, kill_mid_run):
    from .conftest import temp_files

    out = tmp_path / "report"
    argv = ["compare", "--data", str(seq_dir), "--out", str(out), "--n-dirs", "8"]
    # SIGKILL once the report is being staged (its staging folder holds a file).
    left = kill_mid_run(argv, tmp_path, ready=lambda temps: any(p.is_dir() and any(p.rglob("*")) for p in temps))
    assert left and not (out / "metrics.json").exists()
    assert main(["-q", *argv]) == 0
    assert temp_files(tmp_path) == [] and len(json.loads((out / "metrics.json").read_text())["clips"]) == 2
