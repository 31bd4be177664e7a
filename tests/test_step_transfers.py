"""A step with the conservative correction keeps the host out, with every integrator kind.

:class:`granframe.testing.transfers.CountingBackend` counts every copy a GPU backend would
make between host and device. The conservative correction (its moments, Maxwellian
weights, Gram systems and their solution, the energy dissipation D(f)) and the energy
factor E^gamma of the operators run on the backend: a space step with the correction and
a heat bath, penalised ARS(2,2,2) or RK4, with a kernel with or without E^gamma, makes one
device->host copy (the step's record) and no host->device copy. Before, the correction
made 4 device->host and 3 host->device copies per call: 9 per step with ARS(2,2,2), 17
with RK4."""

import numpy
import pytest

import granframe as gf
from granframe.abc import deferred_checks
from granframe.equations.conservative import ConservativeCorrection
from granframe.run.description import RunDescription
from granframe.testing.transfers import CountingBackend, DeviceArray
from test_space_transfers import TOML, counting_problem

STEPS = 3

#: (integrator, time step, Knudsen number): RK4 is explicit in Q/eps, so it takes eps = 1
#: and a step within its limit
SCHEMES = [("penalised_ars222", 0.004, 0.1), ("rk4", 0.0005, 1.0)]

ENERGY_KERNEL = '[kernel]\nname = "vhs"\nexponent = 1.0\nenergy_exponent = 0.5\n'


def _description(integrator, time_step, knudsen, kernel=None):
    toml = ("conservative = true\n" + TOML).replace(
        'integrator = "penalised_ars222"', f'integrator = "{integrator}"').replace(
        "time_step = 0.004", f"time_step = {time_step}").replace(
        "knudsen = 0.1", f"knudsen = {knudsen}")
    if kernel is not None:
        toml = toml.replace('[kernel]\nname = "hard_spheres"\n', kernel)
    return RunDescription.from_toml(toml)


def _counts(description):
    """The crossings of STEPS steps and their records, after one warm-up step."""
    problem, backend = counting_problem(description)
    dt = description.time_step
    state = problem.step(0.0, problem.state(problem.f0), dt)        # caches fill here
    problem.record(state)
    backend.reset()
    for k in range(1, STEPS + 1):
        state = problem.step(k * dt, state, dt)
        record = problem.record(state)
    assert numpy.isfinite(record["temperature"]).all()
    return backend.counts()


@pytest.mark.parametrize("kernel", [None, ENERGY_KERNEL], ids=["hard_spheres", "vhs_E^gamma"])
@pytest.mark.parametrize("integrator, time_step, knudsen", SCHEMES, ids=[s[0] for s in SCHEMES])
def test_a_corrected_step_makes_one_copy_to_the_host_and_none_from_it(integrator, time_step,
                                                                      knudsen, kernel):
    counts = _counts(_description(integrator, time_step, knudsen, kernel))
    assert counts == {"to_host": STEPS, "to_device": 0}, counts


def test_the_correction_on_a_counting_backend_equals_numpy_and_copies_nothing():
    """One call on a stack of distributions with one blown-up member (negative mass,
    positive energy: its weight is |f|): the same Q^c as on NumPy, to round-off, and no
    crossing where the operand checks are deferred (outside a run's step, the checks that
    f is finite and E > 0 copy one sum each to the host)."""
    grid = gf.VelocityGrid(2, 16, 3.0)
    v1, v2 = grid.mesh()
    f = numpy.stack([numpy.exp(-((v1 - 0.3) ** 2 + v2 ** 2) / 1.2),
                     (1.0 + 0.2 * v1) * numpy.exp(-(v1 ** 2 + v2 ** 2) / 0.8),
                     0.2 * numpy.exp(-(v1 ** 2 + v2 ** 2) / 2.0)
                     - numpy.exp(-(v1 ** 2 + v2 ** 2) / 0.5)])
    results = []
    kernel = gf.collision_kernel("vhs", exponent=1.0, energy_exponent=0.5)
    law = gf.restitution_law("constant", value=0.7)
    for backend in (gf.array_backend("numpy"), CountingBackend()):
        operator = gf.collision_operator("fast_spectral", grid, kernel, law, backend=backend)
        corrected = ConservativeCorrection(operator)
        if isinstance(backend, CountingBackend):
            device = backend.asarray(f)
            corrected(device)                                   # warm-up: plans, tables
            backend.reset()
            with deferred_checks():              # as in a run's step
                q = corrected(device)
            assert isinstance(q, DeviceArray)
            assert backend.counts() == {"to_host": 0, "to_device": 0}, backend.log
            q = backend.to_numpy(q)
        else:
            q = corrected(f)
        results.append(q)
    assert numpy.max(numpy.abs(results[0] - results[1])) <= 1e-13 * numpy.max(numpy.abs(results[0]))
