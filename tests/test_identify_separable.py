import numpy as np
import pytest

from flatstep.studies.identify import moving_samples
from flatstep.studies.identify_ls import fit
from flatstep.studies.identify_separable import VIF_MAX, check_separable
from flatstep.studies.record import Recording


def test_a_near_collinear_pair_is_refused_with_the_combination_it_determines():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(2000)
    X = np.column_stack([x + 0.01 * rng.standard_normal(2000), 50.0 * x, rng.standard_normal(2000)])
    y = X @ np.array([0.27, 0.0095, 1.0]) + 1e-3 * rng.standard_normal(2000)
    result = fit([(X, y)], ["Km", "L", "R"], lags=0, source="s.csv", hint="h")
    assert result.vif[0] > VIF_MAX and result.vif[2] < 1.1
    with pytest.raises(ValueError, match=r"s.csv: Km and L cannot be separated .* only Km \+ 50\.\d* L = 0\.74\d* is "
                                         r"determined .*change the current norm"):
        check_separable(result, "s.csv", "h")
    check_separable(fit([(X[:, 1:], y)], ["L", "R"], lags=0, source="s.csv", hint="h"), "s.csv", "h")  # no error


def test_an_encoder_toggling_at_rest_is_not_motion():
    t = np.arange(20000) * 5e-5
    q = 2 * np.pi / 16384
    move = np.clip((t - 0.3) / 0.2, 0, 1) * 2.0  # 2 rad between 0.3 and 0.5 s
    hunt = q * (np.sin(2 * np.pi * 146 * t) > 0)  # one count, back and forth at 146 Hz
    theta = q * np.round((move + hunt) / q)
    rec = Recording(t=t, va=t, vb=t, ia=t, ib=t, theta=theta)
    moving = moving_samples(rec, 100.0)
    assert moving.size == t.size - 1
    rest = ((t[:-1] > 0.035) & (t[:-1] < 0.2)) | ((t[:-1] > 0.6) & (t[:-1] < 0.965))  # beyond the filter's start-up
    assert not moving[rest].any() and moving[(t[:-1] > 0.31) & (t[:-1] < 0.49)].all()
