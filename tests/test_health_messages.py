"""The health checks' messages name the description's setting (``health.<name>``) and show a
value and its limit with digits enough to tell them apart."""

import re

import pytest

import granframe as gf
from granframe.model.initial import check_fits
from granframe.run.description import Health
from granframe.run.runner import RINGING, UNSTABLE, health_problem
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
                        r"health\.mass_tolerance = 1e-08; the collision step does not conserve "
                        r"mass: conservative = true .*", message), message


def test_loss_of_positivity_names_health_positivity_tolerance_with_distinct_numbers():
    record = {**GOOD, "negative_mass_fraction": 0.01004, "min_f": -0.002}
    message = health_problem(record, 1.0, Health(positivity_tolerance=0.01))
    assert message == ("loss of positivity: negative mass share 0.01004 exceeds "
                       "health.positivity_tolerance = 0.01 (min f = -0.002); " + RINGING)


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


def test_every_health_stop_says_what_to_change():
    """Each message ends with the settings to change: the step and the box for a blow-up,
    the conservative correction for a mass drift, n_modes, support_radius and the step for
    a loss of positivity."""
    health = Health()
    blown = health_problem({**GOOD, "mass": float("nan")}, 1.0, health)
    empty = health_problem({**GOOD, "mass": -1.0}, 1.0, health)
    for message in (blown, empty):
        assert message.endswith(UNSTABLE)
        assert all(s in message for s in ("time_step", "grid.support_radius", "conservative"))
    drift = health_problem({**GOOD, "mass": 1.1}, 1.0, health)
    assert "conservative = true" in drift and "grid.n_modes" in drift
    ringing = health_problem({**GOOD, "negative_mass_fraction": 0.5}, 1.0, health)
    assert all(s in ringing for s in ("grid.n_modes", "grid.support_radius", "time_step"))


def _maxwellian_run(space: bool, n_modes: int):
    from granframe.run.description import RunDescription

    return RunDescription(
        grid={"dimension": 3, "n_modes": n_modes, "support_radius": 3.0},
        kernel="hard_spheres", restitution={"name": "constant", "value": 1.0},
        initial={"name": "maxwellian", "temperature": 0.37},
        operator={"name": "fast_spectral"}, integrator="ssp_rk2", time_step=0.01,
        final_time=0.01, **({"space": {"cells": 6}} if space else {}))


@pytest.mark.parametrize("space", [False, True])
def test_initial_data_that_the_first_health_check_would_stop_is_refused(space):
    """A uniform 3D Maxwellian of T = 0.37 on N = 20, S = 3: its Nyquist projection leaves a
    negative mass share of 3.1 %, above health.positivity_tolerance = 1 %, which would stop
    the run at its first step: refused before anything is written, naming the setting,
    the cell and what to change; N = 28 is accepted."""
    from granframe.run.runner import Simulation

    with pytest.raises(ValueError, match=r"negative mass share of f0 after the Nyquist projection'"
                                         r" = 0\.03.*health\.positivity_tolerance = 0\.01.*"
                                         r"grid\.n_modes.*grid\.support_radius") as error:
        Simulation(_maxwellian_run(space, 20))
    assert ("in cell 0 of 6" in str(error.value)) == space
    Simulation(_maxwellian_run(space, 28))
