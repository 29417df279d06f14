"""World ⇄ light frame, and camera-relative lights.

World frame: right-handed, +y up, the default camera looks along −z (OpenGL).
Light frame (where SH directions live, Kanamori–Endo's): x_light = +z_world
(toward the default camera), y_light = +x_world (image right), z_light = +y_world
(up). The map is a cyclic permutation of the axes, a proper rotation.
"""

from __future__ import annotations

import torch

from ..checks import check_shape

__all__ = [
    "WORLD_TO_LIGHT",
    "world_to_light",
    "light_to_world",
    "rotation_world_to_light",
    "camera_normals_to_light",
]

#: 3×3 matrix P with v_light = P @ v_world.
WORLD_TO_LIGHT = torch.tensor([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def world_to_light(v: torch.Tensor) -> torch.Tensor:
    """Map vectors from the world frame to the light frame.

    Args:
        v: (..., 3) world-frame vectors.

    Returns:
        (..., 3) light-frame vectors ``(z_w, x_w, y_w)``.

    Example:
        World +z (toward the default camera) is the light frame's x; world +y (up) its z:

        >>> import torch
        >>> from relightnet.sh import world_to_light
        >>> world_to_light(torch.tensor([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])).tolist()
        [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    check_shape(v, ["...", 3], name="v")
    return v[..., [2, 0, 1]]


def light_to_world(v: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`world_to_light`: (..., 3) light → (..., 3) world ``(y_l, z_l, x_l)``.

    Example:
        >>> import torch
        >>> from relightnet.sh import light_to_world, world_to_light
        >>> v = torch.tensor([0.1, 0.2, 0.3])
        >>> torch.equal(light_to_world(world_to_light(v)), v)
        True
    """
    check_shape(v, ["...", 3], name="v")
    return v[..., [1, 2, 0]]


def rotation_world_to_light(R: torch.Tensor) -> torch.Tensor:
    """Express a world-frame rotation in the light frame: ``P R Pᵀ``.

    Args:
        R: (..., 3, 3) rotation acting on world-frame column vectors.

    Returns:
        (..., 3, 3) the same rotation acting on light-frame vectors
        (use it with :func:`relightnet.sh.rotate_sh`).
    """
    check_shape(R, ["...", 3, 3], name="R")
    P = WORLD_TO_LIGHT.to(R)
    return P @ R @ P.T


def camera_normals_to_light(normals_world: torch.Tensor, cam_R: torch.Tensor) -> torch.Tensor:
    """Light-frame normals for a light estimated relative to a camera.

    A light estimated from an image is expressed relative to that image's camera,
    whose view frame coincides with the world frame for the default camera. For any
    other camera, world normals are first rotated into its view frame
    (``n_view = R_wc n_world``, with ``R_wc`` the world→camera rotation of the
    extrinsics) and then mapped to the light frame.

    Args:
        normals_world: (..., 3) world-frame normals.
        cam_R: (3, 3) world→camera rotation, or (B, 3, 3) with normals (B, ..., 3).

    Returns:
        (..., 3) light-frame normals for SH lookup.

    Example:
        With the default camera (identity rotation) this is :func:`world_to_light`:

        >>> import torch
        >>> from relightnet.sh import camera_normals_to_light
        >>> camera_normals_to_light(torch.tensor([[0.0, 0.0, 1.0]]), torch.eye(3)).tolist()
        [[1.0, 0.0, 0.0]]
    """
    check_shape(normals_world, ["...", 3], name="normals_world")
    check_shape(cam_R, ["...", 3, 3], name="cam_R")
    if cam_R.dim() == 2:
        n_view = normals_world @ cam_R.T.to(normals_world)
    else:
        b = cam_R.shape[0]
        if normals_world.shape[0] != b:
            raise ValueError(
                f"normals_world: expected leading batch {b} to match cam_R, got {tuple(normals_world.shape)}"
            )
        flat = normals_world.reshape(b, -1, 3)
        n_view = (flat @ cam_R.transpose(-1, -2).to(flat)).reshape(normals_world.shape)
    return world_to_light(n_view)
