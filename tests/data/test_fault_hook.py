"""relightnet.data.fault_hook: the test-only hook is off unless its variable is set, and names one shard."""

from relightnet.data.fault_hook import FAULT_ENV, fault_spec, faulty_tick


def test_the_hook_is_off_without_its_variable(monkeypatch):
    monkeypatch.delenv(FAULT_ENV, raising=False)
    assert fault_spec() is None
    monkeypatch.setenv(FAULT_ENV, "train-00001.npz")
    assert fault_spec() == "train-00001.npz"


def test_only_the_named_shard_is_touched(tmp_path):
    calls = []

    def tick():
        calls.append(1)

    assert faulty_tick("train-00001.npz", "train-00000.npz", tick) is tick
    marker = tmp_path / "died-once"
    marker.touch()  # the first attempt already died: the shard's ticks pass through
    wrapped = faulty_tick(f"train-00001.npz@{marker}", "train-00001.npz", tick)
    assert wrapped is not tick
    wrapped()
    assert calls == [1]
