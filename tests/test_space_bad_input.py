"""Bad input to space runs: every invalid ``space`` parameter, wall and space initial
condition is refused with a ValueError/TypeError naming the parameter, the value and what
is allowed, before anything is written -- never a traceback of an internal error, a hang
or a NaN. The grid of these runs is 2D N = 16, S = 3.2: L = 7.0627, h = 0.88284."""

import copy
import math
import os
import re
import subprocess
import sys
import types

import numpy
import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import granframe as gf
from granframe.model.initial import check_fits
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space.boundaries import Diffuse
from granframe.space.initial import RiemannProblem, SinusoidalMode, SpaceFunction
from granframe.space.transport import upwind_speeds
from conftest import mutated
from granframe.tools.cli import main
from test_validation_fuzz import values

GRID = gf.VelocityGrid(2, 16, 3.2)
#: the Sod tube between a specular and a diffuse wall, 40 cells, dt below the CFL limit
BASE = {
    "final_time": 0.006, "time_step": 0.003,
    "grid": {"dimension": 2, "n_modes": 16, "support_radius": 3.2},
    "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
    "initial": {"name": "riemann", "left": {"density": 1.0, "temperature": 1.0},
                "right": {"density": 0.125, "temperature": 0.8}},
    "operator": {"name": "fast_spectral", "radial_points": 8,
                 "sphere": {"name": "circle_trapezoid", "n_points": 8}},
    "backend": {"name": "numpy", "threads": 1},
    "space": {"cells": 40, "left": "specular",
              "right": {"name": "diffuse", "temperature": 1.2, "accommodation": 1.0}},
}


def table(*changes, base=BASE):
    """The base description with dotted keys set (None: removed)."""
    return mutated(copy.deepcopy(base), changes)


def refused(tmp_path, changes, match, error=(ValueError, TypeError)):
    """The run of the changed description is refused with ``match`` and writes no store."""
    out = tmp_path / "run.zarr"
    with pytest.raises(error, match=match) as info:
        Simulation(RunDescription.from_dict(table(*changes))).run(out, progress=False)
    assert not out.exists()
    assert "Traceback" not in str(info.value) and "\n" not in str(info.value)
    return str(info.value)


def accepted(changes):
    """The simulation of the changed description (built: everything checked)."""
    return Simulation(RunDescription.from_dict(table(*changes)))


def re_repr(value) -> str:
    """``repr(value)`` as a regular expression that matches it literally."""
    return re.escape(repr(value))


# -- the space section --------------------------------------------------------------------
@pytest.mark.parametrize("name,ghost", [("upwind", 1), ("muscl", 2), ("weno5", 3)])
def test_cells_below_the_stencil_are_refused(tmp_path, name, ghost):
    stencil = 2 * ghost + 1
    refused(tmp_path, [("space.reconstruction", name), ("space.cells", stencil - 1)],
            rf"^RunDescription: parameter 'space.cells' = {stencil - 1} is invalid; must be >= "
            rf"{stencil}, the stencil of the reconstruction '{name}' \(2 x {ghost} ghost")
    simulation = accepted([("space.reconstruction", name), ("space.cells", stencil)])
    assert simulation.f0.shape == (stencil, 16, 16)


@pytest.mark.parametrize("value,error,allowed", [
    (0, ValueError, "must be an integer >= 1"), (-3, ValueError, "must be an integer >= 1"),
    (10 ** 9 + 1, ValueError, "must be an integer >= 1 and <= 1000000000"),
    (10 ** 400, ValueError, "must be an integer >= 1 and <= 1000000000"),
    (40.0, TypeError, "must be an integer >= 1"), (True, TypeError, "must be an integer"),
    ("40", TypeError, "must be an integer"), ([40], TypeError, "must be an integer")])
def test_cells_that_are_not_a_positive_integer_are_refused(tmp_path, value, error, allowed):
    refused(tmp_path, [("space.cells", value)],
            rf"^Space: parameter 'cells' = {re_repr(value)[:60]}.* is invalid; {allowed}", error)


@pytest.mark.parametrize("value,allowed", [
    (0.0, r"must lie in \[1e-50, 1e\+50\]"), (-1.0, r"must lie in \[1e-50, 1e\+50\]"),
    (1e60, r"must lie in \[1e-50, 1e\+50\]"), (math.inf, "must be finite"),
    (math.nan, "must be finite"), (10 ** 400, "must be finite"),
    (True, "must be a real number"), ("1", "must be a real number")])
def test_length_that_is_not_positive_and_finite_is_refused(tmp_path, value, allowed):
    refused(tmp_path, [("space.length", value)],
            rf"^Space: parameter 'length' = {re_repr(value)[:60]}.* is invalid; {allowed}")


@pytest.mark.parametrize("value", [7, 0, 41, -8, 4.0, True, "x"])
def test_block_cells_that_do_not_divide_cells_are_refused(tmp_path, value):
    refused(tmp_path, [("space.block_cells", value)],
            rf"^Space: parameter 'block_cells' = {re_repr(value)} is invalid; must be a divisor "
            r"of cells = 40 \(or None\)")


def test_block_cells_below_the_ghost_width_are_refused(tmp_path):
    refused(tmp_path, [("space.block_cells", 2), ("space.reconstruction", "weno5")],
            r"^RunDescription: parameter 'space.block_cells' = 2 is invalid; must be >= 3, the "
            r"ghost width of the reconstruction 'weno5'")
    assert accepted([("space.block_cells", 2)]).domain.blocks == 20      # muscl: ghost 2


def test_an_unknown_space_key_and_a_missing_cells_are_refused(tmp_path):
    refused(tmp_path, [("space.cell", 40)], r"parameter 'cell' = 40 is invalid; is not a "
                                            r"parameter of Space; known: block_cells, bottom, cells")
    refused(tmp_path, [("space", {"left": "specular"})], r"'cells'")
    refused(tmp_path, [("space", 40)], r"parameter 'space' = 40 is invalid; must be a Space "
                                       r"table", TypeError)


# -- boundaries -------------------------------------------------------------------------
def test_a_boundary_that_does_not_exist_is_refused(tmp_path):
    refused(tmp_path, [("space.left", "mirror")], r"boundaries: name 'mirror' is not "
                                                  r"registered; known: diffuse, periodic, reservoir, specular, vibrating")
    refused(tmp_path, [("space.reconstruction", "weno3")],
            r"reconstructions: name 'weno3' is not registered; known: muscl, upwind, weno5")


@pytest.mark.parametrize("side,other", [("left", "right"), ("right", "left")])
def test_a_periodic_end_with_a_wall_at_the_other_is_refused(tmp_path, side, other):
    walls = {"left": "specular", "right": "diffuse"}
    refused(tmp_path, [(f"space.{side}", "periodic")],
            rf"^RunDescription: parameter 'space.{other}' = '{walls[other]}' is invalid; must "
            r"be periodic too: an interval is periodic at both ends or at neither")


@pytest.mark.parametrize("value,allowed", [
    (0.0, r"must lie in \(0, inf\]"), (-1.0, r"must lie in \(0, inf\]"),
    (math.nan, "must be finite"), (math.inf, "must be finite"),
    ("1", "must be a real number"), (True, "must be a real number")])
def test_a_wall_temperature_that_is_not_positive_is_refused(tmp_path, value, allowed):
    refused(tmp_path, [("space.right.temperature", value)],
            rf"^Diffuse: parameter 'temperature' = {re_repr(value)} is invalid; {allowed}")


def test_a_wall_maxwellian_wider_than_the_box_is_refused(tmp_path):
    """Fits: exp(-L^2 / (2 T_w)) <= 1e-8, T_w <= L^2 / (2 ln 1e8) = 1.3543."""
    limit = GRID.half_width ** 2 / (2 * math.log(1e8))
    message = refused(tmp_path, [("space.right.temperature", 1.4)],
                      r"^Diffuse: parameter 'temperature' = 1.4 is invalid; with wall velocity "
                      r"\[0.0\] gives a wall Maxwellian that does not fit the velocity box "
                      r"\[-7.06274, 7.06274\]\^2 .* lower it below 1.354")
    assert f"{limit:.4g}" == "1.354" and "support_radius" in message
    accepted([("space.right.temperature", 1.35)])
    refused(tmp_path, [("space.right.velocity", 1.0)], r"'temperature' = 1.2 is invalid; with "
                                                       r"wall velocity \[1.0\]")
    refused(tmp_path, [("space.right.velocity", -8.0)],
            r"^Diffuse: parameter 'velocity' = \[-8.0\] is invalid; must lie inside the velocity "
            r"box: \|u_w\| < L = 7.06274")


def test_a_wall_maxwellian_narrower_than_the_nodes_is_refused(tmp_path):
    """Resolved: sqrt(T_w) >= h / 2, T_w >= h^2 / 4 = 0.19485; a colder wall made NaN
    (0/0 in its emission) at T_w = 1e-300, and a wrong wall flux at 1e-3."""
    assert f"{GRID.spacing ** 2 / 4:.4g}" == "0.1949"
    for cold in (1e-300, 1e-3, 0.19):
        refused(tmp_path, [("space.right.temperature", cold)],
                rf"^Diffuse: parameter 'temperature' = {cold!r} is invalid; must be >= h\^2 / 4 "
                r"= 0.1949 \(a thermal speed sqrt\(T_w\) of at least half the node spacing "
                r"h = 0.8828\)")
    accepted([("space.right.temperature", 0.195)])
    # the error of the half-range flux at the limit, which the message states
    flux = sum(k * math.exp(-2.0 * k * k) for k in range(1, 10)) / 0.25
    assert 0.455 < 1.0 - flux < 0.46


@pytest.mark.parametrize("value", [1.5, -0.1, math.nan, True])
def test_accommodation_outside_0_1_is_refused(tmp_path, value):
    refused(tmp_path, [("space.right.accommodation", value)],
            rf"^Diffuse: parameter 'accommodation' = {re_repr(value)} is invalid; must .*\[0, 1\]")


@pytest.mark.parametrize("dimension,velocity,allowed", [
    (2, [0.1, 0.2], r"must have at most 1 tangential component\(s\) \(v2\) on a 2D"),
    (3, [0.1, 0.2, 0.3], r"must be the finite tangential wall velocity: a number \(along v2\) or "
                         r"a list of 1 \(2D\) or 2 \(3D\) numbers"),
    (2, [], "must be the finite tangential wall velocity"),
    (2, [0.1, math.nan], "must be the finite tangential wall velocity"),
    (2, "fast", "must be the finite tangential wall velocity")])
def test_a_wall_velocity_with_too_many_components_is_refused(dimension, velocity, allowed):
    grid = gf.VelocityGrid(dimension, 16, 3.2)
    with pytest.raises(ValueError, match=r"^Diffuse: parameter 'velocity' = .* is invalid; "
                                         + allowed):
        Diffuse(temperature=1.0, velocity=velocity).check(grid)
    Diffuse(temperature=1.0, velocity=[0.1, 0.2][:dimension - 1]).check(grid)


def test_unknown_boundary_parameters_are_refused(tmp_path):
    refused(tmp_path, [("space.right.wall_temperature", 1.0)],
            r"boundaries 'diffuse': unknown parameter 'wall_temperature'; did you mean "
            r"'temperature'\? Accepted parameters: temperature, velocity, accommodation", TypeError)
    refused(tmp_path, [("space.left", {"name": "specular", "temperature": 1.0})],
            r"boundaries 'specular': unknown parameter 'temperature'; accepted parameters: none",
            TypeError)
    refused(tmp_path, [("space.reconstruction", {"name": "muscl", "limiter": "superbee"})],
            r"MUSCL: parameter 'limiter' = 'superbee' is invalid; must be one of")


# -- time stepping and the equation ---------------------------------------------------------
@pytest.mark.parametrize("name,cfl", [("upwind", 1.0), ("muscl", 0.5), ("weno5", 0.5)])
def test_a_time_step_above_the_cfl_limit_is_refused_with_the_limit(tmp_path, name, cfl):
    """dt <= 2 cfl dx / (L - h), dx = 1/40, L - h = 6.1799."""
    reconstruction = gf.default_registries().create("reconstructions", name)
    assert reconstruction.cfl == cfl
    limit = 2 * cfl * (1 / 40) / (GRID.half_width - GRID.spacing)
    message = refused(tmp_path, [("space.reconstruction", name), ("time_step", 0.0125),
                                 ("final_time", 0.0125)],
                      rf"^RunDescription: parameter 'time_step' = 0.0125 is invalid; must be <= "
                      rf"{limit:.6g}, the transport's CFL limit")
    assert "max|v_1| = L - h = 6.1799" in message and "dx = 0.025" in message
    accepted([("space.reconstruction", name), ("time_step", limit), ("final_time", 2 * limit)])


def test_an_adaptive_integrator_is_refused(tmp_path):
    refused(tmp_path, [("integrator", "dopri54"), ("tolerance", 1e-6)],
            r"^RunDescription: parameter 'integrator' = 'dopri54' is invalid; must be a "
            r"fixed-step integrator in a space run")


def test_rescaled_with_a_diffuse_wall_is_refused(tmp_path):
    refused(tmp_path, [("rescaled", True), ("restitution.value", 0.5)],
            r"^RunDescription: parameter 'space.right' = 'diffuse' is invalid; must be a "
            r"boundary that commutes with the scaling of the velocities \(periodic, specular\)")


def test_a_heat_bath_without_collisions_is_refused(tmp_path):
    refused(tmp_path, [("heat_bath", 0.1), ("space.collisions", False)],
            r"^RunDescription: parameter 'heat_bath' = 0.1 is invalid; must be 0 in a "
            r"collisionless run")
    refused(tmp_path, [("space.collisions", 0)],
            r"^Space: parameter 'collisions' = 0 is invalid; must be True or False", TypeError)


# -- initial data -------------------------------------------------------------------------
def _function(name, body):
    """A module-level function ``sbi_functions:<name>`` (space_function takes references)."""
    module = sys.modules.setdefault("sbi_functions", types.ModuleType("sbi_functions"))
    setattr(module, name, body)
    return f"sbi_functions:{name}"


def gaussian(x, v1, v2):
    return numpy.exp(-(v1 ** 2 + v2 ** 2) / 2) / (2 * math.pi) + 0.0 * x


def test_initial_data_negative_in_some_cell_is_refused(tmp_path):
    """f0 < 0 for x > 0.7: the first such cell is 28 (centre 0.7125) of 40."""
    reference = _function("negative", lambda x, v1, v2: gaussian(x, v1, v2) * (1 - 2 * (x > 0.7)))
    refused(tmp_path, [("initial", {"name": "space_function", "function": reference})],
            r"^initial condition SpaceFunction: parameter 'min f0' = -0.159\d* is invalid; must "
            r"be >= 0 \(f0 is a density\) \(in cell 28 of 40, x = 0.7125\)$")
    nan = _function("nan", lambda x, v1, v2: gaussian(x, v1, v2) * numpy.where(x < 0.2, numpy.nan,
                                                                               1.0))
    refused(tmp_path, [("initial", {"name": "space_function", "function": nan})],
            r"parameter 'f0' = 'non-finite values' is invalid; must be finite everywhere on the "
            r"grid \(in cell 0 of 40")


@pytest.mark.parametrize("body,allowed", [
    (lambda x, v1, v2: 1 / 0, r"calling it raised ZeroDivisionError: division by zero"),
    (lambda v1, v2: v1, r"calling it raised TypeError"),
    (lambda x, v1, v2: numpy.ones(3), r"calling it raised ValueError: operands could not be "
                                      r"broadcast"),
    (lambda x, v1, v2: "f", r"calling it raised ValueError: could not convert string"),
    (lambda x, v1, v2: gaussian(x, v1, v2) * numpy.exp(1j * x),
     r"must return real values; it returned complex values with max \|imaginary part\|")])
def test_a_space_function_that_cannot_be_evaluated_is_refused(tmp_path, body, allowed):
    reference = _function("bad", body)
    refused(tmp_path, [("initial", {"name": "space_function", "function": reference})],
            rf"^SpaceFunction: parameter 'function' = 'sbi_functions:bad' is invalid; .*{allowed}")


def test_a_space_function_with_a_round_off_imaginary_part_is_its_real_part():
    reference = _function("nearly_real", lambda x, v1, v2: gaussian(x, v1, v2) * (1 + 1e-15j))
    f, _ = SpaceFunction(reference).sample_cells(GRID, numpy.linspace(0.0, 1.0, 5))
    assert f.dtype == float and numpy.allclose(f, gaussian(0.0, *GRID.mesh()), rtol=1e-14)


def test_a_hot_cell_of_a_riemann_problem_is_refused_by_its_cell(tmp_path):
    """T = 30 right of x = 0.5 does not fit in L = 7.06: cell 20 of 40 (x = 0.5125) is the
    first that holds it."""
    refused(tmp_path, [("initial.right.temperature", 30.0)],
            r"^initial condition RiemannProblem: parameter 'f0 on the faces of the box / max f0' "
            r"= 0.5\d* is invalid; must be <= health.edge_tolerance = 1e-08: .* enlarge the grid's "
            r"support_radius \(or half_width\) \(in cell 20 of 40, x = 0.5125\)$")
    refused(tmp_path, [("initial.left.velocity", 10.0)], r"\(in cell 0 of 40, x = 0.0125\)$")


IN_STATE_RANGE = r"must be a finite number in \[1e-50, 1e\+50\]"


@pytest.mark.parametrize("key,value,allowed", [
    ("left.density", 0.0, IN_STATE_RANGE),
    ("right.density", -0.125, IN_STATE_RANGE),
    ("left.density", math.inf, IN_STATE_RANGE),
    ("left.density", True, IN_STATE_RANGE),
    ("right.temperature", 0.0, IN_STATE_RANGE),
    ("left.pressure", 1.0, r"is not a state variable \(density, velocity, temperature\)"),
    ("left.velocity", [1.0, 2.0, 3.0], "must be u_1 or 2 components on a 2D grid"),
    ("left.velocity", [math.nan], r"must be u_1 \(a finite number\) or the d components"),
    ("right.velocity", 10 ** 400, r"must be u_1 \(a finite number\) or the d components"),
    ("right.temperature", 10 ** 400, IN_STATE_RANGE),
    ("interface", 1.0, r"must lie in \(0, 1\)")])
def test_riemann_states_out_of_range_are_refused(tmp_path, key, value, allowed):
    refused(tmp_path, [(f"initial.{key}", value)],
            rf"^RiemannProblem: parameter '{key}' = .* is invalid; {allowed}")


@pytest.mark.parametrize("changes,name,allowed", [
    ({"amplitude": 1.0}, "amplitude", r"must be in \(-1, 1\) for the density"),
    ({"amplitude": -1.0, "field": "temperature"}, "amplitude",
     r"must be in \(-1, 1\) for the temperature, which must stay positive"),
    ({"amplitude": math.nan}, "amplitude", "must be finite"),
    ({"field": "pressure"}, "field", r"must be one of \['density', 'velocity', 'temperature'\]"),
    ({"field": 1}, "field", r"must be one of"),
    ({"mode": 0}, "mode", "must be an integer >= 1"),
    ({"mode": 1.5}, "mode", "must be an integer >= 1"),
    ({"mode": 21}, "mode", r"must be <= cells / 2 = 20: 40 cells resolve at most 20 periods"),
    ({"mode": 10 ** 30}, "mode", r"must be <= cells / 2 = 20"),
    ({"density": 0.0}, "density", r"must lie in \[1e-50, 1e\+50\]"),
    ({"temperature": 5e-324}, "temperature", r"must lie in \[1e-50, 1e\+50\]"),
    ({"velocity": 1e300}, "velocity", r"must lie in \[-1e\+50, 1e\+50\]"),
    ({"wavelength": 2.0}, "wavelength", "")])
def test_a_sinusoidal_mode_out_of_range_is_refused(tmp_path, changes, name, allowed):
    refused(tmp_path, [("initial", {"name": "sinusoidal_mode", **changes})],
            rf"'{name}'.*{allowed}")


def test_a_sinusoidal_mode_of_half_the_cells_is_accepted():
    simulation = accepted([("initial", {"name": "sinusoidal_mode", "mode": 20,
                                        "amplitude": 0.5})])
    density = simulation.grid.mass(simulation.f0[0]), simulation.grid.mass(simulation.f0[1])
    # the exact cell averages of 1 + sin(40 pi x) / 2 over [0, 1/40] and [1/40, 2/40]
    assert density == pytest.approx((1 + 1 / math.pi, 1 - 1 / math.pi), rel=1e-9)


@pytest.mark.parametrize("key,value", [
    ("initial.left.density", 1e300), ("initial.left.density", 1e-300),
    ("initial.right.temperature", 5e-324), ("initial.right.temperature", 1e308),
    ("initial.left.velocity", 1e300)])
def test_states_beyond_floating_point_range_are_refused_by_name(tmp_path, key, value):
    """Densities and temperatures whose Maxwellian, its square in Q or its kurtosis would
    overflow or vanish in float64 are refused by name with their range."""
    name = key.removeprefix("initial.")
    refused(tmp_path, [(key, value)], rf"^RiemannProblem: parameter '{name}' = "
                                      rf"{re_repr(value)} is invalid; must be .*1e\+50")


@pytest.mark.parametrize("body,match", [
    (lambda x, v1, v2: 1e300 * gaussian(x, v1, v2),
     r"'max \|f0\| in cell 0' = 1.*e\+299 is invalid; must lie in \[1e-100, 1e\+100\]"),
    (lambda x, v1, v2: 1e-300 * gaussian(x, v1, v2),
     r"'max \|f0\| in cell 0' = 1.*e-301 is invalid; must lie in \[1e-100, 1e\+100\]"),
    (lambda x, v1, v2: numpy.exp(-(v1 ** 2 + v2 ** 2) / 1e-6) + 0 * x,
     r"'moments of f0 in cell 0' = .* is invalid; must be finite and > 0 .* too narrow for "
     r"the grid spacing h = 0.8828")])
def test_space_functions_beyond_floating_point_range_are_refused(tmp_path, body, match):
    """Huge, tiny or too narrow data from a space_function: refused naming the cell, not an
    overflow or a division by zero in the moments of f0."""
    reference = _function("extreme", body)
    refused(tmp_path, [("initial", {"name": "space_function", "function": reference})],
            rf"^initial condition SpaceFunction: parameter {match}")


def test_the_memory_of_all_cells_is_within_the_budget(tmp_path, monkeypatch):
    """A collisionless run too: 400 cells of 16^2 nodes are 800 KiB an f, over 1 MiB."""
    monkeypatch.setenv("GRANFRAME_MEMORY_BUDGET", str(2 ** 20))
    refused(tmp_path, [("space.cells", 400), ("time_step", 3e-4), ("final_time", 6e-4),
                       ("space.collisions", False)],
            r"^Simulation: parameter 'space.cells' = 400 is invalid; .* needs about [0-9.]+ GiB "
            r".* set GRANFRAME_MEMORY_BUDGET")


def test_the_memory_of_the_operator_on_every_cell_is_in_the_one_budget(tmp_path, monkeypatch):
    """direct_spectral gathers 16 bytes per pair of modes for each cell of a call (2D N = 16:
    15^4 pairs); 30 000 cells passed the check with the operator's estimate of one cell and
    failed in the first step. Now the run's copies and the operator's per-cell arrays are
    one estimate, refused before anything is written."""
    from granframe.memory import run_memory

    monkeypatch.delenv("GRANFRAME_MEMORY_BUDGET", raising=False)
    changes = [("operator", {"name": "direct_spectral"}), ("space.cells", 30000),
               ("space.length", 750.0)]
    need = run_memory(RunDescription.from_dict(table(*changes)))
    assert need["operator"] >= 16 * 30000 * 15 ** 4
    assert need["total"] == need["f"] * need["copies"] + need["other"] + need["operator"]
    # a process owning a third of the cells still keeps f0 of them all
    third = run_memory(RunDescription.from_dict(table(*changes)), cells=10000)
    assert third["other"] - need["other"] == 8 * 16 ** 2 * 20000
    refused(tmp_path, changes, r"^Simulation: parameter 'space.cells' = 30000 is invalid; with "
                               r"grid.n_modes = 16 \(d = 2\) needs about 2\d.\d GiB for this run "
                               r"\(operator 2\d.\d GiB \+ \d+ copies of every cell's f")


@pytest.mark.parametrize("command", ["run", "limits", "advise", "bench"])
def test_a_billion_cells_are_refused_by_their_memory_not_hung(tmp_path, capsys, command):
    """1e9 cells without block_cells: the default chunk width looped over every integer up
    to the cell count (minutes), and ``limits`` then sampled f0 in every cell of its
    outline (terabytes). Now the divisors are found in pairs up to sqrt(cells) and every
    command meets the run's memory check first: one line naming space.cells, exit 2."""
    changes = [("space.cells", 10 ** 9), ("time_step", 1e-12), ("final_time", 2e-12)]
    (tmp_path / "x.toml").write_text(tomli_w.dumps(table(*changes)))
    arguments = {"run": ["run", tmp_path / "x.toml", "--out", tmp_path / "out",
                         "--no-progress"],
                 "limits": ["limits", tmp_path / "x.toml"],
                 "advise": ["advise", tmp_path / "x.toml"],
                 "bench": ["bench", "--space", "2:16:1000000000"]}[command]
    assert main([str(a) for a in arguments]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "parameter 'space.cells' = 1000000000 is invalid;" in err
    assert "more than the memory budget" in err
    assert not (tmp_path / "out").exists()


def test_the_divisors_of_the_cells_are_those_of_the_definition():
    from granframe.parallel import cell_divisors

    for cells in list(range(1, 200)) + [2 ** 20, 10 ** 9, 999983]:
        low, high = 3, min(cells, 70)
        assert cell_divisors(cells, low, high) == [b for b in range(low, high + 1)
                                                  if cells % b == 0]
    assert cell_divisors(10 ** 9, 3)[-3:] == [25 * 10 ** 7, 5 * 10 ** 8, 10 ** 9]
    assert cell_divisors(999983, 2) == [999983]                 # a prime


# -- the command line ---------------------------------------------------------------------
@pytest.mark.parametrize("changes,message", [
    ([("space.cells", 4)], "parameter 'space.cells' = 4 is invalid; must be >= 5"),
    ([("space.left", "periodic")], "parameter 'space.right' = 'diffuse' is invalid"),
    ([("space.right.temperature", 0.01)], "parameter 'temperature' = 0.01 is invalid"),
    ([("time_step", 0.006)], "parameter 'time_step' = 0.006 is invalid; must be <= 0.00404537"),
    ([("initial.right.temperature", 30.0)], "(in cell 20 of 40, x = 0.5125)"),
    ([("initial", {"name": "sinusoidal_mode", "mode": 0})], "parameter 'mode' = 0 is invalid")])
def test_the_command_line_refuses_with_one_line(tmp_path, capsys, changes, message):
    (tmp_path / "x.toml").write_text(tomli_w.dumps(table(*changes)))
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "x.toml"), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granframe: error: ") and err.count("\n") == 1, err
    assert message in err and "Traceback" not in err
    assert not out.exists()


# -- fuzz ---------------------------------------------------------------------------------
SPACE_KEYS = {"cells": [3, 5, 7, 8, 40, 0, -1, 10 ** 12], "length": [1.0, 0.5, 1e-300, 1e300],
              "block_cells": [None, 1, 2, 4, 5, 8, 40],
              "reconstruction": ["upwind", "muscl", "weno5", "nope", {"name": "muscl",
                                                                      "limiter": "mc"}],
              "left": ["specular", "periodic", "diffuse", "x"],
              "right": ["specular", "periodic", "diffuse", {"name": "diffuse"}],
              "collisions": [False], "bogus": [1]}
DIFFUSE_KEYS = {"temperature": [1.0, 0.2, 1.35, 2.0, 1e-300], "velocity": [0.0, 0.5, [0.3], 7.5],
                "accommodation": [0.0, 0.5, 1.0], "bogus": [1]}


def _names_a_parameter(message, names):
    return (any(f"'{name}'" in message or f".{name}'" in message or f"'{name}." in message
                for name in names)
            or "name '" in message)


@st.composite
def space_tables(draw):
    """A collisionless space section (and its diffuse right wall) with one to three keys
    replaced, dropped or added, and a time step from the CFL limit's neighbourhood."""
    space = {"cells": 8, "length": 1.0, "left": "specular",
             "right": {"name": "diffuse", "temperature": 1.0}, "collisions": False}
    changed = []
    for key in draw(st.lists(st.sampled_from(list(SPACE_KEYS)), max_size=3, unique=True)):
        space[key] = draw(st.one_of(st.sampled_from(SPACE_KEYS[key]), values, st.none()))
        changed.append(key)
    if isinstance(space.get("right"), dict) and space["right"].get("name") == "diffuse":
        wall = dict(space["right"])
        for key in draw(st.lists(st.sampled_from(list(DIFFUSE_KEYS)), max_size=2, unique=True)):
            wall[key] = draw(st.one_of(st.sampled_from(DIFFUSE_KEYS[key]), values))
            changed.append(key)
        space["right"] = wall
    space = {k: v for k, v in space.items() if v is not None}
    return space, changed, draw(st.sampled_from([1e-3, 0.01, 0.03, 0.1]))


@settings(max_examples=800, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(space_tables())
def test_fuzzed_space_sections_build_or_name_a_parameter(example):
    space, changed, dt = example
    data = table(("space", space), ("time_step", dt), ("final_time", dt))
    try:
        simulation = Simulation(RunDescription.from_dict(data))
    except (ValueError, TypeError) as exc:
        names = [*changed, *SPACE_KEYS, *DIFFUSE_KEYS, "time_step", "space", "f0"]
        assert _names_a_parameter(str(exc), names), str(exc)
        return
    cells = simulation.description.space.cells
    assert simulation.f0.shape == (cells, 16, 16) and numpy.isfinite(simulation.f0).all()
    if not simulation.right.periodic:      # the wall sends back what arrives, finite
        positive, negative = upwind_speeds(GRID)
        incoming = simulation.f0[:1]
        flux = (positive * simulation.right.emit(incoming, GRID, numpy)
                + negative * incoming)
        assert numpy.isfinite(flux).all() and abs(flux.sum()) <= 1e-13 * abs(flux).sum()


STATE = st.fixed_dictionaries({}, optional={
    "density": st.one_of(st.sampled_from([1.0, 0.125, 1e-3]), values),
    "velocity": st.one_of(st.sampled_from([0.0, 0.5, [0.5, 0.0]]), values),
    "temperature": st.one_of(st.sampled_from([1.0, 0.8, 30.0]), values),
    "pressure": values})
FUNCTIONS = [gaussian, lambda x, v1, v2: -gaussian(x, v1, v2), lambda x, v1: x,
             lambda x, v1, v2: gaussian(x, v1, v2) * numpy.sin(2 * math.pi * x),
             lambda x, v1, v2: numpy.full(3, 1.0), lambda x, v1, v2: gaussian(x, v1, v2) / x,
             lambda *a: {}[0], "math:cos", "sbi_functions:missing", "nope:f", "nope"]


@pytest.mark.filterwarnings("ignore::RuntimeWarning")    # exp(-v^2 / (2 T)) of T = 5e-324
@settings(max_examples=1500, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(condition=st.one_of(
    st.tuples(st.just(RiemannProblem), st.fixed_dictionaries(
        {"left": st.one_of(STATE, values), "right": STATE},
        optional={"interface": st.one_of(st.floats(0.0, 1.0), values), "bogus": values})),
    st.tuples(st.just(SinusoidalMode), st.fixed_dictionaries({}, optional={
        key: st.one_of(st.sampled_from(good), values) for key, good in (
            ("density", [1.0]), ("velocity", [0.0, 0.5]), ("temperature", [1.0]),
            ("field", ["density", "velocity", "temperature", "rho"]),
            ("amplitude", [0.1, 0.9, 1.0, -2.0]), ("mode", [1, 2, 4, 5]), ("bogus", [1]))})),
    st.tuples(st.just(SpaceFunction), st.fixed_dictionaries(
        {"function": st.one_of(st.sampled_from(FUNCTIONS), values)}))))
def test_fuzzed_space_initial_conditions_build_or_name_a_parameter(condition):
    """Each builds and gives cell averages on 8 cells (then checked as a run checks them),
    or raises ValueError/TypeError naming one of its parameters (or one of f0's)."""
    cls, kwargs = condition
    names = [*kwargs, "left", "right", "interface", "function", "field", "amplitude", "mode",
             "density", "velocity", "temperature", "f0", "min f0", "max f0",
             "f0 on the faces of the box / max f0", "relative mass error on the grid"]
    try:
        obj = cls(**kwargs)
        f, masses = obj.sample_cells(GRID, numpy.linspace(0.0, 1.0, 9))
        for cell, mass in zip(f, masses if masses is not None else [None] * len(f)):
            check_fits(GRID, cell, type("Cell", (), {"intended_mass": mass})(), 1e-8, 1e-6)
    except (ValueError, TypeError) as exc:
        assert _names_a_parameter(str(exc), names), str(exc)
        return
    assert f.shape == (8, 16, 16) and numpy.isfinite(f).all() and f.min() >= 0.0


def _family(x, v1, v2, *, density=1.0, wave=0.0, periods=1):
    return density * (1 + wave * numpy.sin(2 * math.pi * periods * x)) * gaussian(x, v1, v2)


def test_a_space_function_takes_its_parameters_by_name_from_the_description(tmp_path):
    """One function, two runs: params reach the function as keyword arguments and are kept
    in the stored description."""
    reference = _function("family", _family)
    edges = numpy.linspace(0.0, 1.0, 9)
    plain, _ = SpaceFunction(reference).sample_cells(GRID, edges)
    waved, _ = SpaceFunction(reference, params={"wave": 0.5, "periods": 2}).sample_cells(
        GRID, edges)
    assert numpy.allclose(plain, plain[:1])
    cells = 0.5 * (edges[:-1] + edges[1:])
    mass = GRID.cell_volume * waved.sum(axis=(1, 2))
    # the cell averages of 1 + 0.5 sin(4 pi x) (6-point Gauss: exact for the sine to 1e-9)
    exact = 1 + 0.5 * (numpy.cos(4 * math.pi * edges[:-1]) - numpy.cos(4 * math.pi * edges[1:])) \
        / (4 * math.pi * numpy.diff(edges))
    assert numpy.allclose(mass / mass.mean(), exact, rtol=1e-6), (mass, cells)
    sim = accepted([("initial", {"name": "space_function", "function": reference,
                                 "params": {"wave": 0.2}})])
    assert sim.description.to_dict()["initial"]["params"] == {"wave": 0.2}


@pytest.mark.parametrize("params,match", [
    ({"amplitude": 0.3}, r"parameter 'params.amplitude' = 0.3 is invalid; is not a keyword "
                         r"argument of the function 'sbi_functions:family' \(it takes \['x', "
                         r"'v1', 'v2', 'density', 'wave', 'periods'\]\)"),
    ([0.3], r"parameter 'params' = \[0.3\] is invalid; must be a table of keyword arguments"),
    ({"wave": "big"}, r"parameter 'function' = 'sbi_functions:family' is invalid; .* with "
                      r"params \{'wave': 'big'\}; calling it raised"),
])
def test_space_function_parameters_the_function_does_not_take_are_refused(tmp_path, params,
                                                                          match):
    reference = _function("family", _family)
    refused(tmp_path, [("initial", {"name": "space_function", "function": reference,
                                    "params": params})], match)


def _exits(*_, **__):
    sys.exit(0)


def test_user_code_that_calls_sys_exit_is_refused_naming_it(tmp_path, capsys,
                                                           make_distribution):
    """A space function, a callable initial condition, a kernel's angular part, a module a
    description names and a plugin that call sys.exit: each is that code's failure,
    refused naming it (a space function's sys.exit(0) ended granframe run with status 0,
    nothing printed and no store)."""
    reference = _function("exits", _exits)
    table_exits = table(("initial", {"name": "space_function", "function": reference}))
    (tmp_path / "x.toml").write_text(tomli_w.dumps(table_exits))
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "x.toml"), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granframe: error: SpaceFunction: parameter 'function' = "
                          "'sbi_functions:exits' is invalid;") and err.count("\n") == 1, err
    assert "calling it raised SystemExit (it called sys.exit(0))" in err
    assert not out.exists()
    with pytest.raises(ValueError, match=r"^FromCallable: parameter 'function' = .* calling "
                                         r"it raised SystemExit \(it called sys.exit\(0\)\)"):
        gf.initial_condition("callable", function=_exits).sample(GRID)
    with pytest.raises(TypeError, match=r"parameter 'angular' = .*\(calling it raised "
                                        r"SystemExit \(it called sys.exit\(0\)\)"):
        gf.collision_kernel("vhs", exponent=0.5, angular=_exits)
    (tmp_path / "exits_on_import.py").write_text("import sys\nsys.exit(3)\n")
    sys.path.insert(0, str(tmp_path))
    try:
        with pytest.raises(ValueError, match=r"'exits_on_import:f' is invalid; cannot be "
                                             r"imported: importing 'exits_on_import' raised "
                                             r"SystemExit \(it called sys.exit\(3\)\)"):
            SpaceFunction("exits_on_import:f")
    finally:
        sys.path.remove(str(tmp_path))
    site = make_distribution("granframe-exits", "granframe_exits", "import sys\nsys.exit(0)\n")
    done = subprocess.run([sys.executable, "-m", "granframe.tools.cli", "plugins"],
                          env=dict(os.environ, PYTHONPATH=str(site)), capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert ("cannot load plugin 'granframe_exits'" in done.stderr
            and "SystemExit (it called sys.exit(0))" in done.stderr), done.stderr


def test_a_vibrating_wall_with_an_amplitude_and_a_frequency_is_refused(tmp_path):
    """The vibrating wall is the small-amplitude limit, in which only A omega enters: the
    amplitude and the frequency of an older description are refused by name, with the
    parameters it takes (a period of 6e-12 against dt = 3e-3 ran silently before, its work
    sampled at the stages' phases; the limit has no period to sample)."""
    wall = {"name": "vibrating", "amplitude": 0.5e-12, "frequency": 1e12}
    refused(tmp_path, [("space.left", wall)],
            r"boundaries 'vibrating': unknown parameter 'amplitude'; accepted parameters: "
            r"speed, temperature, reflection")
    accepted([("space.left", {"name": "vibrating", "speed": 0.5})])
