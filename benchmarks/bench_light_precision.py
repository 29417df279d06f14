"""The light solve's precision: the float32 form it had against the float64 equilibrated one.

Three cases, each solved from the same float32 maps (what the network gives):

- ``hemisphere``: the noise-free case of ``tests/model/test_light_solve.py`` (exact transport
  of a hemisphere of normals, one albedo, the image rendered from them, 32² pixels);
- ``cone 60°``: the same with normals only within 60° of the view (deliberately ill-conditioned);
- ``generated``: items of the synthetic generator (exact albedo, occluded transport, light).

For each: the condition number of M (channel 0, before and after scaling to a unit diagonal),
the error against the true light (max abs over K × 3, at the test's λ = 1e-6 and at λ = 1e-9),
and the *order sensitivity*: the largest change of the light when the pixels are summed in
another order (a random permutation: what another CPU's matmul kernel does), which is what made
the suite fail on an AVX2-only AMD EPYC. The float32 form is the solve as it was before
(accumulated and factorised in float32, no scaling), kept here only to compare.

Run: ``python benchmarks/bench_light_precision.py [--items 100] [--res 128]``.
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import table  # noqa: E402

from relightnet.sh.light_solve import light_evidence, solve_light  # noqa: E402
from tests.sh.test_light_solve import front_of_sphere  # noqa: E402  (the test's cases, measured here)


def _old_solve(image, albedo, transport, weight, reg):
    """The float32 solve as it was before: float32 normal equations, unscaled Cholesky."""
    image, albedo, transport, weight = (t.float() for t in (image, albedo, transport, weight))
    n = (weight > 0).float().sum((2, 3)).clamp_min(1.0)[:, :, None]
    a = (albedo[:, :, None] * transport[:, None]).flatten(3)
    aw = a * weight.flatten(2)[:, :, None]
    M = aw @ a.transpose(-1, -2) / n[..., None]
    r = (aw @ image.flatten(2)[..., None])[..., 0] / n
    k = M.shape[-1]
    s = M.diagonal(dim1=-2, dim2=-1).mean(-1, keepdim=True).clamp_min(1e-8)
    A = M + reg * s[..., None] * torch.eye(k)
    G = torch.linalg.cholesky(A)
    return torch.cholesky_solve(r[..., None], G)[..., 0].transpose(1, 2)


def _new_solve(image, albedo, transport, weight, reg):
    return solve_light(light_evidence(image, albedo, transport, weight), None, reg)


def _sphere_case(max_angle_deg: float | None):
    """The test's front of a sphere (``None``: normals up to 63° from the view) or a cone of normals."""
    image, albedo, T, inside, light = front_of_sphere(max_angle_deg=max_angle_deg)
    return image, albedo, T, inside, light[None]


def _generated_items(n: int, res: int):
    from relightnet.body import AnnyBody
    from relightnet.data import SynthConfig
    from relightnet.data.generate import generate_sample, prepare_assets

    cfg = SynthConfig(seed=21, res=res, n_dirs=128, counts={"test": n}, noise_std=0.0, bounce_prob=0.0)
    assets = prepare_assets(AnnyBody())
    for i in range(n):
        a = generate_sample(cfg, "test", i, body=assets).arrays
        to = lambda x: torch.from_numpy(x).float().permute(2, 0, 1)[None]  # noqa: E731
        m = torch.from_numpy(a["mask"]).float()[None, None]
        yield to(a["image"]) * m, to(a["albedo"]), to(a["transport"]), m, torch.from_numpy(a["light"]).float()[None]


def _cond(image, albedo, transport, weight):
    M = light_evidence(image, albedo, transport, weight).M[0, 0]
    d = M.diagonal().rsqrt()
    return float(torch.linalg.cond(M)), float(torch.linalg.cond(M * d[:, None] * d[None]))


def _measure(case, reg_list=(1e-6, 1e-9), n_perm: int = 5):
    image, albedo, transport, weight, light = case
    g = torch.Generator().manual_seed(0)
    row = {"cond": _cond(image, albedo, transport, weight)}
    p = image.shape[-2] * image.shape[-1]
    for name, fn in (("float32", _old_solve), ("float64", _new_solve)):
        for reg in reg_list:
            row[(name, reg)] = float((fn(image, albedo, transport, weight, reg) - light).abs().max())
        base = fn(image, albedo, transport, weight, reg_list[0])
        worst = 0.0
        for _ in range(n_perm):
            perm = torch.randperm(p, generator=g)
            sh = [x.flatten(2)[..., perm].reshape(x.shape) for x in (image, albedo, transport, weight)]
            worst = max(worst, float((fn(*sh, reg_list[0]) - base).abs().max()))
        row[(name, "order")] = worst
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--items", type=int, default=100, help="generated items (default 100)")
    ap.add_argument("--res", type=int, default=128, help="their resolution (default 128)")
    args = ap.parse_args(argv)
    torch.set_num_threads(2)
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")),
               platform.processor())
    print(f"CPU: {cpu}; torch {torch.__version__}, {torch.backends.cpu.get_cpu_capability()}, 2 threads\n")
    rows = []
    for label, case in (("front of a sphere (test case)", _sphere_case(None)), ("cone 60°", _sphere_case(60)),
                        ("cone 30°", _sphere_case(30))):
        m = _measure(case)
        rows.append([label, 1, f"{m['cond'][0]:.3g}", f"{m['cond'][1]:.3g}",
                     *(f"{m[(f, r)]:.2g}" for f in ("float32", "float64") for r in (1e-6, 1e-9, "order"))])
    gen = [_measure(c, n_perm=1) for c in _generated_items(args.items, args.res)]
    if gen:
        def med(key):
            return float(torch.tensor([g[key] for g in gen]).median())

        def p90(key):
            return float(torch.tensor([g[key] for g in gen]).quantile(0.9))

        conds = torch.tensor([g["cond"] for g in gen])
        rows.append([f"generated {args.res}² (median)", len(gen), f"{conds[:, 0].median():.3g}",
                     f"{conds[:, 1].median():.3g}",
                     *(f"{med((f, r)):.2g}" for f in ("float32", "float64") for r in (1e-6, 1e-9, "order"))])
        rows.append([f"generated {args.res}² (p90)", len(gen), f"{conds[:, 0].quantile(0.9):.3g}",
                     f"{conds[:, 1].quantile(0.9):.3g}",
                     *(f"{p90((f, r)):.2g}" for f in ("float32", "float64") for r in (1e-6, 1e-9, "order"))])
    print(table(["case", "items", "cond(M)", "cond(scaled M)", "f32 err λ=1e-6", "f32 err λ=1e-9", "f32 order Δ",
                 "f64 err λ=1e-6", "f64 err λ=1e-9", "f64 order Δ"], rows))


if __name__ == "__main__":
    main()
