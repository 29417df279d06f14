"""The options that travel together through the video jobs, as frozen objects with today's defaults.

:class:`AvatarLook` is what the avatar looks like, :class:`AvatarPlacement` where it goes in the
frame and what it is composited over, :class:`VideoLightSettings` how the light of a video's
frames is found and smoothed, :class:`PredictorSettings` which CNN estimates it and where. The PRT
options are :class:`relightnet.prt.PrtSettings`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..checks import InputError
from ..segment.sources import check_mask_source
from .backends import BACKENDS
from .clean_plate import check_stand_in

__all__ = ["AvatarLook", "AvatarPlacement", "PredictorSettings", "VideoLightSettings"]


@dataclass(frozen=True)
class AvatarLook:
    """What the avatar of :func:`~relightnet.pipeline.avatar` looks like.

    Args:
        body: ``"anny"``, ``"smpl:PATH"`` or a body model.
        albedo: ``"default"``, a texture image path (sRGB, in the body's UV layout), a (V, 3)
            per-vertex albedo or a :class:`~relightnet.render.TexturedAlbedo`.
        outfit: dress the body (an outfit of :mod:`relightnet.pipeline.outfits`), or None.
        captured: a captured person's avatar file (``relightnet capture``), or None.
        antialias: smooth the avatar's silhouette against the background (analytic edge
            antialiasing at the silhouette pixels).

    Example:
        >>> AvatarLook(outfit="jacket").body
        'anny'
    """

    body: object = "anny"
    albedo: object = "default"
    outfit: str | None = None
    captured: object = None
    antialias: bool = False

    def __post_init__(self):
        if self.captured is not None and self.outfit:
            raise InputError("--avatar brings its own geometry and texture: drop --outfit")
        own = self.outfit or self.captured is not None
        if own and not (isinstance(self.albedo, str) and self.albedo == "default"):
            raise InputError(f"{'--outfit' if self.outfit else '--avatar'} brings its own albedo: drop --albedo")
        if not isinstance(self.antialias, bool):
            raise InputError(f"antialias: expected True or False, got {self.antialias!r}")


@dataclass(frozen=True)
class AvatarPlacement:
    """Where the avatar of :func:`~relightnet.pipeline.avatar` stands and what it is composited over.

    Args:
        plate: None (the target's frames), a clean-plate video of the same size (the scene
            without the person) or one image.
        camera: the avatar's :class:`~relightnet.raster.Camera` (None: the
            :func:`~relightnet.raster.default_camera` at the video's size: full body, at the origin).
        replace_person: take the person's place (:func:`~relightnet.pipeline.clean_plate.stand_in`):
            the job builds the plate and places the camera itself, so not with ``plate`` or ``camera``.

    Example:
        >>> AvatarPlacement(replace_person=True).plate is None
        True
    """

    plate: object = None
    camera: object = None
    replace_person: bool = False

    def __post_init__(self):
        check_stand_in(self.replace_person, self.plate, self.camera)


@dataclass(frozen=True)
class VideoLightSettings:
    """How the light of a video's frames is found and smoothed over time.

    Args:
        smoothing: the smoothing method; each job checks it against its own set
            (:data:`relightnet.names.VIDEO_SMOOTHING` offline, ``STREAMING_SMOOTHING`` streaming).
        mask_source: without masks: ``segment`` (the person segmentation) or ``head`` (the
            model's mask head); :mod:`relightnet.segment.sources`.
        alpha: the streaming ``ema``'s weight of the newest frame, in (0, 1].
        model_name: names the model in the resume fingerprint of the estimates (e.g. the
            checkpoint path).
        plate_light: a :class:`relightnet.light.Plate`, combined with each estimate
            (:func:`relightnet.light.combine_person_plate`), or None.

    Example:
        >>> VideoLightSettings(smoothing="hermite").mask_source
        'segment'
    """

    smoothing: str = "auto"
    mask_source: str = "segment"
    alpha: float = 0.3
    model_name: str = "model"
    plate_light: object = None

    def __post_init__(self):
        check_mask_source(self.mask_source)
        a = self.alpha
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not 0 < a <= 1:
            raise InputError(f"alpha: expected a weight in (0, 1], got {a!r}")
        if not isinstance(self.model_name, str):
            raise InputError(f"model_name: expected a string, got {type(self.model_name).__name__}")


@dataclass(frozen=True)
class PredictorSettings:
    """Which CNN a job runs and where (:func:`~relightnet.pipeline.backends.make_predictor`).

    Args:
        checkpoint: the CNN's checkpoint (None: the shipped model); with ``backend="onnx"`` also an
            ``.onnx`` file (a checkpoint is exported once).
        backend: ``"torch"`` or ``"onnx"`` (CPU); :data:`~relightnet.pipeline.BACKENDS`.
        device: for the CNN (``"cpu"``, ``"cuda"``).
        size: the CNN's working size, a positive multiple of 16 (None: its training size).

    Example:
        >>> PredictorSettings(backend="onnx").device
        'cpu'
    """

    checkpoint: object = None
    backend: str = "torch"
    device: str = "cpu"
    size: int | None = None

    def __post_init__(self):
        if self.backend not in BACKENDS:
            raise InputError(f"backend: expected one of {', '.join(BACKENDS)}, got {self.backend!r}")
        s = self.size
        if s is not None and (isinstance(s, bool) or not isinstance(s, int) or s < 16 or s % 16):
            raise InputError(f"size: expected a positive multiple of 16, got {s!r}")
