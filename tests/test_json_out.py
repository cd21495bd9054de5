"""Every JSON that flatstep writes is JSON: non-finite numbers become null."""
import json
import math

import numpy as np
import pytest

from flatstep.json_out import finite_or_none, strict_json


def test_non_finite_numbers_become_null_at_any_depth():
    obj = {"a": math.nan, "b": [1.0, math.inf, {"c": -math.inf, "d": np.float64("nan")}], "e": (np.float32(2.5),)}
    text = strict_json(obj)
    assert json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in {text}")) == {
        "a": None, "b": [1.0, None, {"c": None, "d": None}], "e": [2.5]}
    assert finite_or_none({"x": 1, "y": "s", "z": None}) == {"x": 1, "y": "s", "z": None}


def test_a_summary_without_rest_samples_is_valid_json(tmp_path, capsys):
    """A horizon that ends with the move has no samples after it: its 'after' metrics are null, not NaN."""
    from flatstep.cli import main

    assert main(["simulate", "--t-end", "0.04", "--json"]) == 0
    out = capsys.readouterr().out
    json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in the output"))
