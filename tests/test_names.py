"""relightnet.names: every name listed there is implemented where it is used, and the module stays torch-free."""

import subprocess
import sys

import torch

from relightnet import names


def test_every_listed_name_is_implemented():
    from relightnet.body.anny_model import POSE_PRESETS, pose_preset
    from relightnet.body.motion import make_motion
    from relightnet.light import load_light
    from relightnet.temporal import make_smoother, smooth_sequence, smoothing_matrix

    assert tuple(POSE_PRESETS) == names.POSE_PRESETS  # the rotations exist for exactly the listed poses
    assert all(isinstance(pose_preset(p), dict) for p in names.POSE_PRESETS)
    for kind in names.MOTION_KINDS:
        assert isinstance(make_motion(kind, 2, fps=10), dict)
    for method in names.OFFLINE_METHODS:
        assert smoothing_matrix(12, method).shape == (12, 12)
    lights = torch.rand(6, 9, 3)
    for name, method in names.SMOOTHING_METHODS.items():
        if method.causal:
            assert isinstance(make_smoother(name), torch.nn.Module)
        if not method.evidence:  # every method smooths a recorded sequence
            assert smooth_sequence(lights, name).smoothed.shape == lights.shape
    assert names.light_presets() and all(load_light(p).shape == (9, 3) for p in names.light_presets()[:2])


def test_lists_agree_with_the_library():
    from relightnet.light.presets import preset_names
    from relightnet.segment.sources import MASK_SOURCES, check_mask_source

    assert MASK_SOURCES == names.MASK_SOURCES
    assert preset_names() == names.light_presets() == sorted(p.stem for p in names.envmap_dir().glob("*.exr"))
    assert [check_mask_source(s) for s in names.MASK_SOURCES] == list(names.MASK_SOURCES)


def test_the_smoothing_lists_derive_from_the_one_table():
    table = names.SMOOTHING_METHODS
    assert names.VIDEO_SMOOTHING == ("auto", *table)
    assert names.STREAMING_SMOOTHING == ("auto", *(n for n, m in table.items() if m.causal))
    assert names.SEQUENCE_SMOOTHING == tuple(n for n, m in table.items() if not m.evidence)
    assert names.OFFLINE_METHODS == ("hermite", "poly", "savgol")
    assert names.smoothing_names(causal=True, evidence=True) == ("pooled",)


def test_every_smoothing_option_in_the_help_comes_from_the_table():
    from relightnet.cli import build_parser, command_table

    seen = {}
    for name, parser in command_table(build_parser()).items():
        for action in parser._actions:
            # segment's --smoothing is the mask tracker's weight (a number), not a light-smoothing method
            if "--smoothing" in action.option_strings and action.type is not float:
                seen[name] = action
    assert set(seen) >= {"avatar", "compare", "relight-video", "export", "smooth-light"}
    for name, action in seen.items():
        allowed = tuple(action.choices)
        assert allowed in (names.VIDEO_SMOOTHING, names.STREAMING_SMOOTHING, names.SEQUENCE_SMOOTHING), name
        assert action.help.startswith(names.smoothing_help(allowed, action.default).replace("%", "%%")), name


def test_importing_names_and_the_cli_parser_does_not_import_torch():
    code = ("import sys, relightnet.names, relightnet.cli; relightnet.cli.build_parser(); "
            "print('torch' in sys.modules, 'numpy' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.split() == ["False", "False"]
