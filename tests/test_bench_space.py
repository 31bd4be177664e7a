"""granframe bench --space on a small run: one step of the problem and its parts are timed
through the problem contract, and the record is JSON (what the subprocess prints)."""

import json

from granframe.tools.bench import measure_space, space_table


def test_a_space_step_is_timed_and_reported():
    record = measure_space(2, 24, 8, 8, 8, "numpy", 1, 1)
    json.dumps(record)
    assert record["backend"] == "numpy" and record["cells"] == 8
    assert record["step_s"] > 0 and record["moments_s"] > 0 and record["target_s"] > 0
    assert abs(record["step_over_target"] - (record["step_s"] + record["moments_s"])
               / record["target_s"]) < 1e-12
    assert "| 2D N = 24 | 8 |" in space_table([record])
