"""The source video's sound carried over to the videos relightnet writes."""

import av
import numpy as np
import pytest

from relightnet.checks import InputError
from relightnet.io import VideoWriter, read_video
from relightnet.io.audio import add_audio, has_audio


def _audio_seconds(path):
    with av.open(str(path)) as c:
        return sum(f.samples for f in c.decode(audio=0)) / c.streams.audio[0].codec_context.sample_rate


@pytest.mark.parametrize(("acodec", "fmt", "src_name", "out_name", "codec_out"), [
    ("aac", "mp4", "in.mp4", "out.mp4", "aac"),                # copied as it is
    ("pcm_s16le", "matroska", "in.mkv", "out.mp4", "aac"),     # PCM is not for mp4: re-encoded
    ("pcm_s16le", "matroska", "in.mkv", "out.mkv", "pcm_s16le"),
])
def test_writer_carries_the_sound_over(tmp_path, clip_with_sound, acodec, fmt, src_name, out_name, codec_out):
    src = clip_with_sound(tmp_path / src_name, acodec, fmt)
    frames = list(read_video(src))
    out = tmp_path / out_name
    with VideoWriter(out, fps=10, audio_from=src) as w:
        for f in frames[:15]:  # a shorter video than the sound: the sound is cut to it
            w.write(255 - f)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([src_name, out_name])  # no leftovers
    with av.open(str(out)) as c:
        assert [s.type for s in c.streams] == ["video", "audio"]
        assert c.streams.audio[0].codec_context.name == codec_out
    back = list(read_video(out))
    assert len(back) == 15
    assert abs(int(back[3].mean()) - (255 - int(frames[3].mean()))) <= 3
    assert 1.3 <= _audio_seconds(out) <= 1.7


def test_silent_sources_and_errors(tmp_path):
    silent = tmp_path / "silent.mp4"
    with VideoWriter(silent, fps=10) as w:
        for _ in range(3):
            w.write(np.zeros((16, 16, 3), np.uint8))
    assert not has_audio(silent) and not has_audio(tmp_path / "missing.mp4")
    out = tmp_path / "out.mp4"
    with VideoWriter(out, fps=10, audio_from=silent) as w:  # nothing to carry: a plain video
        w.write(np.zeros((16, 16, 3), np.uint8))
    with av.open(str(out)) as c:
        assert not c.streams.audio
    with pytest.raises(InputError, match="no audio stream"):
        add_audio(out, silent, tmp_path / "x.mp4")
    assert not (tmp_path / "x.mp4").exists()
