"""Light switches seen in the frames themselves: a step of the whole frame's colour.

A light that is switched, dimmed or recoloured changes every pixel of the frame at once; a person
turning or walking changes only their own pixels, and gradually. The frame's mean linear colour
(:func:`frame_colour`, three numbers a frame) therefore shows a switch as a clean step, far above
its frame-to-frame noise, even where the network's per-frame light scatters too much for the step
to stand out (on real footage of a person turning, the light estimate's 5-frame jump at a switch
to 0.6× the level was 2.9 where the threshold over its noise was 3.5, while the frame colour
stepped by 0.29–0.81 in log units over a noise of 0.0006). :func:`colour_switches` finds those
steps; :func:`merge_switches` joins them with the ones found in the lights
(:func:`~relightnet.temporal.offline.detect_switches`), the colour's frame winning where both
found the same switch.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from ..checks import InputError, check_shape
from ..color import srgb_to_linear
from .offline import running_median

__all__ = ["COLOUR_STEP", "frame_colour", "colour_switches", "merge_switches"]

#: The smallest step of a frame's mean colour (log units, in any channel: 0.05 ≈ 5%) taken as a light
#: switch; below it a missed switch moves the shot's pooled light by less than half of it.
COLOUR_STEP = 0.05


def frame_colour(image: torch.Tensor, stride: int = 4) -> torch.Tensor:
    """The mean linear RGB of a frame, from every ``stride``-th pixel of every ``stride``-th row.

    Args:
        image: (3, H, W) sRGB, float in [0, 1] or uint8.

    Returns:
        (3,) float64.
    """
    check_shape(image, [3, "H", "W"], name="frame")
    x = image[:, ::stride, ::stride].double()
    return srgb_to_linear(x / 255 if image.dtype == torch.uint8 else x).mean((1, 2))


def colour_switches(colour: torch.Tensor, window: int = 5, noise: float = 8.0, min_step: float = COLOUR_STEP
                    ) -> torch.Tensor:
    """Frames where the whole frame's colour steps and stays (module docstring).

    The log colour is cleaned by a 5-frame running median (a flash or one odd frame is no switch);
    the jump at frame t is the largest change over the channels between the means of the
    ``window`` cleaned frames before and after t. A jump is a switch when it is at least
    ``min_step`` and ``noise`` times the median frame-to-frame change, the largest within
    ``window`` frames, and twice the jumps ``window`` frames to either side (a fade or a pan, whose
    jump profile is flat, is none). The switch is put on the frame of the largest single-frame
    change of the raw colour near it.

    Args:
        colour: (T, C) positive mean colours of the frames (:func:`frame_colour`).
        window: frames on each side; no switch within ``window`` frames of the ends.
        noise, min_step: the thresholds above.

    Returns:
        (T,) bool, True on the first frame after each switch.
    """
    dims = check_shape(colour, ["T", "C"], name="frame colours")
    if not (noise > 0 and min_step > 0) or int(window) != window or window < 1:
        raise InputError(f"colour switches: expected a positive window, noise and step, got {window!r}, "
                         f"{noise!r}, {min_step!r}")
    t_len, out = dims["T"], torch.zeros(dims["T"], dtype=torch.bool)
    if t_len < 2 * window + 1:
        return out
    y = colour.double().clamp_min(1e-6).log()
    c = running_median(y[None], 5)[0]
    csum = F.pad(c.cumsum(0), (0, 0, 1, 0))
    t = torch.arange(window, t_len - window + 1)
    jump = ((csum[t + window] - 2 * csum[t] + csum[t - window]) / window).abs().amax(1)  # right mean − left mean
    step = (y[1:] - y[:-1]).abs().amax(1)  # step[j]: between frames j and j + 1
    thr = max(float(min_step), float(noise) * float(step.median()))
    peak = F.max_pool1d(jump[None, None], 2 * window + 1, 1, window)[0, 0]
    first = torch.ones_like(jump, dtype=torch.bool)
    first[1:] = jump[1:] > jump[:-1]
    pad = F.pad(jump[None, None], (window, window), mode="replicate")[0, 0]
    hit = (jump >= thr) & (jump >= peak) & first & (jump > 2 * torch.maximum(pad[:-2 * window], pad[2 * window:]))
    for i in hit.nonzero().flatten().tolist():
        lo, hi = int(t[i]) - 2, int(t[i]) + 2  # the switch frame s: the step between s − 1 and s
        lo, hi = max(lo, 1), min(hi, t_len - 1)
        out[lo + int(step[lo - 1:hi].argmax())] = True
    return out


def merge_switches(from_lights: torch.Tensor, from_colour: torch.Tensor | None, window: int = 5) -> torch.Tensor:
    """(T,) bool: the switches of both detectors; one found in the lights within ``window`` frames of one
    found in the colour is the same switch, kept at the colour's frame."""
    if from_colour is None:
        return from_lights
    check_shape(from_colour, [from_lights.shape[0]], name="colour switches")
    near = F.max_pool1d(from_colour.double()[None, None], 2 * window + 1, 1, window)[0, 0] > 0
    return from_colour.bool() | (from_lights.bool() & ~near)
