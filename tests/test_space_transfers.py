"""A space step keeps the host out: counted on a backend that tells host from device.

:class:`granframe.testing.transfers.CountingBackend` runs the step with NumPy but counts every
copy that a GPU backend would make between host and device (CuPy's rules). A step of a
space run with diffuse walls on both sides, WENO5, a heat bath and penalised collisions
(the BGK rate and Maxwellian of every cell) makes at most 2 device->host copies (the
record of the step: fields, totals and wall totals in one vector), and no copy from the
host of a constant array (the upwind speeds, the wall Maxwellians, the moment basis)."""

import collections

import numpy
import pytest

from granframe.run.description import RunDescription
from granframe.run.problems import make_problem
from granframe.testing.transfers import CountingBackend, DeviceArray
from test_space_backends import TOML as SPACE_TOML

TOML = SPACE_TOML.replace('right = "specular"', 'right = {name = "diffuse", temperature = 0.9}')

STEPS = 3


def counting_problem(description):
    """The description's problem built on a :class:`CountingBackend`, and that backend."""
    backend = CountingBackend()
    original = RunDescription.build

    def build(self, field, **extra):
        return backend if field == "backend" else original(self, field, **extra)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(RunDescription, "build", build)
        return make_problem(description), backend


@pytest.fixture(scope="module")
def counted():
    """A problem on the counting backend after one warm-up step, and the crossings of
    STEPS steps, each a step and its record."""
    description = RunDescription.from_toml(TOML)
    problem, backend = counting_problem(description)
    state = problem.state(problem.f0)
    state = problem.step(0.0, state, description.time_step)      # caches fill here
    problem.record(state)
    backend.reset()
    records = []
    for k in range(1, STEPS + 1):
        state = problem.step(k * description.time_step, state, description.time_step)
        records.append(problem.record(state))
    return problem, state, backend, records


def test_a_space_step_makes_at_most_two_device_to_host_copies(counted):
    _, _, backend, _ = counted
    counts = backend.counts()
    assert counts["to_host"] <= STEPS, collections.Counter(backend.log)     # measured: 1


def test_a_space_step_copies_no_constant_array_from_the_host(counted):
    _, _, backend, _ = counted
    uploads = collections.Counter(entry for entry in backend.log if entry[0] == "to_device")
    assert not uploads, uploads


def test_the_state_stays_on_the_device_and_the_record_is_on_the_host(counted):
    problem, state, _, records = counted
    assert isinstance(state, DeviceArray)
    record = records[-1]
    for name in problem.record_names:
        assert not isinstance(record[name], DeviceArray), name
    assert numpy.isfinite(record["density"]).all() and record["wall_mass"].shape == (2,)


def test_the_counting_backend_counts_what_cupy_would_copy():
    backend = CountingBackend()
    xp = backend.xp
    a = xp.ones(4)
    assert backend.counts() == {"to_host": 0, "to_device": 0}
    float(a.sum())
    bool(a[0] > 0)
    backend.to_numpy(a)
    assert backend.counts()["to_host"] == 3
    a + numpy.arange(4.0)                          # a host operand: CuPy would need a copy
    xp.asarray(numpy.zeros(3))
    assert backend.counts()["to_device"] == 2


HIERARCHY = ('conservative = true\n' + TOML).replace(
    'right = {name = "diffuse", temperature = 0.9}',
    'right = {name = "diffuse", temperature = 0.9}\n[space.hierarchy]\n'
    'realizability = [0.002, 0.01]\ndistance = [0.05, 0.1]\nfree_paths = 0.0')


def _warmed(toml):
    """(problem, backend, state, dt) on the counting backend after two steps and their
    records (the caches fill, the levels spread)."""
    description = RunDescription.from_toml(toml)
    problem, backend = counting_problem(description)
    state = problem.state(problem.f0)
    dt = description.time_step
    for k in range(2):
        state = problem.step(k * dt, state, dt)
        problem.record(state)
    return problem, backend, state, dt


def _counted_steps(toml):
    """(counts of STEPS steps after two, the number of levels in use in each step)."""
    problem, backend, state, dt = _warmed(toml)
    backend.reset()
    used = []
    for k in range(2, 2 + STEPS):
        state = problem.step(k * dt, state, dt)
        problem.record(state)
        if problem.hierarchy is not None:
            used.append(len(numpy.unique(problem.hierarchy.owned_levels)))
    return backend.counts(), used, problem


def test_a_hybrid_step_adds_the_copies_of_the_indicators_and_the_level_indices():
    """With a hierarchy (every level in use; the heat bath makes the fluid levels integrate
    the temperature law by substeps), against the same run without one (both with the
    conservative correction): per step at most one more device->host copy (the indicators
    of the cells) and one host->device copy of the cell indices per level in use."""
    baseline, _, _ = _counted_steps(HIERARCHY.split("[space.hierarchy]")[0])
    counts, used, _ = _counted_steps(HIERARCHY)
    assert max(used) >= 2, used
    assert counts["to_host"] <= baseline["to_host"] + STEPS, counts
    assert counts["to_device"] <= baseline["to_device"] + sum(used), counts


@pytest.mark.parametrize("heat_bath", [0.0, 0.05])
def test_a_hybrid_step_brings_one_vector_to_the_host_and_copies_nothing_from_it(heat_bath):
    """Step by step with a hierarchy (several levels in use, the euler level among them):
    one copy, the record's, which also carries the hierarchy's vector (the indicators of
    every cell and the levels chosen for the next step); under a heat bath the euler level
    takes the substeps of its heated temperature law from the fields that record brought
    to the host, not from the device. No copy from the host (the cells of each level are
    slices of a sort of the levels on the device). At 2df7252: a second device->host copy
    per step (the indicators), a third under a heat bath (the substeps), and one
    host->device copy of the cell indices per level in use in every step."""
    toml = HIERARCHY.replace("heat_bath = 0.05", f"heat_bath = {heat_bath}")
    assert f"heat_bath = {heat_bath}" in toml
    problem, backend, state, dt = _warmed(toml)
    used, euler = set(), 0
    for k in range(2, 2 + STEPS):
        before = len(backend.log)
        state = problem.step(k * dt, state, dt)
        problem.record(state)
        levels = problem.hierarchy.owned_levels
        used.add(len(numpy.unique(levels)))
        euler += int((levels == 0).any())
        counts = backend.counts(since=before)
        assert counts == {"to_host": 1, "to_device": 0}, (k, backend.log[before:])
    assert max(used) >= 2 and euler == STEPS, (used, euler)


def test_a_step_on_a_rectangle_makes_one_device_to_host_copy_and_no_upload():
    """A rectangle with walls on its four sides (a diffuse lid, specular sides), MUSCL:
    after a warm-up step, three steps with their records bring one vector each to the host
    and copy no constant array from it; the state stays on the device."""
    import tomllib

    data = tomllib.loads(TOML)
    data["space"] = {"cells": [6, 5], "reconstruction": "muscl", "left": "specular",
                     "right": {"name": "diffuse", "temperature": 0.9},
                     "bottom": "specular", "top": {"name": "diffuse", "velocity": 0.2}}
    data.pop("initial", None)
    data["initial"] = {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.1,
                       "mode": [1, 1]}
    description = RunDescription.from_dict(data)
    problem, backend = counting_problem(description)
    state = problem.state(problem.f0)
    state = problem.step(0.0, state, description.time_step)
    problem.record(state)
    backend.reset()
    for k in range(1, STEPS + 1):
        state = problem.step(k * description.time_step, state, description.time_step)
        record = problem.record(state)
    assert isinstance(state, DeviceArray)
    assert record["wall_mass"].shape == (4,) and record["density"].shape == (6, 5)
    assert backend.counts()["to_host"] <= STEPS, collections.Counter(backend.log)  # measured: 3
    uploads = collections.Counter(entry for entry in backend.log if entry[0] == "to_device")
    assert not uploads, uploads


def test_a_hybrid_step_on_a_rectangle_brings_one_vector_to_the_host():
    """The hierarchy on a rectangle (four quadrants, walls on the four sides, a heat bath):
    step by step one device->host copy, the record's, carrying the indicators of every
    cell and the levels chosen ahead, and no copy from the host; the indicators with both
    gradient components, the spread over the square and the cells of each level stay on
    the device."""
    import tomllib

    data = tomllib.loads(HIERARCHY)
    hierarchy = dict(data["space"]["hierarchy"], buffer=0)      # no reach: levels mixed
    data["space"] = {"cells": [6, 5], "reconstruction": "muscl", "left": "specular",
                     "right": {"name": "diffuse", "temperature": 0.9}, "bottom": "specular",
                     "top": {"name": "diffuse", "velocity": 0.2}, "hierarchy": hierarchy}
    data["initial"] = {"name": "quadrants",
                       "upper_right": {"density": 1.0, "temperature": 1.0},
                       "upper_left": {"density": 0.5, "velocity": [0.3, 0.0],
                                      "temperature": 0.8},
                       "lower_left": {"density": 1.0, "velocity": [0.3, 0.3],
                                      "temperature": 1.0},
                       "lower_right": {"density": 0.5, "velocity": [0.0, 0.3],
                                       "temperature": 0.8}}
    problem, backend = counting_problem(RunDescription.from_dict(data))
    dt = data["time_step"]
    state = problem.state(problem.f0)
    for k in range(2):
        state = problem.step(k * dt, state, dt)
        problem.record(state)
    used = set()
    for k in range(2, 2 + STEPS):
        before = len(backend.log)
        state = problem.step(k * dt, state, dt)
        problem.record(state)
        used.add(len(numpy.unique(problem.hierarchy.owned_levels)))
        assert backend.counts(since=before) == {"to_host": 1, "to_device": 0}, \
            (k, backend.log[before:])
    assert problem.hierarchy.levels.shape == (30,) and max(used) >= 2, used
