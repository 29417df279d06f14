"""``relightnet blender-export`` and ``relightnet blender-render`` end to end."""

import json

import pytest

from relightnet.cli import main
from relightnet.io import read_envmap, read_image


def test_export_then_render(tmp_path):
    blend = tmp_path / "walk.blend"
    assert main(["-q", "blender-export", "--motion", "walk", "--frames", "2", "--fps", "25", "--light", "studio",
                 "--band-limit", "--negative", "lift", "--world-res", "16", "--res", "32", "--camera", "fit",
                 "--spp", "4", "--bounces", "1", "--out", str(blend)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.blend"]
    from relightnet.blender.cycles import open_blend

    scene = open_blend(blend)
    meta = json.loads(scene["relightnet"])
    assert meta["frames"] == 2 and meta["light_kind"] == "sh" and meta["light_negative_fraction"] < 1e-6
    assert (scene.cycles.samples, scene.cycles.max_bounces, scene.render.fps) == (4, 1, 25)
    out = tmp_path / "frames"
    assert main(["-q", "blender-render", str(blend), "--frames", "1:2", "--bounces", "0", "--exposure", "3",
                 "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["frame_00001.exr", "frame_00001.png"]
    exr, png = read_envmap(out / "frame_00001.exr"), read_image(out / "frame_00001.png")
    assert exr.shape == png.shape == (32, 32, 3) and exr.max() > 0


def test_bad_inputs_fail_in_one_line_and_leave_nothing(tmp_path, capsys):
    out = str(tmp_path / "a.blend")
    cases = [
        (["--pose", "apose", "--light", "no_such_light"], "no_such_light"),
        (["--pose", "apose", "--light", "studio", "--albedo", str(tmp_path / "skin.png")], "texture file not found"),
        (["--motion", "moonwalk", "--light", "studio"], "moonwalk"),
        (["--motion", "clip.npz", "--light", "studio"], "SMPL-style motion files drive an SMPL body"),
    ]
    for args, msg in cases:
        assert main(["-q", "blender-export", *args, "--out", out]) == 1
        err = capsys.readouterr().err
        assert msg in err and len(err.strip().splitlines()) == 1, err
    assert main(["-q", "blender-export", "--light", "studio", "--out", str(tmp_path / "a.png")]) == 1
    assert ".blend" in capsys.readouterr().err
    assert main(["-q", "blender-render", str(tmp_path / "none.blend"), "--out", str(tmp_path / "o")]) == 1
    assert "no such .blend" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["blender-render", "x.blend", "--frames", "a:b", "--out", "o"])
    capsys.readouterr()
    with pytest.raises(SystemExit):  # pose presets are the option's choices (listed in --help)
        main(["-q", "blender-export", "--pose", "superman", "--light", "studio", "--out", out])
    assert "invalid choice: 'superman'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
