"""Fuzz corpus, data readers: light files, motion and SMPL files, configs, dataset shards and manifest.

Each reader has seeds (valid files made here) and structured cases (valid containers with
wrong shapes, dtypes, values, types), all from a seeded ``random.Random``; the runner adds
byte mutations of the seeds and files of other formats under this reader's name.
"""

from __future__ import annotations

import io
import json
import pickle
import random

import numpy as np

DTYPES = ("bool", "int8", "uint16", "int64", "float16", "float32", ">f8", "complex64", "U4", "S3")
SHAPES = ((), (0,), (3,), (9,), (9, 3), (4, 3), (9, 4), (2, 9, 3), (0, 9, 3), (10, 3), (1, 1, 1, 1), (3, 0))
ODD = (None, True, -1, 0, 2.5, float("nan"), float("inf"), 10**30, "x", "", [1, 2], {"a": 1}, [[1]], -(2**63))


def rand_array(r: random.Random, shape=None, dtype=None) -> np.ndarray:
    shape = r.choice(SHAPES) if shape is None else shape
    dtype = np.dtype(r.choice(DTYPES) if dtype is None else dtype)
    if dtype.kind in "US":
        return np.full(shape, "ab", dtype=dtype)
    a = np.asarray(np.random.default_rng(r.randrange(1 << 30)).normal(size=shape) * r.choice([1, 1e3, 1e30]))
    if a.size and dtype.kind == "f" and r.random() < 0.3:
        a.flat[r.randrange(a.size)] = r.choice([np.nan, np.inf, -np.inf])
    with np.errstate(all="ignore"):
        return a.astype(dtype)


def npz_bytes(arrays: dict) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def npy_bytes(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    return buf.getvalue()


def npy_lying_header(r: random.Random) -> bytes:
    """A .npy whose header claims a huge or odd array over a few bytes of data."""
    shape = r.choice([(10**12, 3), (9, 3 * 10**9), (2**62,), (9, 3), (-1, 3), (9,)])
    descr = r.choice(["<f8", "|O", "<f4", "|V8", "<U99999999", "<c16", "x"])
    order = r.choice(["False", "True", "1"])
    header = f"{{'descr': {descr!r}, 'fortran_order': {order}, 'shape': {shape!r}, }}"
    header = header.ljust(118) + "\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + bytes(r.randrange(300))


# --- light ------------------------------------------------------------------------------------------------------

def light_seeds() -> dict[str, bytes]:
    sh = np.random.default_rng(0).normal(size=(9, 3)).astype(np.float32)
    out = {".npz": npz_bytes({"sh": sh, "lmax": np.int64(2), "frame": np.str_("light"),
                              "units": np.str_("linear radiance")}),
           ".npy": npy_bytes(sh[:, ::-1].copy()),
           ".json": json.dumps({"lmax": 2, "frame": "light", "units": "linear radiance",
                                "sh": sh.tolist()}).encode()}
    return out


def light_npz_cases(r: random.Random):
    d = {"sh": rand_array(r)}
    for k in ("lmax", "frame", "units"):
        if r.random() < 0.5:
            d[k] = np.asarray(r.choice([2, -1, 10**18, "light", "camera", 2.5, np.nan]) if r.random() < 0.8
                              else rand_array(r))
    if r.random() < 0.1:
        d = {"other": d["sh"]}
    yield "arrays", npz_bytes(d)


def light_npy_cases(r: random.Random):
    if r.random() < 0.5:
        yield "array", npy_bytes(rand_array(r, shape=r.choice([(9, 3), (9, 3), (3, 9), (9,), (27,)])))
    else:
        yield "lying-header", npy_lying_header(r)


def light_json_cases(r: random.Random):
    k = r.choice([1, 4, 9, 8, 0])
    sh = [[r.choice([0.5, 1, -2e308 * 10, "1", None, [1], True, 1e400]) if r.random() < 0.1 else 0.5
           for _ in range(r.choice([3, 3, 2]))] for _ in range(k)]
    doc = {"sh": sh if r.random() < 0.8 else r.choice(ODD)}
    for key in ("lmax", "frame", "units"):
        if r.random() < 0.5:
            doc[key] = r.choice(ODD + (2, "light", "linear radiance"))
    text = json.dumps(doc if r.random() < 0.9 else r.choice([[1, 2], "sh", None, 3]))
    choice = r.random()
    if choice < 0.08:
        text = "[" * 100000 + "]" * 100000  # nesting deeper than the parser's recursion limit
    elif choice < 0.15:
        text = '{"sh": ' + "[" * 5000 + "1" + "]" * 5000 + "}"
    elif choice < 0.2:
        text = '{"sh": NaN, "lmax": Infinity}'
    data = text.encode()
    if r.random() < 0.05:
        data = b"\xff\xfe" + data  # not UTF-8
    yield "json", data


# --- motion and SMPL ----------------------------------------------------------------------------------------------

def motion_arrays(T: int = 5) -> dict:
    g = np.random.default_rng(1)
    return {"poses": g.normal(size=(T, 72)).astype(np.float32) * 0.1, "betas": g.normal(size=10).astype(np.float32),
            "trans": g.normal(size=(T, 3)).astype(np.float32), "fps": np.float32(30)}


def _motion_variant(r: random.Random) -> dict:
    d = motion_arrays(r.choice([1, 5]))
    key = r.choice(["poses", "betas", "trans", "fps", "mocap_framerate", "camera_K", "drop", "extra"])
    if key == "drop":
        d.pop(r.choice(["poses", "betas", "trans"]))
    elif key == "extra":
        d["gender"] = np.str_("female")
    elif key in ("fps", "mocap_framerate"):
        d[key] = np.asarray(r.choice([0, -5, np.nan, np.inf, 1e300, "x", [30, 30]])) if r.random() < 0.7 \
            else rand_array(r)
    else:
        shape = r.choice([None, (5, 69), (5, 72), (0, 72), (10,), (5, 3), (3, 3), (6, 3), ()])
        d[key] = rand_array(r, shape=shape)
    return d


def motion_npz_cases(r: random.Random):
    yield "arrays", npz_bytes({k: np.asarray(v) for k, v in _motion_variant(r).items()})


def motion_pkl_cases(r: random.Random):
    d = _motion_variant(r)
    roll = r.random()
    if roll < 0.1:
        d = r.choice([[1, 2], None, 5, "poses", (d,)])
    elif roll < 0.2:
        d["camera"] = r.choice([{"K": np.eye(3)}, {"K": "x"}, {"K": np.full(3, np.nan)}, [1, 2], {1: np.eye(3)}])
    elif roll < 0.3:
        loop: list = []
        loop.append(loop)
        d["poses"] = loop
    elif roll < 0.35:
        d = {1: 2, (1, 2): 3, frozenset([1]): {4}}
    yield "pickle", pickle.dumps(d, protocol=r.choice([0, 2, 4, 5]))


def smpl_arrays(n_verts: int = 40) -> dict:
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "body"))
    from conftest import make_smpl_arrays

    return make_smpl_arrays(n_verts=n_verts)


def _smpl_variant(r: random.Random, base: dict) -> dict:
    d = dict(base)
    key = r.choice(list(d) + ["vt", "drop", "f-range", "parents"])
    if key == "drop":
        d.pop(r.choice(list(base)))
    elif key == "f-range":
        f = d["f"].astype(np.int64).copy()
        f.flat[r.randrange(f.size)] = r.choice([-1, 10**6, len(d["v_template"])])
        d["f"] = f
    elif key == "parents":
        kt = d["kintree_table"].astype(np.int64).copy()
        kt[0, r.randrange(1, kt.shape[1])] = r.choice([-5, 30, 23, kt.shape[1] + 3])
        d["kintree_table"] = kt
    elif key == "vt":
        d["vt"] = rand_array(r, shape=r.choice([(40, 2), (40, 3), (0, 2)]), dtype="float64")
        if r.random() < 0.7:
            d["ft"] = np.asarray(d["f"]).astype(np.int64) + r.choice([0, 0, 50])
    else:
        a = np.asarray(d[key])
        shape = r.choice([a.shape, a.shape[:-1], a.shape + (1,), (0,) + a.shape[1:], (1,), ()])
        d[key] = rand_array(r, shape=shape, dtype=r.choice(["float64", "float64", "int64", "U2", "bool"]))
    return d


def smpl_npz_cases(r: random.Random, base: dict):
    yield "arrays", npz_bytes(_smpl_variant(r, base))


def smpl_pkl_cases(r: random.Random, base: dict):
    import scipy.sparse as sp

    d = _smpl_variant(r, base)
    roll = r.random()
    if roll < 0.3 and isinstance(d.get("J_regressor"), np.ndarray) and d["J_regressor"].ndim == 2:
        m = sp.csc_matrix(d["J_regressor"])
        bad = r.choice(["indices", "indptr", "shape", "none"])
        if bad == "indices" and m.nnz:
            m.indices[r.randrange(m.nnz)] = r.choice([10**6, 2**31 - 1])
        elif bad == "indptr":
            m.indptr[r.randrange(len(m.indptr))] = r.choice([10**6, 0])
        elif bad == "shape":
            m._shape = r.choice([(10**9, 10**9), (24, 10), (-1, 5)])
        d["J_regressor"] = m
    yield "pickle", pickle.dumps(d, protocol=r.choice([2, 4, 5]))


# --- configs ------------------------------------------------------------------------------------------------------

SYNTH_KEYS = ("seed", "res", "lmax", "n_dirs", "shard_size", "counts", "hdri_train", "hdri_test",
              "synthetic_light_prob", "bounce_prob", "noise_std", "partial_crop_prob", "pad", "jitter", "ages",
              "sequence_frames")
TRAIN_KEYS = ("steps", "batch_size", "lr", "weight_decay", "warmup", "seed", "checkpoint_every", "log_every",
              "target", "render_target", "net", "loss", "augment", "threads", "init")
YAML_ODD = ("2001-02-30", "!!binary aGVsbG8=", "!!python/object:os.system ['x']", "&a [*a]", "0x1F", "1e400",
            ".nan", "-.inf", "~", "[1, [2, [3]]]", "{a: {b: {c: 1}}}", "'16'", "16", "100000000000000000000",
            "[night, sunrise]", "{train: 8, test: -1}", "{train: 10000000000000}", "[0.5, 0.2]", "yes")


def yaml_cases(r: random.Random, keys):
    lines = []
    for k in r.sample(keys, r.randint(1, 4)):
        lines.append(f"{k}: {r.choice(YAML_ODD)}")
    roll = r.random()
    if roll < 0.05:  # "billion laughs": aliases of aliases
        lines = ["l0: &l0 [x, x, x, x, x, x, x, x, x]"] + [
            f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 9)}]" for i in range(1, 9)]
    elif roll < 0.1:
        lines = ["[" * 3000 + "]" * 3000]
    elif roll < 0.15:
        lines = [r.choice(["- 1\n- 2", "just a string", "", "!!python/name:os.system", "{unknown_key: 1}"])]
    yield "yaml", "\n".join(lines).encode()


# --- dataset shards and manifest ------------------------------------------------------------------------------------

TINY = {"seed": 0, "res": 16, "lmax": 1, "n_dirs": 8, "shard_size": 2, "counts": {"train": 0, "val": 0, "test": 2},
        "hdri_train": ["city"], "hdri_test": ["night"], "synthetic_light_prob": 0.3, "bounce_prob": 0.0,
        "noise_std": 0.0, "partial_crop_prob": 0.1, "pad": 0.05, "jitter": 0.03, "ages": [0.6, 1.0],
        "sequence_frames": 0}


def shard_arrays(n: int = 2) -> dict:
    from relightnet.data.config import SynthConfig
    from relightnet.data.shards import expected_fields

    g = np.random.default_rng(2)
    out = {k: g.uniform(size=(n, *shape)).astype(dtype) for k, (shape, dtype) in
           expected_fields(SynthConfig.from_dict(TINY)).items()}
    out["meta"] = np.array([json.dumps({"seed": i}) for i in range(n)])
    return out


def shard_cases(r: random.Random):
    d = shard_arrays()
    key = r.choice(list(d) + ["meta-bad"])
    if key == "meta-bad":
        d["meta"] = r.choice([np.array("{}"), np.array(["{not json", "[]"]), np.array([1.0, 2.0]),
                              np.array(["[" * 5000 + "]" * 5000] * 2)])
    else:
        d[key] = rand_array(r)
    yield "arrays", npz_bytes(d)


def manifest_doc() -> dict:
    return {"format": "relightnet-synth/1", "generator_version": "x", "config": dict(TINY), "complete": True,
            "fields": {}, "splits": {"train": {"count": 0, "n_shards": 0, "shards": []},
                                     "val": {"count": 0, "n_shards": 0, "shards": []},
                                     "test": {"count": 2, "n_shards": 1, "shards": [
                                         {"file": "test-00000.npz", "index": 0, "start": 0, "count": 2,
                                          "sha256": "", "bytes": 0}]}}}


def _poke(doc, r: random.Random, depth: int = 0):
    """Replace one value somewhere in a JSON document by an odd one (or drop a key)."""
    if isinstance(doc, dict) and doc and (depth < 4 and r.random() < 0.6):
        k = r.choice(list(doc))
        if r.random() < 0.15:
            doc.pop(k)
        else:
            doc[k] = _poke(doc[k], r, depth + 1)
        return doc
    if isinstance(doc, list) and doc and r.random() < 0.6:
        i = r.randrange(len(doc))
        doc[i] = _poke(doc[i], r, depth + 1)
        return doc
    return r.choice(ODD + ("../../etc/passwd", "/etc/hosts", "test-00000.npz", 10**12, -3, [], {}))


def manifest_cases(r: random.Random):
    doc = manifest_doc()
    for _ in range(r.randint(1, 3)):
        doc = _poke(doc, r)
    text = json.dumps(doc, allow_nan=True) if r.random() < 0.95 else "[" * 100000
    yield "manifest", text.encode()
