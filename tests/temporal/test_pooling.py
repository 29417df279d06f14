"""Shot pooling of the light solve's evidence: offline per segment/window, causal with a gate."""

import torch

from relightnet.sh.light_solve import Evidence, light_evidence, solve_light
from relightnet.temporal import PooledSolve, pool_shot_lights
from relightnet.temporal.distance import light_distance, light_norm
from relightnet.temporal.pooling import pooling_weights


def _frames(lights, n_pix=200, noise=0.05, seed=0):
    """Per-frame evidence of frames that see different (random) transport under the given lights."""
    g = torch.Generator().manual_seed(seed)
    Ms, rs = [], []
    for L in lights:
        T = torch.randn(1, 9, n_pix, 1, generator=g)
        A = torch.rand(1, 3, n_pix, 1, generator=g) * 0.5 + 0.25
        I = A * torch.einsum("bkhw,kc->bchw", T, L)
        I = I + noise * torch.randn(I.shape, generator=g)  # the frame's own estimation error
        ev = light_evidence(I, A, T, torch.ones(1, 1, n_pix, 1))
        Ms.append(ev.M)
        rs.append(ev.r)
    return Evidence(torch.cat(Ms), torch.cat(rs))


def _light(seed):
    dc = torch.zeros(9, 1)
    dc[0] = 3.0
    return torch.randn(9, 3, generator=torch.Generator().manual_seed(seed)) + dc


def test_weights_respect_segments_and_windows():
    sw = torch.zeros(6, dtype=torch.bool)
    sw[3] = True
    w = pooling_weights(sw)
    assert w[0, 3] == 0 and w[4, 5] == 1 and w[0, 2] == 1
    tri = pooling_weights(sw, window=2)
    assert tri[0, 0] == 1 and tri[0, 1] == 0.5 and tri[0, 2] == 0


def test_constant_light_gives_a_constant_estimate_closer_to_the_truth():
    L = _light(1)
    ev = _frames([L] * 20, noise=0.3)
    pooled, per_frame, switches = pool_shot_lights(ev, None, 1e-6, switches=None)
    assert not switches.any()
    assert torch.allclose(pooled, pooled[:1].expand_as(pooled))
    err_pooled = light_distance(pooled[0], L) / light_norm(L)
    err_frames = (light_distance(per_frame, L) / light_norm(L)).mean()
    assert err_pooled < 0.5 * err_frames


def test_a_switch_splits_the_pool():
    a, b = _light(2), _light(3) * 1.5
    ev = _frames([a] * 15 + [b] * 15, noise=0.05)
    pooled, _, switches = pool_shot_lights(ev, None, 1e-6)
    assert switches.nonzero().flatten().tolist() == [15]
    assert float(light_distance(pooled[:15], a).max() / light_norm(a)) < 0.05
    assert float(light_distance(pooled[15:], b).max() / light_norm(b)) < 0.05


def test_prior_is_pooled_with_the_evidence():
    L = _light(4)
    ev = _frames([L] * 6)
    prior = L.expand(6, 9, 3) + 0.1
    strong = pool_shot_lights(ev, prior, 1e4, switches=None)[0]
    assert torch.allclose(strong, prior, atol=1e-2)


def test_causal_pool_settles_and_follows_a_switch():
    a, b = _light(5), _light(6) * 2
    lights = [a] * 20 + [b] * 10
    ev = _frames(lights, noise=0.2)
    per_frame = solve_light(ev, None, 1e-6)
    f = PooledSolve(alpha=0.02, reg=1e-6)
    state, ys = None, []
    for t in range(len(lights)):
        first = torch.tensor([t == 0])
        y, state = f(per_frame[t:t + 1], state, first, evidence=Evidence(ev.M[t:t + 1], ev.r[t:t + 1]))
        ys.append(y[0])
        assert state.shape == (1, 15, 9, 3)
    ys = torch.stack(ys)
    # constant part: the pooled estimate moves less and is closer to the truth than the per-frame one
    step = light_distance(ys[11:20], ys[10:19]).mean()
    raw_step = light_distance(per_frame[11:20], per_frame[10:19]).mean()
    assert step < 0.3 * raw_step
    assert light_distance(ys[19], a) < light_distance(per_frame[10:20], a).mean()
    # the switch is taken within 2 frames (persist = 2)
    assert float(light_distance(ys[22], b) / light_norm(b)) < 0.25


def test_causal_pool_equals_the_offline_pool_on_a_constant_shot():
    """Before the floor on the new frame's weight is reached, the running mean is the offline pool."""
    L = _light(7)
    ev = _frames([L] * 8, noise=0.01)
    per_frame = solve_light(ev, None, 1e-3)
    f = PooledSolve(alpha=0.01, reg=1e-3)
    state = None
    for t in range(8):
        y, state = f(per_frame[t:t + 1], state, torch.tensor([t == 0]), evidence=Evidence(ev.M[t:t + 1], ev.r[t:t + 1]))
    offline = pool_shot_lights(ev, None, 1e-3, switches=None)[0][-1]
    assert torch.allclose(y[0], offline, atol=1e-4)


def test_a_window_follows_a_turning_light():
    from relightnet.sh import rotate_sh_up
    from relightnet.temporal.pooling import POOL_SECONDS, pool_window

    base = _light(8)
    lights = [rotate_sh_up(base, 0.05 * t) for t in range(40)]  # ~90° over the shot, no switch
    ev = _frames(lights, noise=0.05)
    truth = torch.stack(lights)
    win = pool_shot_lights(ev, None, 1e-6, window=pool_window(10.0, 0.5), switches=None)[0]
    shot = pool_shot_lights(ev, None, 1e-6, switches=None)[0]
    rel = lambda x: float((light_distance(x, truth) / light_norm(truth)).mean())  # noqa: E731
    assert rel(win) < 0.5 * rel(shot)
    assert pool_window(30.0) == round(30 * POOL_SECONDS) and pool_window(0.5, 1.0) == 1


def test_a_switch_half_way_through_a_short_shot_is_found():
    """24 frames with the switch at 12: most jump values are near the step, so a threshold over
    them (the offline smoothers' 8 MAD) finds nothing; one over the frame noise finds it."""
    from relightnet.temporal import detect_switches
    from relightnet.temporal.offline import frame_noise
    from relightnet.temporal.pooling import SWITCH_NOISE

    a, b = _light(4), _light(5)
    ev = _frames([a] * 12 + [b] * 12, noise=0.3, seed=1)
    pooled, per_frame, switches = pool_shot_lights(ev, None, 1e-6)
    assert not detect_switches(per_frame.double()).any()
    assert switches.nonzero().flatten().tolist() == [12]
    assert float(light_distance(pooled[12:], b).max() / light_norm(b)) < 0.05
    # the same shot without the switch: none found, one pooled light
    ev = _frames([a] * 24, noise=0.3, seed=1)
    pooled, per_frame, switches = pool_shot_lights(ev, None, 1e-6)
    assert not switches.any() and float(frame_noise(per_frame)) > 0
    assert not detect_switches(per_frame.double(), eps=None, noise=SWITCH_NOISE).any()


def test_a_turning_light_is_a_changing_segment_and_a_noisy_constant_one_is_not():
    from relightnet.sh import rotate_sh_up
    from relightnet.temporal import changing_segments
    from relightnet.temporal.pooling import CHANGE_EXPLAINED

    base = _light(8)
    turning = torch.stack([rotate_sh_up(base, 0.05 * t) for t in range(40)])
    noisy = base + 0.3 * torch.randn(40, 9, 3, generator=torch.Generator().manual_seed(0))
    none = torch.zeros(40, dtype=torch.bool)
    assert changing_segments(turning, none).all()
    assert not changing_segments(noisy, none).any()
    both = torch.cat([noisy, turning])
    sw = torch.zeros(80, dtype=torch.bool)
    sw[40] = True
    flags = changing_segments(both, sw)
    assert not flags[:40].any() and flags[40:].all()
    assert not changing_segments(turning[:3], none[:3]).any()  # too short to tell
    assert 0 < CHANGE_EXPLAINED < 1


def test_the_video_jobs_pool_a_constant_light_over_the_whole_shot_and_follow_a_turning_one():
    from relightnet.sh import rotate_sh_up
    from relightnet.temporal import smooth_video_lights

    a = _light(9)
    ev = _frames([a] * 90, noise=0.3, seed=2)
    per_frame = solve_light(ev, None, 1e-6)
    res = smooth_video_lights(per_frame, "pooled", ev, None, 1e-6, fps=30.0)
    assert res.method == "pooled" and not res.switches.any()
    assert torch.allclose(res.smoothed, res.smoothed[:1].expand_as(res.smoothed))  # one light: no drift
    whole = pool_shot_lights(ev, None, 1e-6, switches=None)[0]
    torch.testing.assert_close(res.smoothed, whole)
    lights = [rotate_sh_up(a, 0.05 * t) for t in range(90)]  # ~260° over the shot
    ev = _frames(lights, noise=0.05, seed=3)
    res = smooth_video_lights(solve_light(ev, None, 1e-6), "pooled", ev, None, 1e-6, fps=10.0)
    truth = torch.stack(lights)
    err = float((light_distance(res.smoothed, truth) / light_norm(truth)).mean())
    shot = pool_shot_lights(ev, None, 1e-6, switches=None)[0]
    assert err < 0.5 * float((light_distance(shot, truth) / light_norm(truth)).mean())


def test_a_switch_seen_in_the_frames_colour_splits_the_shot():
    """The lights alone scatter too much to show the step; the frames' colour shows it at its frame."""
    from relightnet.temporal import smooth_video_lights

    a, b = _light(10), _light(10) * 0.8
    ev = _frames([a] * 30 + [b] * 30, noise=1.5, seed=4)
    per_frame = solve_light(ev, None, 1e-6)
    colour = torch.cat([torch.full((30, 3), 0.4), torch.full((30, 3), 0.32)]).double()
    plain = smooth_video_lights(per_frame, "pooled", ev, None, 1e-6, fps=30.0)
    seen = smooth_video_lights(per_frame, "pooled", ev, None, 1e-6, fps=30.0, colour=colour)
    assert not plain.switches.any()
    assert seen.switches.nonzero().flatten().tolist() == [30]
    err = lambda x, y: float(light_distance(x, y) / light_norm(y))  # noqa: E731
    assert err(seen.smoothed[0], a) < err(plain.smoothed[0], a)
    assert err(seen.smoothed[-1], b) < err(plain.smoothed[-1], b)


def test_pooled_sums_are_the_weights_times_the_frames_without_the_weights():
    from relightnet.temporal.pooling import pooled_sums

    g = torch.Generator().manual_seed(5)
    x = torch.randn(40, 7, generator=g, dtype=torch.float64)
    sw = torch.zeros(40, dtype=torch.bool)
    sw[[13, 31]] = True
    windowed = torch.zeros(40, dtype=torch.bool)
    windowed[13:31] = True
    for window, rows in ((None, None), (5, None), (5, windowed), (60, windowed)):
        torch.testing.assert_close(pooled_sums(x, sw, window, rows), pooling_weights(sw, window, rows) @ x)
