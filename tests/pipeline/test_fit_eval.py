"""The fit's evaluation on generated clips: a real fit of a generated clip against its true body."""

import math

import pytest

from relightnet.checks import InputError
from relightnet.fit import FitBody, FitOptions
from relightnet.pipeline.fit_eval import FIT_METRICS, evaluate_fit_clip, fit_eval_config, format_fit_report
from relightnet.segment import PersonModels


def test_the_config_is_checked():
    cfg = fit_eval_config(2, 3, 128)
    assert cfg.counts["test"] == 2 and cfg.sequence_frames == 3 and cfg.res == 128
    for bad in ((0, 3, 128), (1, 1, 128), (1, 3, 100), (1, 3, 48)):
        with pytest.raises(InputError, match="fit evaluation"):
            fit_eval_config(*bad)


@pytest.mark.slow
def test_a_clip_is_fitted_and_measured(anny_body):
    cfg = fit_eval_config(1, 3, 192)
    row = evaluate_fit_clip(cfg, 0, FitBody(anny_body), PersonModels(threads=1),
                            FitOptions(iters=30, warm_iters=10, window=3))
    assert set(row) == {*FIT_METRICS, "motion"} and all(math.isfinite(row[k]) for k in FIT_METRICS)
    # a fit, even a short one: within a person's scale of the truth, its outline overlapping the body's
    assert 0 < row["pa_mpjpe"] < 250 and 0 < row["mpjpe"] < 250
    assert 0.5 < row["iou_body"] <= 1 and 0.5 < row["seg_iou_true"] <= 1
    text = format_fit_report({"clips": [row], "median": {k: row[k] for k in FIT_METRICS}})
    assert text.count("\n") == len(FIT_METRICS) + 1 and f"clip 0 ({row['motion']})" in text
