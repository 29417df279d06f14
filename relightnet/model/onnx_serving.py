"""Serving the exported model with ONNX Runtime: ``OnnxRelighter`` and int8 quantisation.

``OnnxRelighter`` runs frames in order through one ``onnxruntime.InferenceSession``,
carrying the smoothing state between calls, and validates every input (name, shape, dtype)
before ONNX Runtime sees it, so mistakes give one clear line.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import torch

from ..checks import InputError, ShapeError, check_shape
from .onnx_export import EVIDENCE_OUTPUTS, INPUTS

logger = logging.getLogger(__name__)

__all__ = ["INT8_KEEP_FLOAT", "OnnxRelighter", "calibration_set", "quantize_int8", "run_video"]

#: The weights whose layers :func:`quantize_int8` leaves in float by default: regular expressions matched
#: in full against the name of a convolution's or matrix product's weight (the torch parameter names,
#: which every export keeps; node names change from one export to the next). They are the frozen
#: MediaPipe pose encoder's six convolutions before its first residual connection (its weights w1–w18:
#: the stem and two inverted-residual blocks, at 1/2 and 1/4 of the pose input's size). A per-layer
#: sweep on the shipped model found nearly all of int8's error there: with them in float the relit RMSE is
#: within 1% of fp32 instead of +9–17% (BENCHMARKS.md, "ONNX export and serving"), at a cost in time at small
#: sizes (two threads, 256²: 95.8 vs 75.6 ms with every layer in int8).
#: A model without a pose encoder has no such weight, and every layer is quantised.
INT8_KEEP_FLOAT = (r"net\.pose\.encoder\.params\.w(1|5|7|13|16|18)",)

_QUANTISED_OPS = ("Conv", "MatMul", "Gemm")


class OnnxRelighter:
    """A streaming relighter backed by an exported ``.onnx`` file.

    Args:
        path: the model from ``relightnet export``.
        threads: intra-op threads of the session (0: ONNX Runtime's default).

    Call :meth:`step` with one frame batch at a time; :meth:`reset` starts a new sequence.
    """

    def __init__(self, path, threads: int = 0) -> None:
        import onnxruntime as ort

        from .onnx_check import check_graph, load_graph

        self.path = Path(path)
        if not self.path.is_file():
            raise InputError(f"{self.path}: ONNX model not found")
        # The graph is checked before ONNX Runtime sees it (it folds constants when the session
        # is made): relightnet's inputs and outputs, every shape bounded at the working size.
        self._graph = load_graph(self.path)
        self._checked: set[tuple[int, int, int]] = set()
        self._check_graph = check_graph
        self._graph_shapes(1, self._meta_size(), self._meta_size())
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads
        opts.log_severity_level = 3
        try:
            self.session = ort.InferenceSession(str(self.path), opts, providers=["CPUExecutionProvider"])
        except Exception as e:  # truncated or not an ONNX file
            first = str(e).strip().splitlines()[0][:200] if str(e).strip() else type(e).__name__
            raise InputError(f"{self.path}: unreadable ONNX model ({first})") from None
        names = [i.name for i in self.session.get_inputs()]
        if names != list(INPUTS):
            raise InputError(f"{self.path}: not a relightnet model (inputs {names}, expected {list(INPUTS)})")
        meta = self.session.get_modelmeta().custom_metadata_map
        self.metadata = dict(meta)
        #: what the input's H and W must be multiples of (read once from the metadata: 16, or 32)
        self.multiple = self._meta_multiple()
        state = self.session.get_inputs()[2].shape  # [batch, S, K, 3]
        if len(state) != 4 or not all(isinstance(n, int) and 0 < n <= 4096 for n in state[1:]):
            raise InputError(f"{self.path}: not a relightnet model (light_state is {state}, expected "
                             "[batch, S, K, 3] with fixed S, K)")
        self.state_size, self.n_coeffs = state[1], state[2]
        outputs = [o.name for o in self.session.get_outputs()]
        #: the light solve's per-frame evidence outputs (solve/hybrid networks), else empty
        self.evidence_outputs = tuple(n for n in EVIDENCE_OUTPUTS if n in outputs)
        self._state: np.ndarray | None = None

    def _meta_size(self) -> int:
        from .network import DEFAULT_INPUT_SIZE

        meta = {p.key: p.value for p in self._graph.metadata_props}
        try:
            size = int(meta.get("relightnet.input_size", DEFAULT_INPUT_SIZE))
        except ValueError:
            raise InputError(f"{self.path}: metadata relightnet.input_size is not an integer") from None
        if not 16 <= size <= 4096 or size % 16:
            raise InputError(f"{self.path}: metadata relightnet.input_size {size} is not a multiple of 16 in 16..4096")
        return size

    def _graph_shapes(self, batch: int, height: int, width: int) -> None:
        """Check the graph's shapes at this input size once (:func:`~relightnet.model.onnx_check.check_graph`)."""
        if (batch, height, width) not in self._checked:
            self._check_graph(self._graph, self.path, batch, height, width)
            self._checked.add((batch, height, width))

    def _meta_multiple(self) -> int:
        """What the input's H and W must be multiples of: 16, or 32 for a network at half resolution
        (metadata ``relightnet.multiple``; 16 when absent, as in files exported before it existed)."""
        try:
            m = int(self.metadata.get("relightnet.multiple", 16))
        except ValueError:
            raise InputError(f"{self.path}: metadata relightnet.multiple is not an integer") from None
        if m not in (16, 32):
            raise InputError(f"{self.path}: metadata relightnet.multiple {m}: expected 16 or 32")
        return m

    @property
    def input_size(self) -> int:
        """The model's working size: the training size stored by the export (metadata
        ``relightnet.input_size``; :data:`~relightnet.model.network.DEFAULT_INPUT_SIZE` when absent)."""
        from .network import DEFAULT_INPUT_SIZE

        try:
            return int(self.metadata.get("relightnet.input_size", DEFAULT_INPUT_SIZE))
        except ValueError:
            raise InputError(f"{self.path}: metadata relightnet.input_size is not an integer") from None

    def reset(self) -> None:
        """Forget the smoothing state: the next frame starts a new sequence."""
        self._state = None

    def _check(self, image: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if not isinstance(image, np.ndarray) or image.dtype != np.float32:
            raise InputError(f"image: expected a float32 numpy array (sRGB in [0, 1]), got "
                             f"{getattr(image, 'dtype', type(image).__name__)}")
        if image.ndim != 4 or image.shape[1] != 3:
            raise ShapeError(f"image: expected (B, 3, H, W), got {tuple(image.shape)}")
        b, _, h, w = image.shape
        if h % self.multiple or w % self.multiple:
            raise ShapeError(f"image: H and W must be multiples of {self.multiple}, got ({h}, {w})")
        mask = np.asarray(mask, dtype=np.float32)
        if mask.shape != (b, 1, h, w):
            raise ShapeError(f"mask: expected ({b}, 1, {h}, {w}), got {tuple(mask.shape)}")
        return image, mask

    def run(self, feeds: dict) -> list[np.ndarray]:
        """One raw session call with validated feeds (the four named inputs, right dtypes)."""
        if set(feeds) != set(INPUTS):
            raise InputError(f"inputs: expected exactly {list(INPUTS)}, got {sorted(feeds)}")
        want = {"image": np.float32, "mask": np.float32, "light_state": np.float32, "is_first": np.bool_}
        for name, dtype in want.items():
            arr = feeds[name]
            if not isinstance(arr, np.ndarray) or arr.dtype != dtype:
                raise InputError(f"{name}: expected a numpy {np.dtype(dtype).name} array, got "
                                 f"{getattr(arr, 'dtype', type(arr).__name__)}")
        self._check(feeds["image"], feeds["mask"])
        b = feeds["image"].shape[0]
        self._graph_shapes(b, *feeds["image"].shape[2:])
        if feeds["light_state"].shape != (b, self.state_size, self.n_coeffs, 3):
            raise ShapeError(f"light_state: expected ({b}, {self.state_size}, {self.n_coeffs}, 3), "
                             f"got {tuple(feeds['light_state'].shape)}")
        if feeds["is_first"].shape != (b,):
            raise ShapeError(f"is_first: expected ({b},), got {tuple(feeds['is_first'].shape)}")
        return self.session.run(None, feeds)

    def step(self, image: np.ndarray, mask: np.ndarray) -> dict:
        """Run one frame (batch of B streams).

        Args:
            image: (B, 3, H, W) float32 sRGB in [0, 1].
            mask: (B, 1, H, W) float32.

        Returns:
            ``albedo``, ``transport``, ``light_raw``, ``light_smoothed`` numpy arrays, and for a
            network that solves its light ``evidence_M``, ``evidence_r``, ``light_prior``.
        """
        image, mask = self._check(image, mask)
        b = image.shape[0]
        first = self._state is None or self._state.shape[0] != b
        state = np.zeros((b, self.state_size, self.n_coeffs, 3), np.float32) if first else self._state
        outs = self.run({"image": image, "mask": mask, "light_state": state,
                         "is_first": np.full((b,), first, dtype=bool)})
        albedo, transport, raw, smoothed, self._state = outs[:5]
        res = {"albedo": albedo, "transport": transport, "light_raw": raw, "light_smoothed": smoothed}
        res.update(zip(self.evidence_outputs, outs[5:], strict=True))
        return res

    def step_photo(self, image: torch.Tensor, mask: torch.Tensor, size: int):
        """Run one frame of any size: crop around the mask (KE18 framing), resize to ``size``, :meth:`step`.

        Args:
            image: (3, H, W) sRGB in [0, 1] (or uint8).
            mask: (H, W) person mask.
            size: working size, a multiple of 16.

        Returns:
            (the :meth:`step` outputs at ``size``, the :class:`~relightnet.model.inference.CropBox`
            to paste them back with).
        """
        from .inference import frame_person

        check_shape(image, [3, "H", "W"], name="image")
        check_shape(mask, image.shape[1:], name="mask")
        image = image.float() / 255 if image.dtype == torch.uint8 else image.float()
        x, m, box = frame_person(image, mask.float(), size)
        return self.step(x.contiguous().numpy(), m.numpy()), box


def calibration_set(n: int = 16, size: int = 128, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Inputs for static quantisation: ``n`` generated people (val split, held apart from training).

    Returns:
        ``n`` pairs (image (1, 3, size, size) float32 sRGB, mask (1, 1, size, size) float32).
    """
    from ..body import AnnyBody
    from ..data import SynthConfig, generate_sample

    cfg, body = SynthConfig(seed=seed, res=size, n_dirs=16), AnnyBody()
    out = []
    for i in range(n):
        a = generate_sample(cfg, "val", i, body=body).arrays
        img = (a["image_composite"].astype(np.float32) / 255).transpose(2, 0, 1)[None]
        out.append((np.ascontiguousarray(img), a["mask"][None, None].astype(np.float32)))
    return out


class _Reader:
    """An onnxruntime CalibrationDataReader over (image, mask) pairs."""

    def __init__(self, pairs, state_shape) -> None:
        self._it = iter(pairs)
        self._state_shape = state_shape

    def get_next(self):
        pair = next(self._it, None)
        if pair is None:
            return None
        img, mask = pair
        b = img.shape[0]
        return {"image": img, "mask": mask, "light_state": np.zeros((b, *self._state_shape), np.float32),
                "is_first": np.ones(b, bool)}


def _drop_stale_value_info(path: Path) -> None:
    """Remove the shape records of tensors no node produces: the quantiser keeps the records of the
    float tensors it replaced (the float64 light solve's casts among them), and a record without a
    tensor keeps its symbolic batch size, so the file's every-shape-known check would refuse it."""
    import onnx

    m = onnx.load(str(path))
    made = {o for n in m.graph.node for o in n.output}
    keep = [v for v in m.graph.value_info if v.name in made]
    if len(keep) < len(m.graph.value_info):
        del m.graph.value_info[:]
        m.graph.value_info.extend(keep)
        onnx.save(m, str(path))


def _float_nodes(path: Path, patterns) -> list[str]:
    """Names of the nodes of ``path`` (quantisable ops) whose weight name matches one of ``patterns``."""
    import re

    import onnx

    if not isinstance(patterns, (list, tuple)) or not all(isinstance(p, str) for p in patterns):
        raise InputError(f"keep_float: expected a sequence of regular expressions, got {patterns!r}")
    try:
        regexes = [re.compile(p) for p in patterns]
    except re.error as e:
        raise InputError(f"keep_float: not a regular expression ({e})") from None
    if not regexes:
        return []
    g = onnx.load(str(path), load_external_data=False).graph
    return [n.name for n in g.node if n.op_type in _QUANTISED_OPS and len(n.input) > 1
            and any(r.fullmatch(n.input[1]) for r in regexes)]


def quantize_int8(src, dst, mode: str = "static", calibration=None, reduce_range: bool = True,
                  keep_float=INT8_KEEP_FLOAT) -> Path:
    """A second model file in int8.

    Args:
        src: the fp32 model from :func:`~relightnet.model.onnx_export.export_onnx`.
        dst: output path (written atomically).
        mode: ``"static"`` (default): QDQ format, convolutions and matrix products in int8
            (per-channel 7-bit weights, uint8 activations with min–max ranges calibrated on
            ``calibration``; normalisation layers stay in float). ``"dynamic"``: int8 weights,
            activations quantised on the fly (small file, but slow for convolutions).
        calibration: (image (B, 3, H, W), mask (B, 1, H, W)) float32 pairs for ``static``
            (default: :func:`calibration_set`, 16 people at the model's training size).
        reduce_range: 7-bit weights (the default: right on every x86 CPU). x86 CPUs without VNNI
            sum pairs of uint8 × int8 products in saturating 16-bit registers; with 7-bit weights
            a pair cannot saturate (2 · 255 · 64 < 2¹⁵), so the int8 arithmetic is exact everywhere.
            False gives 8-bit weights, for CPUs with VNNI or AMX int8 instructions (32-bit sums).
        keep_float: regular expressions over weight names (matched in full): the convolutions and
            matrix products whose weight matches stay in float, in either mode. Default
            :data:`INT8_KEEP_FLOAT` (the pose encoder's first layers); ``()`` quantises every one.
    """
    import onnxruntime.quantization as q
    from onnxruntime.quantization.shape_inference import quant_pre_process

    src, dst = Path(src), Path(dst)
    if mode not in ("static", "dynamic"):
        raise InputError(f"mode: expected 'static' or 'dynamic', got {mode!r}")
    from ..io.atomic import remove_stale, temp_path

    r = OnnxRelighter(src)  # validates the file
    excluded = _float_nodes(src, keep_float)  # validates the patterns before any work
    remove_stale(dst)  # of an earlier quantisation that was killed
    tmp, pre = temp_path(dst, "quant"), temp_path(dst, "pre")
    try:
        if mode == "dynamic":
            q.quantize_dynamic(str(src), str(tmp), weight_type=q.QuantType.QInt8, nodes_to_exclude=excluded)
        else:
            if calibration is None:
                calibration = calibration_set(size=r.input_size)
            # Pre-processing (shape inference, graph clean-up) makes graphs from the dynamo exporter
            # quantisable: without it the QDQ pass duplicates a value name.
            quant_pre_process(str(src), str(pre), skip_symbolic_shape=True)
            excluded = _float_nodes(pre, keep_float)  # the names after the clean-up
            q.quantize_static(str(pre), str(tmp), _Reader(calibration, (r.state_size, r.n_coeffs, 3)),
                              quant_format=q.QuantFormat.QDQ, activation_type=q.QuantType.QUInt8,
                              weight_type=q.QuantType.QInt8, per_channel=True, reduce_range=bool(reduce_range),
                              op_types_to_quantize=list(_QUANTISED_OPS), nodes_to_exclude=excluded)
        logger.info("int8 (%s): %d layers kept in float by keep_float", mode, len(excluded))
        _drop_stale_value_info(tmp)
        tmp.replace(dst)
    finally:
        tmp.unlink(missing_ok=True)
        pre.unlink(missing_ok=True)
    return dst


def run_video(model_path, video, masks, out_dir, size: int | None = None, threads: int = 0) -> dict:
    """Stream a video through an exported model: per-frame raw and smoothed lights, albedo video.

    ``masks``: a folder of mask images or a mask video; None: the person segmentation
    (:func:`relightnet.segment.video_masks`; the exported graph has no mask head).
    Frames are cropped around each frame's mask (KE18 framing), resized to ``size`` (default:
    the model's training size from its metadata), and run in order so the smoothing state
    carries over. Writes ``lights_raw.npz`` and ``lights_smoothed.npz`` ((T, K, 3) light
    sequences) and ``albedo.mp4`` (the predicted albedo pasted back into the frame).

    Returns:
        ``{"raw": (T, K, 3), "smoothed": (T, K, 3)}`` numpy arrays.
    """
    from ..io import VideoWriter
    from ..segment.sources import video_masks
    from ..sh import save_light
    from .inference import paste_from_box

    r = OnnxRelighter(model_path, threads=threads)
    size = r.input_size if size is None else int(size)
    if size % r.multiple:
        raise InputError(f"size: expected a multiple of {r.multiple}, got {size}")
    info, _, pairs = video_masks(video, masks, "segment")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: --out-dir is a file; expected a folder (made if needed)")
    made = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        raw, smooth = [], []
        with VideoWriter(out / "albedo.mp4", fps=info.fps) as writer:
            for _, img, mask in pairs:
                res, box = r.step_photo(img, mask, size)
                raw.append(res["light_raw"][0])
                smooth.append(res["light_smoothed"][0])
                albedo = paste_from_box(torch.from_numpy(res["albedo"]), box, *img.shape[1:])[0] * mask
                writer.write(albedo.permute(1, 2, 0))
        result = {"raw": np.stack(raw), "smoothed": np.stack(smooth)}
        save_light(out / "lights_raw.npz", torch.from_numpy(result["raw"]))
        save_light(out / "lights_smoothed.npz", torch.from_numpy(result["smoothed"]))
    except BaseException:
        if made and out.is_dir() and not any(out.iterdir()):
            out.rmdir()  # a failed run leaves no empty folder behind
        raise
    return result
