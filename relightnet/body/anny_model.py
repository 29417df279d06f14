"""Anny (MakeHuman-based, Apache-2.0) behind the :class:`BodyModel` interface.

What the model exposes (anny 0.6.2, ``anny.Anny()`` defaults: rig ``"anny"``,
topology ``"anny"``):

- mesh: 13,718 vertices, 27,420 triangles (Anny triangulates the MakeHuman quads,
  faces and UV faces together, splitting each quad along its shorter diagonal), one
  closed, outward-wound surface per component (body, mouth cavity + tongue, 2 eyes);
  21,334 UV coordinates (seams duplicate them), v up;
- rig: 104 bones (``root``, legs, toes, 5 spine bones, arms, fingers, neck, head,
  eyes); a bone's joint is its head;
- phenotype: six values, see :data:`PHENOTYPES`;
- native frame: z up, the person faces −y, left side on +x, metres; zero pose deltas put
  the root joint (pelvis) at the origin. :func:`anny_to_world` is the one place that
  converts to relightnet's frame (y up, facing +z).

Pose: Anny's ``local-ref`` parameterisation is used — each bone's delta rotation is
expressed in axes aligned with the (Anny) world axes of the rest pose and applied about
the bone's head in its parent's posed frame, exactly the SMPL convention. relightnet takes
rotation vectors in *relightnet* world axes and conjugates them by the frame rotation.
Zero rotations give Anny's *reference* pose — an A-pose with the arms about 47° below
horizontal and the hands a little forward — which is within a few degrees of, but not
equal to, the rest mesh its blend shapes produce.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

import torch

from ..checks import InputError, ShapeError, check_finite, check_shape
from .base import BodyModel, BodyOutput, broadcast_batch, rotvec_to_matrix

logger = logging.getLogger(__name__)

__all__ = [
    "AnnyBody",
    "ANNY_TO_WORLD",
    "anny_to_world",
    "PHENOTYPES",
    "POSE_PRESETS",
    "pose_preset",
    "load_anny",
]

#: v_world = ANNY_TO_WORLD @ v_anny: a −90° rotation about x, (x, y, z) → (x, z, −y).
#: Anny's up (+z) becomes +y, its facing direction (−y) becomes +z; left stays +x.
ANNY_TO_WORLD = torch.tensor([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]], dtype=torch.float64)

#: Phenotype name → (min, max, relightnet default). Values are Anny's blend coordinates:
#: ``gender`` 0 male … 1 female; ``age`` anchors −1/3 newborn, 0 baby, 1/3 child,
#: 2/3 young, 1 old — Anny's calibration maps age 0.415 ≈ 11 y, 0.67 ≈ 16 y, 0.77 ≈ 18 y,
#: 0.83 ≈ 64 y, so the default 0.78 is an adult of about 25; ``muscle``, ``weight``,
#: ``height`` 0 min … 1 max (an adult of gender 0.5 is 1.28 m at height 0, 1.83 m at 0.5,
#: 2.38 m at 1; the default 0.37, about Anny's calibrated adult mean, gives 1.69 m);
#: ``proportions`` 0 ideal … 1 uncommon. (Anny's own default, 0.5 everywhere, is a
#: 1.63 m 12-year-old.)
PHENOTYPES: dict[str, tuple[float, float, float]] = {
    "gender": (0.0, 1.0, 0.5),
    "age": (-1.0 / 3.0, 1.0, 0.78),
    "muscle": (0.0, 1.0, 0.5),
    "weight": (0.0, 1.0, 0.5),
    "height": (0.0, 1.0, 0.37),
    "proportions": (0.0, 1.0, 0.5),
}


def anny_to_world(x: torch.Tensor) -> torch.Tensor:
    """Convert points or vectors from Anny's frame (z up, facing −y) to relightnet's world.

    Args:
        x: (..., 3) in Anny's frame.

    Returns:
        (..., 3) in the world frame (y up, facing +z): ``(x, z, −y)``.
    """
    check_shape(x, ["...", 3], name="x")
    return torch.stack([x[..., 0], x[..., 2], -x[..., 1]], dim=-1)  # = x @ ANNY_TO_WORLD.T, exactly


def load_anny(dtype: torch.dtype = torch.float32, device: torch.device | str | None = None):
    """Build ``anny.Anny()`` (default rig and MakeHuman topology, pure-torch dense LBS).

    The cache is ``$ANNY_CACHE_DIR`` as set *now* (anny itself reads it once, at import),
    else the checkout's ``.cache/anny`` that ``make`` filled, else ``~/.cache/anny``
    (:func:`relightnet.body.cache.anny_cache_dir`); a cold cache takes minutes and ~1 GB to fill
    (``python -m relightnet.body.cache``), a warm one loads in well under a second.
    Dense LBS (``skinning_method="lbs"``) is plain torch: no NVIDIA Warp import, any device,
    differentiable.
    """
    import anny
    import anny.paths

    from .cache import anny_cache_dir

    cache = anny_cache_dir()
    if cache:
        anny.paths.set_anny_cache_path(cache)
    else:
        logger.info("ANNY_CACHE_DIR is not set and make filled no cache: anny uses %s",
                    anny.paths.get_anny_cache_path())

    model = anny.Anny(skinning_method="lbs")
    return model.to(device=device, dtype=dtype).eval()


class AnnyBody(BodyModel):
    """Anny as a :class:`BodyModel`.

    Parameters (a mapping or keyword arguments of ``forward``):

    - ``pose``: (B, 104, 3) or (104, 3) rotation vectors in world axes (index 0: root,
      global orientation about the pelvis), or a mapping bone name → (B, 3) / (3,);
      default: zero rotations (Anny's reference A-pose, preset ``"rest"``).
    - ``trans``: (B, 3) or (3,) world translation, default 0.
    - ``phenotype``: mapping name → float or (B,) (missing names take the defaults of
      :data:`PHENOTYPES`), or a (B, 6) / (6,) tensor in :data:`PHENOTYPES` order.

    Args:
        dtype: float32 (default) or float64.
        device: where the buffers live.
        ground: see :data:`relightnet.body.base.GROUND_MODES`; default ``"rest"`` puts the
            feet of the rest pose on y = 0 (pelvis at about 0.9 m for an adult).
        model: an already built ``anny.Anny`` to wrap (tests share one); it is moved to
            ``dtype``/``device`` in place.
    """

    param_names = ("pose", "trans", "phenotype")

    def __init__(
        self,
        dtype: torch.dtype = torch.float32,
        device: torch.device | str | None = None,
        ground: str = "rest",
        model=None,
    ) -> None:
        super().__init__(ground=ground)
        if dtype not in (torch.float32, torch.float64):
            raise InputError(f"dtype: expected float32 or float64, got {dtype}")
        self.anny = load_anny(dtype, device) if model is None else model.to(device=device, dtype=dtype)
        faces = self.anny.faces
        uv_faces = self.anny.face_texture_coordinate_indices
        if faces.dim() != 2 or faces.shape[1] != 3 or uv_faces.shape != faces.shape:
            raise ShapeError(
                f"anny faces: expected (F, 3) triangles with matching UV faces, got {tuple(faces.shape)} "
                f"and {tuple(uv_faces.shape)} (use the default 'anny' topology)"
            )
        dev = self.anny.template_vertices.device
        self.register_buffer("faces", faces.to(device=dev, dtype=torch.int64), persistent=False)
        self.register_buffer("uv", self.anny.texture_coordinates.to(dtype), persistent=False)
        self.register_buffer("uv_faces", uv_faces.to(device=dev, dtype=torch.int64), persistent=False)
        self.joint_names = tuple(self.anny.bone_labels)
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        # Sole candidates for grounding: template vertices within 6 cm of the lowest one.
        tz = self.anny.template_vertices[:, 2]
        soles = torch.nonzero(tz < tz.min() + 0.06).flatten()
        self.register_buffer("_soles", soles, persistent=False)
        self.register_buffer("_sole_weights", self.anny.vertex_bone_weights[soles].to(dtype), persistent=False)
        self.register_buffer("_sole_bones", self.anny.vertex_bone_indices[soles].long(), persistent=False)
        if list(self.anny.phenotype_labels) != list(PHENOTYPES):
            raise InputError(f"anny phenotypes {self.anny.phenotype_labels} differ from {list(PHENOTYPES)}")

    @property
    def dtype(self) -> torch.dtype:
        return self.anny.template_vertices.dtype

    @property
    def num_verts(self) -> int:
        return self.anny.template_vertices.shape[0]

    def joint_index(self, name: str) -> int:
        """Index of bone ``name`` in ``joint_names`` (raise :class:`InputError` if unknown)."""
        try:
            return self._index[name]
        except KeyError:
            raise InputError(f"unknown Anny bone {name!r}; see AnnyBody.joint_names") from None

    def pose_from_dict(self, rotations: Mapping[str, object], batch_size: int | None = None) -> torch.Tensor:
        """(B, J, 3) pose from bone name → rotation vector (3,) or (B, 3); other bones at rest."""
        vals = {}
        for name, v in rotations.items():
            i = self.joint_index(name)
            v = torch.as_tensor(v, dtype=self.dtype, device=self.faces.device)
            if v.dim() == 1:
                v = v[None]
            check_shape(v, ["B", 3], name=f"pose[{name!r}]")
            vals[i] = v
        if batch_size is not None:
            b = int(batch_size)
        else:
            b = broadcast_batch({str(k): v for k, v in vals.items()}, "pose") if vals else 1
        pose = torch.zeros(b, self.num_joints, 3, dtype=self.dtype, device=self.faces.device)
        for i, v in vals.items():
            pose[:, i] = v.expand(b, 3)
        return pose

    def pose(self, name: str, batch_size: int = 1) -> torch.Tensor:
        """(B, J, 3) pose of a preset (see :data:`POSE_PRESETS`)."""
        return self.pose_from_dict(pose_preset(name), batch_size)

    def phenotype_tensor(self, phenotype=None) -> torch.Tensor:
        """(B, 6) phenotype values from a mapping / tensor, validated against :data:`PHENOTYPES`."""
        names = list(PHENOTYPES)
        dev = self.faces.device
        if phenotype is None:
            phenotype = {}
        if isinstance(phenotype, Mapping):
            unknown = sorted(set(phenotype) - set(names))
            if unknown:
                raise InputError(f"phenotype: unknown name(s) {unknown}; expected some of {names}")
            cols = {}
            for n in names:
                v = torch.as_tensor(phenotype.get(n, PHENOTYPES[n][2]), dtype=self.dtype, device=dev)
                if v.dim() > 1:
                    raise ShapeError(f"phenotype[{n!r}]: expected a float or (B,), got {tuple(v.shape)}")
                cols[n] = v.reshape(-1)
            b = broadcast_batch(cols, "phenotype")
            x = torch.stack([cols[n].expand(b) for n in names], dim=1)
        else:
            x = torch.as_tensor(phenotype, dtype=self.dtype, device=dev)
            if x.dim() == 1:
                x = x[None]
            check_shape(x, ["B", len(names)], name="phenotype")
        check_finite(x, "phenotype")
        for j, n in enumerate(names):
            lo, hi, _ = PHENOTYPES[n]
            col = x[:, j]
            if bool(((col < lo - 1e-6) | (col > hi + 1e-6)).any()):
                raise InputError(
                    f"phenotype[{n!r}]: expected values in [{lo:.3g}, {hi:.3g}], got {col.tolist()}"
                )
        return x

    def _forward(self, params: dict) -> BodyOutput:
        dev, dtype = self.faces.device, self.dtype
        pose = params.get("pose")
        if isinstance(pose, Mapping):
            pose = self.pose_from_dict(pose)
        pose = self._batched(pose, "pose", [self.num_joints, 3])
        trans = self._batched(params.get("trans"), "trans", [3])
        phen = self.phenotype_tensor(params.get("phenotype"))
        b = broadcast_batch({"pose": pose, "trans": trans, "phenotype": phen}, "AnnyBody")
        if pose is None:
            pose = torch.zeros(1, self.num_joints, 3, dtype=dtype, device=dev)
        if trans is None:
            trans = torch.zeros(1, 3, dtype=dtype, device=dev)
        # World-axis rotations → Anny-axis rotations: R_anny = Cᵀ R_world C.
        C = ANNY_TO_WORLD.to(device=dev, dtype=dtype)
        R = C.T @ rotvec_to_matrix(pose.expand(b, -1, -1)) @ C
        delta = torch.zeros(b, self.num_joints, 4, 4, dtype=dtype, device=dev)
        delta[..., :3, :3] = R
        delta[..., 3, 3] = 1.0
        out = self.anny(pose_parameters=delta, phenotype_kwargs=phen)  # a (1, 6) phenotype is shaped once
        verts = anny_to_world(out["vertices"])
        joints = anny_to_world(out["bone_poses"][..., :3, 3])
        rest_min_y = self._zero_pose_min_y(out).expand(b) if self.ground == "rest" else None
        return self._finish(verts, joints, rest_min_y, trans.expand(b, 3))

    def _zero_pose_min_y(self, out: dict) -> torch.Tensor:
        """(B_phenotype,) lowest world y of the zero-pose mesh, skinning only the sole vertices.

        Zero deltas give Anny's *reference* pose (within a few degrees of its rest mesh, not
        equal to it), so the sole candidates are skinned with the zero-pose bone transforms.
        """
        rest_poses = out["rest_bone_poses"]
        eye = torch.eye(4, dtype=rest_poses.dtype, device=rest_poses.device)
        T, _ = self.anny.get_bone_transforms(eye.expand_as(rest_poses), rest_poses)
        idx, w, bones = self._soles, self._sole_weights, self._sole_bones  # (S,), (S, K), (S, K)
        v = out["rest_vertices"][:, idx]  # (Bp, S, 3)
        Tk = T[:, bones]  # (Bp, S, K, 4, 4)
        p = (Tk[..., :3, :3] @ v[:, :, None, :, None])[..., 0] + Tk[..., :3, 3]
        z = (w[None, :, :, None] * p).sum(2)[..., 2]  # Anny z is world y
        return z.amin(dim=1)


#: Preset name → {bone: world-axis rotation vector (radians)}; every other bone at zero.
#: Derived once, on the default adult's zero-pose joints, as the smallest rotations taking
#: the upper arm (upperarm01 → lowerarm01) and the forearm (lowerarm01 → wrist) onto target
#: directions: ``tpose`` (±1, 0, 0); ``apose`` 45° below horizontal in the frontal plane;
#: ``arms_down`` upper arms 9° out from vertical, elbows bent 17° forward; ``arms_crossed``
#: upper arms down-forward, forearms across the chest (left above right), wrists 20 cm in
#: front of the spine. Other phenotypes get nearly the same pose.
POSE_PRESETS: dict[str, dict[str, tuple[float, float, float]]] = {
    "rest": {},
    "tpose": {
        "upperarm01.L": (0.0000, 0.0320, 0.8538),
        "lowerarm01.L": (0.5470, 0.4750, -0.0448),
        "upperarm01.R": (0.0000, -0.0320, -0.8538),
        "lowerarm01.R": (0.5470, -0.4750, 0.0448),
    },
    "apose": {
        "upperarm01.L": (0.0200, 0.0200, 0.0686),
        "lowerarm01.L": (0.5470, 0.4750, -0.0448),
        "upperarm01.R": (0.0200, -0.0200, -0.0686),
        "lowerarm01.R": (0.5470, -0.4750, 0.0448),
    },
    "arms_down": {
        "upperarm01.L": (0.0137, -0.0090, -0.5578),
        "lowerarm01.L": (0.3743, 0.2600, -0.0804),
        "upperarm01.R": (0.0137, 0.0090, 0.5578),
        "lowerarm01.R": (0.3743, -0.2600, 0.0804),
    },
    "arms_crossed": {
        "upperarm01.L": (-0.6015, -0.5482, -0.6417),
        "lowerarm01.L": (0.1358, -0.8872, -0.7799),
        "upperarm01.R": (-0.5265, 0.4841, 0.6770),
        "lowerarm01.R": (0.2545, 0.7537, 0.7663),
    },
}


def pose_preset(name: str) -> dict[str, tuple[float, float, float]]:
    """Bone name → world-axis rotation vector of a preset pose (see :data:`POSE_PRESETS`)."""
    if name not in POSE_PRESETS:
        raise InputError(f"pose preset: expected one of {sorted(POSE_PRESETS)}, got {name!r}")
    return dict(POSE_PRESETS[name])
