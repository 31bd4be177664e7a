"""The hierarchy of collision models on a rectangle (docs/space.md, "Two dimensions"):

- a cell lifts the cells of the square of its reach about it, on both axes, across the ends
  of a periodic axis (against a direct count over all pairs of cells);
- kappa takes the whole velocity gradient and the whole temperature gradient: its exact
  value for linear fields;
- data along x alone are the interval's hybrid run in every row (the same levels, f to
  round-off), and the levels are stored on (x, y);
- an interrupted hybrid run on a rectangle resumes bitwise, and its figures map the levels.
"""

import numpy
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation, StorageObserver
from granframe.run.storage import RunStore
from granframe.space.hierarchy import realizability, spread_levels
from granframe.tools.plotting import figures


def _covered(level, reach, periodic):
    """The spread levels by a count over every pair of cells (i, j): i takes j's level when
    |i_a - j_a| <= max(reach_j, 0) on every axis, the distance across a periodic axis's
    ends the shorter way round."""
    out = level.copy()
    for i in numpy.ndindex(*level.shape):
        for j in numpy.ndindex(*level.shape):
            r = max(int(reach[j]), 0)
            near = True
            for a, (cells, wraps) in enumerate(zip(level.shape, periodic)):
                distance = abs(i[a] - j[a])
                near &= (min(distance, cells - distance) if wraps else distance) <= r
            if near:
                out[i] = max(out[i], level[j])
    return out


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_a_cell_lifts_the_square_of_its_reach_on_both_axes(data):
    shape = tuple(data.draw(st.lists(st.integers(1, 6), min_size=1, max_size=2)))
    periodic = tuple(data.draw(st.lists(st.booleans(), min_size=len(shape),
                                        max_size=len(shape))))
    size = int(numpy.prod(shape))
    level = numpy.array(data.draw(st.lists(st.sampled_from([0, 0, 0, 1, 2]), min_size=size,
                                           max_size=size))).reshape(shape)
    reach = numpy.array(data.draw(st.lists(st.integers(-1, 8), min_size=size,
                                           max_size=size))).reshape(shape)
    numpy.testing.assert_array_equal(spread_levels(level, reach, periodic, 2),
                                     _covered(level, reach, periodic))


@pytest.mark.parametrize("d", [2, 3])
def test_kappa_of_linear_fields_is_the_navier_stokes_stress_and_heat_flux(d):
    """u = G x (G any 2 x 2 gradient in the plane, u_3 = 0), T = T_0 + b . x between walls
    (the one-sided differences are exact for linear fields): kappa = max(|S|_F, (d+2)/2
    |b| / sqrt T) mu / p, S = G + G^T - (2/d) tr G the rate of strain (d x d, zero
    outside the plane), in every cell."""
    rng = numpy.random.default_rng(5)
    gradient, b = rng.normal(0, 0.4, (2, 2)), rng.normal(0, 0.3, 2)
    x, y = numpy.meshgrid(0.1 * (numpy.arange(6) + 0.5), 0.2 * (numpy.arange(5) + 0.5),
                          indexing="ij")
    velocity = numpy.zeros((6, 5, d))
    velocity[..., :2] = numpy.stack([x, y], axis=-1) @ gradient     # G[a, j] = d u_j / d x_a
    rho = 1.0 + 0.1 * x
    rate = 2.0 * rho
    strain = numpy.zeros((d, d))
    strain[:2, :2] = gradient + gradient.T
    strain -= (2.0 / d) * numpy.trace(gradient) * numpy.eye(d)
    scale = 0.01 / rate
    stress = scale * numpy.sqrt((strain ** 2).sum())
    wins = []
    for factor in (0.1, 2.0):                # the stress, then the heat flux the larger
        temperature = 1.0 + factor * (b[0] * x + b[1] * y)
        kappa = realizability(rho, velocity, temperature, (0.1, 0.2), (False, False), 0.01,
                              rate, axes=(0, 1))
        heat = scale * 0.5 * (d + 2) * factor * numpy.hypot(*b) / numpy.sqrt(temperature)
        numpy.testing.assert_allclose(kappa, numpy.maximum(stress, heat), rtol=1e-12)
        wins.append((heat > stress).all())
    assert wins == [False, True]


SOD = {"title": "Sod", "grid": {"dimension": 2, "n_modes": 24, "support_radius": 3.5},
       "kernel": "maxwell", "restitution": {"name": "constant", "value": 1.0},
       "initial": {"name": "riemann", "left": {"density": 1.0, "temperature": 1.0},
                   "right": {"density": 0.125, "temperature": 0.8}},
       "operator": {"name": "fast_spectral"}, "integrator": "penalised_ars222",
       "knudsen": 1e-3, "conservative": True, "time_step": 0.004, "final_time": 0.06,
       "output": {"snapshot_interval": 0.02}, "backend": {"name": "numpy", "threads": 1}}
WALLS = {"left": "specular", "right": "specular", "hierarchy": {}}


def _description(space, **changes):
    return RunDescription.from_dict({**SOD, "space": {**WALLS, **space}, **changes})


def test_data_along_x_with_a_hierarchy_are_the_interval_hybrid_run_in_every_row():
    """Sod's tube at eps = 1e-3 along x, periodic across y, under the default hierarchy:
    every row has the interval's levels at every step (all three in use) and its f to
    round-off; the levels are stored on (x, y)."""
    line = Simulation(_description({"cells": 24})).run(None, progress=False).dataset
    box = Simulation(_description({"cells": [24, 5], "length": [1.0, 0.5]})).run(
        None, progress=False).dataset
    assert box.level.dims == ("step_time", "x", "y")
    assert numpy.unique(line.level.values[1:]).tolist() == [0, 1, 2]
    for j in range(5):
        numpy.testing.assert_array_equal(box.level.values[:, :, j], line.level.values)
        numpy.testing.assert_array_equal(box.reach.values[:, :, j], line.reach.values)
        numpy.testing.assert_allclose(box.f.values[:, :, j], line.f.values, rtol=0,
                                      atol=1e-13 * line.f.values.max())


def test_an_interrupted_hybrid_run_on_a_rectangle_resumes_bitwise(tmp_path, monkeypatch):
    """Sod's tube on a rectangle under the default hierarchy, Ctrl-C after the second commit,
    then resume: f, the levels and the indicators are the uninterrupted run's bitwise."""
    d = _description({"cells": [24, 5], "length": [1.0, 0.5]})
    Simulation(d).run(tmp_path / "reference.zarr", progress=False)
    reference = granframe.open_run(tmp_path / "reference.zarr")
    commit, commits = StorageObserver.at_output, []

    def stop_after_two(self, state, final):
        commit(self, state, final)
        commits.append(state.step)
        if len(commits) == 2:
            raise KeyboardInterrupt

    path = tmp_path / "stopped.zarr"
    monkeypatch.setattr(StorageObserver, "at_output", stop_after_two)
    with pytest.raises(KeyboardInterrupt):
        Simulation(d).run(path, progress=False)
    monkeypatch.setattr(StorageObserver, "at_output", commit)
    Simulation(d).run(path, resume=True, progress=False)
    resumed = granframe.open_run(path)
    assert RunStore.open(path).progress["resumes"] == [commits[-1]]
    assert len(numpy.unique(reference.level.values[commits[-1]:])) >= 2
    for name in ("f", "density", "level", "realizability", "distance", "reach"):
        numpy.testing.assert_array_equal(resumed[name].values, reference[name].values,
                                         err_msg=name)
    # the figure of each snapshot maps the levels on (x, y) beside the fields
    drawn = figures(resumed)
    assert sorted(drawn) == [f"plane_{k}" for k in range(4)] + ["totals"]
    titles = [ax.get_title() for ax in drawn["plane_2"].axes]
    assert any(t.startswith("collision model of each cell at t = 0.04") for t in titles)
