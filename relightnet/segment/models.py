"""The two shipped person models, run by ONNX Runtime.

Both are MediaPipe models (Apache-2.0) converted to ONNX by ``tools/convert_segmentation.py``
(origin, licence and checksums in ``relightnet/weights/NOTICE``):

- ``person_selfie.onnx`` (MediaPipe selfie segmentation): (1, 256, 256, 3) RGB in [0, 1] ->
  (1, 256, 256, 1) person probability, for the whole frame squeezed to 256².
- ``person_pose.onnx`` (MediaPipe BlazePose GHUM full): (1, 256, 256, 3) RGB in [0, 1], an
  upright square crop around one person -> ``Identity`` (1, 195): 39 landmarks × (x, y, z,
  visibility logit, presence logit) in crop pixels; ``Identity_1`` (1, 1): the probability
  that a person is in the crop; ``Identity_2`` (1, 256, 256, 1): person mask logits;
  ``Identity_4`` (1, 117): 39 landmarks × (x, y, z) in metres around the hips.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import check_shape

__all__ = ["WEIGHTS_DIR", "SELFIE_FILE", "POSE_FILE", "INPUT_SIZE", "LANDMARK_NAMES", "PoseOutput", "PersonModels"]

#: The shipped weights (``relightnet/weights``): the selfie segmentation model (whole-frame person box)
#: and the full-body pose model (mask and 33 landmarks of a square crop), both ONNX.
WEIGHTS_DIR = Path(__file__).resolve().parents[1] / "weights"
#: The selfie segmentation model (finds the person in the whole frame).
SELFIE_FILE = WEIGHTS_DIR / "person_selfie.onnx"
#: The full-body pose model (mask and landmarks of the crop around the person).
POSE_FILE = WEIGHTS_DIR / "person_pose.onnx"
#: Both models read 256 × 256 RGB.
INPUT_SIZE = 256
#: The pose model's first 33 landmarks are BlazePose's body points (the rest are its own helpers),
#: in this order (left/right: the person's own).
LANDMARK_NAMES = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
    "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder", "left_elbow",
    "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky", "left_index", "right_index",
    "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
    "left_heel", "right_heel", "left_foot_index", "right_foot_index",
)
N_LANDMARKS = len(LANDMARK_NAMES)


@dataclass(frozen=True)
class PoseOutput:
    """What the pose model says about one crop (numpy, crop coordinates).

    mask_logits (256, 256); presence: probability that a person is in the crop;
    landmarks (33, 5): x, y, z in crop pixels (z relative to the hips, same scale as x),
    visibility and presence probabilities; world (33, 3): metres, origin between the hips.
    """

    mask_logits: np.ndarray
    presence: float
    landmarks: np.ndarray
    world: np.ndarray


def _sigmoid(x: np.ndarray) -> np.ndarray:
    return 0.5 * (1 + np.tanh(0.5 * x))


class PersonModels:
    """The two ONNX Runtime sessions (~0.2 s to load: make one and pass it on for many images).

    Args:
        threads: intra-op threads of each session (0: ONNX Runtime's default, all cores).
    """

    def __init__(self, threads: int = 0) -> None:
        import onnxruntime as ort

        opts = ort.SessionOptions()
        opts.intra_op_num_threads = threads
        opts.inter_op_num_threads = 1
        self.threads = threads
        self._selfie = ort.InferenceSession(str(SELFIE_FILE), opts, providers=["CPUExecutionProvider"])
        self._pose = ort.InferenceSession(str(POSE_FILE), opts, providers=["CPUExecutionProvider"])
        self._pose_outputs = ["Identity", "Identity_1", "Identity_2", "Identity_4"]

    @staticmethod
    def _input(x: np.ndarray, name: str) -> np.ndarray:
        check_shape(x, [INPUT_SIZE, INPUT_SIZE, 3], name=name)
        return np.ascontiguousarray(x, dtype=np.float32)[None]

    def selfie(self, x: np.ndarray) -> np.ndarray:
        """Person probability of a frame squeezed to 256²: (256, 256, 3) RGB [0, 1] -> (256, 256)."""
        return self._selfie.run(None, {"input_1": self._input(x, "selfie input")})[0][0, ..., 0]

    def pose(self, x: np.ndarray) -> PoseOutput:
        """Mask, presence and landmarks of the person in an upright square crop: (256, 256, 3) RGB [0, 1]."""
        lm, flag, mask, world = self._pose.run(self._pose_outputs, {"input_1": self._input(x, "pose input")})
        lm = lm.reshape(-1, 5)[:N_LANDMARKS].copy()
        lm[:, 3:] = _sigmoid(lm[:, 3:])
        return PoseOutput(mask[0, ..., 0], float(flag.reshape(-1)[0]), lm,
                          world.reshape(-1, 3)[:N_LANDMARKS].copy())
