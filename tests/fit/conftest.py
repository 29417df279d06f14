"""Fit fixtures: one FitBody per session, and synthetic evidence made from a known body."""

from __future__ import annotations

import pytest
import torch


@pytest.fixture(scope="session")
def fit_body(anny_body):
    from relightnet.fit import FitBody

    return FitBody(anny_body)


def known_clip(fb, T: int = 2, size=(192, 192), fov: float = 50.0, yaw: float = 0.4, seed: int = 1):
    """Evidence made from a known walking body: (Observations, intrinsics, truth points (T, 33, 3))."""
    from relightnet.body import make_motion
    from relightnet.body.base import compose_rotvecs
    from relightnet.fit import Observations, default_intrinsics
    from relightnet.fit.camera import project_points
    from relightnet.raster import Camera, rasterize
    from relightnet.raster.camera import perspective_projection

    intr = default_intrinsics(size, fov)
    m = make_motion("walk", T, fps=30, seed=seed)
    pose = fb.body.pose_from_dict(m["pose"], T)
    pose[:, 0] = compose_rotvecs(torch.tensor([0.0, yaw, 0.0]).expand(T, 3), pose[:, 0])
    trans = m["trans"] + torch.tensor([0.0, -1.0, -4.0])
    phen = fb.body.phenotype_tensor({"height": 0.5, "weight": 0.35})
    with torch.no_grad():
        out = fb.body(pose=pose, trans=trans, phenotype=phen)
        pts = fb.landmarks(out.verts, out.joints)
        hip = 0.5 * (pts[:, 23:24] + pts[:, 24:25])
        world = (pts - hip) * torch.tensor([1.0, -1.0, -1.0])
        lm = torch.cat([project_points(pts, intr), torch.zeros(T, 33, 1), torch.ones(T, 33, 2)], -1)
        P = perspective_projection(*intr, size)
        cam = Camera(torch.eye(4)[None].expand(T, 4, 4), P.expand(T, 4, 4), size)
        masks = rasterize(cam.transform(out.verts), out.faces, size).mask.float()
    return Observations(lm, world, masks, torch.ones(T, dtype=torch.bool), size), intr, pts
