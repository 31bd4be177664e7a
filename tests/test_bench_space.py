"""granframe bench --space on a small run: one step of the problem and its parts are timed
through the problem contract, and the record is JSON (what the subprocess prints)."""

import json

import pytest

from granframe.tools.bench import measure_space, space_table


def test_a_space_step_is_timed_and_reported():
    record = measure_space(2, 24, 8, 8, 8, "numpy", 1, 1)
    json.dumps(record)
    assert record["backend"] == "numpy" and record["cells"] == 8
    assert record["step_s"] > 0 and record["moments_s"] > 0 and record["target_s"] > 0
    assert abs(record["step_over_target"] - (record["step_s"] + record["moments_s"])
               / record["target_s"]) < 1e-12
    assert "| 2D N = 24 | 8 |" in space_table([record])


def test_a_rectangle_is_a_space_configuration_of_two_cell_counts():
    from granframe.tools.bench import parse_space_config

    assert parse_space_config("2:32:64x64") == (2, 32, (64, 64), 32, 16)
    assert parse_space_config("3:16:16x8:30:32") == (3, 16, (16, 8), 30, 32)
    for bad in ("2:32:64x", "2:32:4x4x4", "2:32:ax4"):
        with pytest.raises(ValueError, match="parameter 'space' = .* is invalid; use "
                                             "D:N:CELLS"):
            parse_space_config(bad)
