"""Run the fuzz corpus through relightnet's readers in this process; one JSON line per reader.

    python tests/fuzz/runner.py WORKDIR [READER ...] [--cases N] [--seed S]

Every case must end in a normal return or ``InputError``; anything else is recorded with its
input (kept under WORKDIR/failures). A watchdog (``faulthandler``) ends the process when one
case runs longer than ``--timeout`` seconds, so a hang in C code is caught too; the case that
was running is the last ``START`` line of WORKDIR/progress.txt. Pickle payloads try to create
files in WORKDIR/markers: any file there counts as an executed payload.
"""

from __future__ import annotations

import argparse
import faulthandler
import json
import random
import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import corpus_data as cd  # noqa: E402
import corpus_media as cm  # noqa: E402
import mutations  # noqa: E402
import payloads  # noqa: E402


def _video(path):
    from relightnet.io import read_video, video_info

    video_info(path)
    for _ in read_video(path):
        pass


def _manifest(path):
    from relightnet.data import SynthDataset
    from relightnet.data.shards import verify_dataset

    verify_dataset(path.parent)
    ds = SynthDataset(path.parent, "test", fields=("image", "light"))
    for i in range(len(ds)):
        ds[i]


def _onnx(path):
    import numpy as np

    from relightnet.model.onnx_serving import OnnxRelighter

    r = OnnxRelighter(path)
    r.step(np.zeros((1, 3, 16, 16), np.float32), np.ones((1, 1, 16, 16), np.float32))


def readers(tmp: Path) -> dict:
    """name → (suffix, seeds {suffix: bytes}, structured case generator, read function, payload kind)."""
    from relightnet.body import load_motion
    from relightnet.body.smpl_model import load_smpl_file
    from relightnet.data import load_config
    from relightnet.data.shards import read_shard
    from relightnet.io import read_envmap, read_image_alpha, read_mask
    from relightnet.light import load_light
    from relightnet.model import load_model
    from relightnet.model.train_config import load_train_config

    light = cd.light_seeds()
    smpl = cd.smpl_arrays()
    media, video, env = cm.image_seeds(tmp), cm.video_seeds(tmp), cm.envmap_seeds(tmp)
    ckpt = cm.checkpoint_state()
    synth_yaml = "\n".join(f"{k}: {json.dumps(v)}" for k, v in cd.TINY.items()).encode()
    return {
        "light-npz": (".npz", {".npz": light[".npz"]}, cd.light_npz_cases, load_light, None),
        "light-json": (".json", {".json": light[".json"]}, cd.light_json_cases, load_light, None),
        "light-npy": (".npy", {".npy": light[".npy"]}, cd.light_npy_cases, load_light, None),
        "light-exr": (".exr", {".exr": env[".exr"]}, lambda r: cm.envmap_cases(r, env), load_light, None),
        "light-hdr": (".hdr", {".hdr": env[".hdr"]}, lambda r: cm.envmap_cases(r, env), read_envmap, None),
        "motion-npz": (".npz", {".npz": cd.npz_bytes(cd.motion_arrays())}, cd.motion_npz_cases, load_motion, None),
        "motion-pkl": (".pkl", {".pkl": __import__("pickle").dumps(cd.motion_arrays())}, cd.motion_pkl_cases,
                       load_motion, "pickle"),
        "smpl-npz": (".npz", {".npz": cd.npz_bytes(smpl)}, lambda r: cd.smpl_npz_cases(r, smpl), load_smpl_file,
                     None),
        "smpl-pkl": (".pkl", {".pkl": __import__("pickle").dumps(smpl)}, lambda r: cd.smpl_pkl_cases(r, smpl),
                     load_smpl_file, "pickle"),
        "image": (".png", media, cm.image_cases, read_image_alpha, None),
        "mask": (".png", {".png": media[".png"]}, cm.image_cases, read_mask, None),
        "video": (".mp4", video, lambda r: cm.video_cases(r, video), _video, None),
        "synth-config": (".yaml", {".yaml": synth_yaml}, lambda r: cd.yaml_cases(r, cd.SYNTH_KEYS), load_config,
                         None),
        "train-config": (".yaml", {".yaml": b"steps: 10\nbatch_size: 2\nnet: {width: 8}\n"},
                         lambda r: cd.yaml_cases(r, cd.TRAIN_KEYS), load_train_config, None),
        "shard": (".npz", {".npz": cd.npz_bytes(cd.shard_arrays())}, cd.shard_cases, read_shard, None),
        "manifest": (".json", {".json": json.dumps(cd.manifest_doc()).encode()}, cd.manifest_cases, _manifest,
                     None),
        "checkpoint": (".pt", {".pt": cm._torch_bytes(ckpt)}, lambda r: cm.checkpoint_cases(r, ckpt), load_model,
                       "torch"),
        "onnx": (".onnx", {".onnx": cm.onnx_seed()}, cm.onnx_cases, _onnx, None),
    }


def _cases(name: str, spec, n: int, seed: int, others: list[bytes]):
    suffix, seeds, structured, _, payload_kind = spec
    r = random.Random(f"{seed}:{name}")
    for i in range(n):
        if i % 10 == 9:
            yield i, "wrong-format", suffix, r.choice(others)
        elif i % 2 == 0:
            kind, data = next(iter(structured(r)))
            yield i, kind, suffix, data
        else:
            s = r.choice(sorted(seeds))
            kind, data = mutations.mutate(seeds[s], r.randrange(1 << 30))
            yield i, f"{kind}{s}", suffix if r.random() < 0.8 else s, data
    if payload_kind:
        for j, (kind, data) in enumerate(payloads.payloads(payload_kind)):
            yield n + j, f"payload:{kind}", suffix, data


def run_reader(name: str, spec, n: int, seed: int, work: Path, others, timeout: float, progress) -> dict:
    from relightnet.checks import InputError

    read = spec[3]
    case_dir, markers, failures = work / "case" / name, work / "markers", work / "failures"
    case_dir.mkdir(parents=True, exist_ok=True)
    markers.mkdir(exist_ok=True)
    payloads.MARKERS = markers
    res = {"reader": name, "cases": 0, "ok": 0, "input_error": 0, "failures": [], "payloads": 0, "executed": 0}
    shard = cd.npz_bytes(cd.shard_arrays()) if name == "manifest" else None
    t0 = time.perf_counter()
    for i, kind, suffix, data in _cases(name, spec, n, seed, others):
        path = case_dir / f"case{suffix}" if name != "manifest" else case_dir / "manifest.json"
        if shard is not None:  # a dataset folder: the manifest under test and one valid shard
            (case_dir / "test-00000.npz").write_bytes(shard)
        path.write_bytes(data)
        progress.write(f"START {name} {i} {kind}\n")
        progress.flush()
        faulthandler.dump_traceback_later(timeout, exit=True)
        try:
            read(path)
            res["ok"] += 1
        except InputError:
            res["input_error"] += 1
        except Exception as e:  # noqa: BLE001 - exactly what the fuzzing looks for
            keep = failures / f"{name}-{i}{suffix}"
            keep.parent.mkdir(exist_ok=True)
            keep.write_bytes(data)
            frames = traceback.extract_tb(e.__traceback__)
            where = [f"{fr.filename.split('relightnet/')[-1]}:{fr.lineno}" for fr in frames
                     if "/relightnet/" in fr.filename][-1:]
            res["failures"].append({"case": i, "kind": kind, "error": f"{type(e).__name__}: {str(e)[:160]}",
                                    "where": where, "file": str(keep)})
        finally:
            faulthandler.cancel_dump_traceback_later()
        res["cases"] += 1
        if kind.startswith("payload:"):
            res["payloads"] += 1
            made = list(markers.iterdir())
            res["executed"] += bool(made)
            for m in made:
                m.unlink()
    res["seconds"] = round(time.perf_counter() - t0, 2)
    return res


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("work", type=Path)
    ap.add_argument("names", nargs="*")
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    import logging
    import warnings

    logging.disable(logging.CRITICAL)
    warnings.simplefilter("ignore")
    args.work.mkdir(parents=True, exist_ok=True)
    specs = readers(args.work)
    names = args.names or list(specs)
    others = [b for spec in specs.values() for b in spec[1].values()]
    with open(args.work / "progress.txt", "a") as progress, open(args.work / "results.jsonl", "a") as out:
        for name in names:
            res = run_reader(name, specs[name], args.cases, args.seed, args.work, others, args.timeout, progress)
            out.write(json.dumps(res) + "\n")
            out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
