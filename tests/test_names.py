"""relightnet.names: every name listed there is implemented where it is used, and the module stays torch-free."""

import subprocess
import sys

import torch

from relightnet import names


def test_every_listed_name_is_implemented():
    from relightnet.body.anny_model import POSE_PRESETS, pose_preset
    from relightnet.body.motion import make_motion
    from relightnet.model.onnx_export import make_smoother
    from relightnet.sh import load_light
    from relightnet.temporal import smoothing_matrix

    assert tuple(POSE_PRESETS) == names.POSE_PRESETS  # the rotations exist for exactly the listed poses
    assert all(isinstance(pose_preset(p), dict) for p in names.POSE_PRESETS)
    for kind in names.MOTION_KINDS:
        assert isinstance(make_motion(kind, 2, fps=10), dict)
    for method in names.OFFLINE_METHODS:
        assert smoothing_matrix(12, method).shape == (12, 12)
    for name in names.ONNX_SMOOTHERS:
        assert isinstance(make_smoother(name), torch.nn.Module)
    assert names.light_presets() and all(load_light(p).shape == (9, 3) for p in names.light_presets()[:2])


def test_lists_agree_with_the_library():
    from relightnet.model.onnx_export import SMOOTHERS
    from relightnet.segment.sources import MASK_SOURCES, check_mask_source
    from relightnet.sh.presets import preset_names
    from relightnet.temporal.registry import SMOOTHING_METHODS, smoothing_names
    from relightnet.temporal.smoothers import METHODS

    assert (SMOOTHERS, MASK_SOURCES, METHODS) == (names.ONNX_SMOOTHERS, names.MASK_SOURCES, names.OFFLINE_METHODS)
    assert preset_names() == names.light_presets() == sorted(p.stem for p in names.envmap_dir().glob("*.exr"))
    assert [check_mask_source(s) for s in names.MASK_SOURCES] == list(names.MASK_SOURCES)
    # the smoothing lists are the registry's methods, split by where they run
    assert set(names.VIDEO_SMOOTHING) == {"auto", *SMOOTHING_METHODS}
    assert set(names.STREAMING_SMOOTHING) == {"auto", *smoothing_names(causal=True)}
    assert set(names.SEQUENCE_SMOOTHING) == set(smoothing_names(evidence=False))
    assert set(names.OFFLINE_METHODS) == set(smoothing_names(causal=False))


def test_importing_names_and_the_cli_parser_does_not_import_torch():
    code = ("import sys, relightnet.names, relightnet.cli; relightnet.cli.build_parser(); "
            "print('torch' in sys.modules, 'numpy' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.split() == ["False", "False"]
