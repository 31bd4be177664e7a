"""The health checks' messages name the description's setting (``health.<name>``) and show a
value and its limit with digits enough to tell them apart."""

import re

import pytest

import granframe as gf
from granframe.model.initial import check_fits
from granframe.run.description import Health
from granframe.run.runner import health_problem
from granframe.validators import distinct

GOOD = {"mass": 1.0, "kinetic_energy": 1.0, "min_f": 0.0, "negative_mass_fraction": 0.0}


@pytest.mark.parametrize("value, limit, shown", [
    (0.01004, 0.01, ("0.01004", "0.01")),         # 3 digits would read 0.01 and 0.01
    (0.0100000002, 0.01, ("0.0100000002", "0.01")),
    (2.5e-8, 1e-8, ("2.5e-08", "1e-08")),          # 3 digits already differ
    (0.25, 0.25, ("0.25", "0.25")),                # equal values stay equal
])
def test_distinct_widens_until_value_and_limit_differ(value, limit, shown):
    assert distinct(value, limit) == shown


def test_mass_drift_names_health_mass_tolerance_with_distinct_numbers():
    message = health_problem({**GOOD, "mass": 1.0 + 1.0004e-8}, 1.0, Health())
    assert re.fullmatch(r"mass drift \|mass/mass\(0\) - 1\| = 1\.0004e-08 exceeds "
                        r"health\.mass_tolerance = 1e-08", message), message


def test_loss_of_positivity_names_health_positivity_tolerance_with_distinct_numbers():
    record = {**GOOD, "negative_mass_fraction": 0.01004, "min_f": -0.002}
    message = health_problem(record, 1.0, Health(positivity_tolerance=0.01))
    assert message == ("loss of positivity: negative mass share 0.01004 exceeds "
                       "health.positivity_tolerance = 0.01 (min f = -0.002)")


@pytest.mark.parametrize("temperature, setting", [
    (60.0, r"must be <= health\.edge_tolerance = 1e-08: "),             # wraps around
    (0.01, r"must be <= health\.initial_mass_tolerance = 1e-06 \("),     # narrower than h
])
def test_initial_data_refusals_name_the_health_setting(temperature, setting):
    grid = gf.VelocityGrid(2, 16, 4.0)
    initial = gf.initial_condition("maxwellian", temperature=temperature)
    health = Health()
    with pytest.raises(ValueError, match=setting):
        check_fits(grid, initial.sample(grid), initial, health.edge_tolerance,
                   health.initial_mass_tolerance)
