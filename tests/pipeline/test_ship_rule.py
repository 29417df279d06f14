import pytest

from relightnet.cli import main
from relightnet.pipeline.ship_rule import (
    FLOOR_METRICS,
    INFO_METRICS,
    SCORE_METRICS,
    format_ship_report,
    ship_decision,
)


def _figures(**change):
    base = {k: 0.2 for k in (*FLOOR_METRICS, *SCORE_METRICS, *INFO_METRICS)}
    base |= {"relit_psnr_as_photos": 20.0, "relit_psnr_as_rendered": 20.0, "photo_side_contrast": 6.0}
    return base | change


def test_a_candidate_that_keeps_the_floors_and_lowers_the_light_errors_ships():
    inc = _figures()
    cand = _figures(light_error_as_photos=0.1, compare_light_error=0.2, photo_round_trip=0.22,
                    shading_rmse_as_photos=0.209, light_error_as_rendered=0.3)  # 4.5% worse: within the floor
    d = ship_decision(inc, cand)
    assert d["ships"] and d["score"] == pytest.approx((0.5 + 1 + 1.1) / 3)
    assert d["floors"]["shading_rmse_as_photos"]["worse"] == pytest.approx(0.045)
    assert "candidate ships" in format_ship_report(inc, cand)


@pytest.mark.parametrize("change,reason", [
    ({"albedo_rmse_as_photos": 0.22}, "albedo_rmse_as_photos 10.0% worse"),
    ({"relit_psnr_as_photos": 18.0}, "relit_psnr_as_photos 10.0% worse"),  # higher is better
    ({"photo_side_contrast": 3.5}, "side contrast 3.50 < 4"),
])
def test_a_broken_floor_blocks_however_good_the_score(change, reason):
    cand = _figures(light_error_as_photos=0.05, **change)
    d = ship_decision(_figures(), cand)
    assert not d["ships"] and d["score"] < 1 and any(reason in r for r in d["reasons"])


def test_no_gain_in_the_light_errors_does_not_ship():
    d = ship_decision(_figures(), _figures(light_error_as_photos=0.18, photo_round_trip=0.23))
    assert not d["ships"] and d["score"] > 1 and "do not improve" in d["reasons"][0]
    # Figures reported beside the rule do not change it.
    assert ship_decision(_figures(), _figures(light_error_as_photos=0.1, light_error_as_rendered=0.9))["ships"]


def test_evaluate_ship_checks_its_options_before_any_work(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", "ship", "shipped", "x.pt", "--out", str(tmp_path / "r")])
    assert "the following arguments are required: --data, --clips, --photos" in capsys.readouterr().err
    (tmp_path / "photos").mkdir()
    assert main(["evaluate", "ship", "shipped", str(tmp_path / "x.pt"), "--data", str(tmp_path), "--clips",
                 str(tmp_path), "--photos", str(tmp_path / "photos"), "--out", str(tmp_path / "r")]) == 1
    assert "no photos" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
