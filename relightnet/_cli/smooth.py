"""``relightnet smooth-light``: smooth a light sequence over time, correct outliers, plot it."""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..names import OFFLINE_METHODS, SEQUENCE_SMOOTHING, SMOOTHING_METHODS, smoothing_help, smoothing_names
from .argtypes import nonneg_int, pos_float, pos_int
from .options import add_command, check_method_options, method_options
from .paths import out_file

logger = logging.getLogger("relightnet.smooth")


def _smooth(args, sh):
    """(smoothed, outliers (T,) bool, switches (T,) bool) for the chosen method (the registry's
    :func:`relightnet.temporal.smooth_sequence`; the command's defaults for each method's options)."""
    from ..checks import InputError
    from ..temporal.distance import parse_eps
    from ..temporal.registry import smooth_sequence

    eps = parse_eps(args.outlier_eps)
    deg = 2 if args.degree is None else args.degree
    if not SMOOTHING_METHODS[args.smoothing].causal:
        opts = {"hermite": {"knot_spacing": args.knots, "tangents": args.tangents},
                "poly": {"degree": deg, "window": 15 if args.window is None else (args.window or None)},
                "savgol": {"degree": deg, "window": 9 if args.window is None else args.window}}[args.smoothing]
        res = smooth_sequence(sh, args.smoothing, outlier_eps=args.outlier_eps, iterations=args.iterations,
                              switches=None if args.switches == "none" else "auto", **opts)
        return res.smoothed, res.outliers, res.switches
    if eps is not None and eps[0] != "mad":
        raise InputError(
            f"--outlier-eps: causal methods take 'none' or '<c>mad' (c times the running innovation scale), "
            f"got {args.outlier_eps!r}"
        )
    opts = {"ema": {"alpha": args.alpha},
            "one-euro": {"min_cutoff": args.min_cutoff, "beta": args.beta, "rate": args.rate},
            "fir": {"window": 5 if args.window is None else args.window, "degree": args.degree or 0},
            "gated-one-euro": {"persist": args.persist, **({"eps": eps[1]} if eps is not None else {})},
            "none": {}}[args.smoothing]
    gate = None if eps is None or args.smoothing in ("gated-one-euro", "none") else {"eps": eps[1],
                                                                                  "persist": args.persist}
    res = smooth_sequence(sh, args.smoothing, gate=gate, **opts)
    return res.smoothed, res.outliers, res.switches


def run_smooth(args: argparse.Namespace) -> int:
    from ..checks import ShapeError
    from ..io.atomic import atomic_write
    from ..light import load_light
    from ..sh.io import load_light_sequence, save_light, save_light_sequence
    from ..temporal import jitter, light_error
    from ..temporal.distance import parse_eps
    from ..temporal.plot import light_curves_png

    check_method_options(args, args.smoothing)
    parse_eps(args.outlier_eps)
    out = out_file(args.output, "OUT", (".npz", ".json"), inputs=(args.input,))
    plot = out_file(args.plot, "--plot", (".png",), inputs=(args.input,)) if args.plot else None
    sh, side = load_light_sequence(args.input, ("raw",))
    if "raw" in side:  # a smoothed file (avatar's OUT.lights.npz, our own output): start again from its estimates
        sh = load_light(side["raw"])
        if sh.dim() != 3:
            raise ShapeError(f"{args.input}: 'raw' must be (T, K, 3), got {tuple(sh.shape)}")
        logger.info("%s: smoothing its raw estimates ('raw' array)", args.input)
    if sh.shape[0] < 2:
        raise ShapeError(f"{args.input}: expected at least 2 frames, got {sh.shape[0]}")
    truth = None
    if args.truth:
        truth = load_light(args.truth)
        if tuple(truth.shape) != tuple(sh.shape):
            raise ShapeError(f"{args.truth}: expected the input's shape {tuple(sh.shape)}, got {tuple(truth.shape)}")

    smoothed, outliers, switches = _smooth(args, sh)
    smoothed = smoothed.detach()
    n_out = int(outliers.sum())
    summary = f"{args.smoothing}: {sh.shape[0]} frames, {n_out} outlier(s)"
    if bool(switches.any()):
        summary += f", switches at frames {switches.nonzero().flatten().tolist()}"
    if truth is not None and sh.shape[0] >= 3:
        e0, e1 = light_error(sh, truth).item(), light_error(smoothed, truth).item()
        j0, j1 = jitter(sh).item(), jitter(smoothed).item()
        summary += f"; error to truth {e0:.4g} -> {e1:.4g}, jitter {j0:.4g} -> {j1:.4g}"
    title = f"{Path(args.input).name}: {summary}"
    png = light_curves_png(sh, smoothed, truth, outliers, switches, title) if plot else None

    if out.suffix.lower() == ".npz":
        save_light_sequence(out, smoothed, raw=sh, outliers=outliers, switches=switches, smoothing=args.smoothing)
    else:
        save_light(out, smoothed)
    if png is not None:
        with atomic_write(plot) as f:
            f.write(png)
    logger.info("wrote %s (%s)%s", out, summary, f" and {plot}" if plot else "")
    return 0


def register(sub) -> None:
    p = add_command(
        sub,
        "smooth-light",
        "Smooth a light sequence (T, K, 3) over time: offline regression (hermite spline, poly, savgol) with "
        "outlier correction and switch splitting, or a causal filter (ema, one-euro, fir) as used on live video.",
        "  relightnet smooth-light lights.npz smooth.npz --smoothing hermite --knots 8 --outlier-eps 3mad\n"
        "  relightnet smooth-light lights.npz smooth.npz --truth true.npz --plot plot.png\n"
        "  relightnet smooth-light lights.npz smooth.npz --smoothing savgol --window 11 --degree 2\n"
        "  relightnet smooth-light lights.npz live.npz --smoothing one-euro --min-cutoff 0.5 --beta 1\n",
    )
    p.add_argument("input", metavar="IN", help="light sequence .npz/.json with sh (T, K, 3); when it also holds "
                   "'raw' (the estimates a smoothed file was made from: avatar's OUT.lights.npz, this command's "
                   ".npz output), those are smoothed")
    p.add_argument("output", metavar="OUT", help="smoothed sequence: .npz (sh = smoothed, with raw, outliers, "
                   "switches) or .json (sh only)")
    p.add_argument("--smoothing", default="hermite", choices=SEQUENCE_SMOOTHING,
                   help=smoothing_help(SEQUENCE_SMOOTHING, "hermite"))
    p.add_argument("--knots", type=pos_float, default=8.0, help="hermite: frames between knots (default: %(default)g)")
    p.add_argument("--tangents", choices=("catmull-rom", "free"), default="catmull-rom",
                   help="hermite: knot tangents from finite differences or fitted (default: %(default)s)")
    p.add_argument("--degree", type=int, default=None,
                   help="poly/savgol: polynomial degree (default 2); fir: 0 = moving average, 1 = linear")
    p.add_argument("--window", type=nonneg_int, default=None,
                   help="poly: local window (default 15; 0 = one polynomial per segment); savgol: odd window "
                        "(default 9); fir: taps (default 5)")
    p.add_argument("--outlier-eps", default="3mad",
                   help="outlier threshold: '<c>mad' (c robust deviations above the median distance), an "
                        "absolute light distance, or 'none' (default: %(default)s); causal: '<c>mad' = c times the "
                        "running innovation scale")
    p.add_argument("--switches", choices=("auto", "none"), default="auto",
                   help="offline: split the sequence at persistent jumps (default: %(default)s)")
    p.add_argument("--iterations", type=pos_int, default=3, help="offline outlier passes (default: %(default)s)")
    p.add_argument("--alpha", type=pos_float, default=0.3, help="ema: weight of the new frame (default: %(default)g)")
    p.add_argument("--min-cutoff", type=pos_float, default=0.5,
                   help="one-euro: cutoff at rest, Hz (default: %(default)g)")
    p.add_argument("--beta", type=float, default=1.0,
                   help="one-euro: cutoff gain per unit speed (default: %(default)g)")
    p.add_argument("--rate", type=pos_float, default=30.0, help="one-euro: frames per second (default: %(default)g)")
    p.add_argument("--persist", type=pos_int, default=2,
                   help="causal: frames a jump must last to count as a switch (default: %(default)s)")
    p.add_argument("--truth", default=None, help="true light sequence, for the error and the plot")
    p.add_argument("--plot", default=None, help="write a .png of raw/smoothed/true coefficients over time")
    offline, causal = OFFLINE_METHODS, tuple(n for n in smoothing_names(causal=True) if n in SEQUENCE_SMOOTHING)
    method_options(p, {"knots": ("hermite",), "tangents": ("hermite",), "degree": ("poly", "savgol", "fir"),
                       "window": ("poly", "savgol", "fir"), "switches": offline, "iterations": offline,
                       "alpha": ("ema",), "min_cutoff": ("one-euro",), "beta": ("one-euro",),
                       "rate": ("one-euro",), "persist": causal})
    p.set_defaults(func=run_smooth)
