"""Limits of the space-inhomogeneous equation d_t f + v_1 d_x f = Q(f, f)/eps (docs/space.md).

- the Euler limit: the elastic Sod tube at eps = 1e-4 against the exact Euler Riemann
  solution (gamma = (d+2)/d = 2), and at eps = 1e-2, where the kinetic solution departs
  from it;
- x-uniform granular gas in a periodic box: every cell follows the homogeneous cooling law
  of Maxwell molecules, and the same run without space;
- the energy balance of an inelastic gas between diffuse walls: heat put in by the walls,
  collisional dissipation and the change of the energy agree to O(dt).

The bounds are the values measured on the set-ups of studies/space.py (Sod tube: N = 32,
walls: N = 24, S = 3.5) times 1.5; the convergence tables are the study's
(``python studies/space.py --convergence``).
"""

import importlib.util
import pathlib

import numpy
import pytest

import granframe as gf
from granframe.model.exact import heated_maxwell_law
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.tools.studykit import mean_distances


def _study(name="space"):
    path = pathlib.Path(__file__).parent.parent / "studies" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"{name}_study", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SPACE = _study()


def test_conservative_correction_acts_on_a_batch_of_cell_blocks():
    """Q^c on f of shape (blocks, block_cells, *grid.shape), as the split step calls it:
    each distribution's mass and momentum conserved and its energy change equal to its own
    D(f), to round-off, and each equal to the correction of that distribution alone."""
    grid = gf.VelocityGrid(2, 24, 3.5)          # the wall runs' grid
    operator = gf.collision_operator("fast_spectral", grid, gf.collision_kernel("maxwell"),
                                     gf.restitution_law("constant", value=0.9))
    corrected = gf.ConservativeCorrection(operator)
    f = numpy.stack([[grid.project(grid.maxwellian(1.0 + 0.1 * i, [0.3 * j, 0.0], 0.8 + 0.1 * j)
                                   + grid.maxwellian(0.3, [-1.0, 0.2], 0.5))
                      for j in range(4)] for i in range(3)])
    q = corrected(f)
    assert q.shape == f.shape
    h, v = grid.cell_volume, grid.mesh()

    def sums(weight):
        return h * numpy.sum(q * weight, axis=(-2, -1))

    dissipation = corrected.dissipation(f)
    assert dissipation.shape == (3, 4) and numpy.all(dissipation < -0.1)
    assert numpy.abs(sums(1.0)).max() < 1e-15
    assert max(numpy.abs(sums(v[0])).max(), numpy.abs(sums(v[1])).max()) < 1e-15
    assert numpy.abs(sums(grid.speed_squared()) - dissipation).max() < 1e-15
    assert numpy.abs(corrected(f[1, 2]) - q[1, 2]).max() < 1e-15


def test_sod_tube_reaches_the_euler_solution_as_eps_vanishes():
    """50 cells, t = 0.1, dt = CFL limit (dt/eps = 27 at eps = 1e-4). Measured L1 errors at
    eps = 1e-4: rho 1.49e-2, u 2.40e-2, T 3.35e-2 (energy drift -2.1e-7); at eps = 1e-2:
    rho 2.43e-2, u 5.52e-2, T 9.14e-2, the kinetic solution's own departure from Euler."""
    errors, drift = {}, {}
    for eps in (1e-4, 1e-2):
        ds = Simulation(SPACE.sod_description(50, eps, final=0.1)).run(None, progress=False).dataset
        assert abs(float(ds.step_time.values[-1]) - 0.1) < 1e-12
        errors[eps] = SPACE.sod_errors(ds)
        mass, energy = ds.mass.values, ds.kinetic_energy.values
        assert abs(mass[-1] / mass[0] - 1) < 1e-12       # specular walls: nothing leaves
        drift[eps] = abs(energy[-1] / energy[0] - 1)
    near = errors[1e-4]
    assert near["rho"] < 0.0225 and near["u"] < 0.036 and near["T"] < 0.050, near
    assert drift[1e-4] < 2e-6, drift                      # elastic: energy conserved
    far = errors[1e-2]
    assert far["rho"] > 1.3 * near["rho"] and far["u"] > 1.8 * near["u"], errors
    assert far["T"] > 2.0 * near["T"], errors


#: two Maxwellians, T0 = 1.012 (N = 32, S = 4: the grid's D is 8e-7 off the exact law)
MIXTURE = {"name": "gaussian_mixture", "components": [
    {"density": 0.6, "velocity": [0.5, 0.0], "temperature": 0.9},
    {"density": 0.4, "velocity": [-0.75, 0.2], "temperature": 0.7}]}


def _cooling(space: bool) -> RunDescription:
    return RunDescription(
        grid={"dimension": 2, "n_modes": 32, "support_radius": 4.0}, kernel="maxwell",
        restitution={"name": "constant", "value": 0.5}, initial=MIXTURE,
        operator={"name": "fast_spectral"}, integrator="rk4", conservative=True,
        time_step=0.02, final_time=1.0, output={"snapshot_interval": 1.0},
        **({"space": {"cells": 6}} if space else {}))


def test_uniform_granular_gas_cools_by_the_homogeneous_law_in_every_cell():
    """Periodic box, x-uniform non-Maxwellian data, e = 0.5, eps = 1: T drops from 1.012 to
    0.839 by t = 1 and follows T0 exp(-rho (1-e^2) t/4) in every cell to 8.1e-7 (the grid's
    D, not the time step: dt/2 gives the same), and f equals the run without space to
    round-off."""
    description = _cooling(True)
    ds = Simulation(description).run(None, progress=False).dataset
    law = heated_maxwell_law(gf.collision_kernel("maxwell"), description.build("restitution"),
                             0.0, 1.0)
    t, T, rho = ds.step_time.values, ds.temperature.values, ds.density.values
    exact = law(t[:, None], T[0][None, :], rho[0][None, :])
    assert T[-1].max() < 0.85 * T[0].min()
    assert numpy.abs(T / exact - 1).max() < 1.5e-6
    homogeneous = Simulation(_cooling(False)).run(None, progress=False).dataset
    assert numpy.abs(ds.f.values[-1] - homogeneous.f.values[-1][None]).max() <= 1e-14 * \
        numpy.abs(homogeneous.f.values[-1]).max()
    # the recorded T counts the node v_1 = -L as +-L (granframe.velocity.moments), the
    # homogeneous one as -L: they differ by that node's momentum, 8e-11 here
    assert numpy.abs(T / homogeneous.temperature.values[:, None] - 1).max() < 1e-9


def test_energy_balance_between_diffuse_walls():
    """e = 0.9, eps = 0.2, walls at T = 1, 8 cells, t = 1 (not yet steady: dE/dt = -2.4%
    of the heat): heat in + dissipation - dE/dt = 8.2e-5 of the heat at the CFL limit and
    4.7e-5 at dt/2 (the collision step's energy change against its rate at the end of the
    step, O(dt))."""
    residuals = []
    for fraction in (1.0, 0.5):
        simulation = Simulation(SPACE.balance_description(8, fraction, final=1.0))
        ds = simulation.run(None, progress=False).dataset
        budget = SPACE.energy_balance(ds, simulation.operator, SPACE.BALANCE["knudsen"])
        assert budget["heat"] > 0.15 and budget["dissipation"] < -0.15, budget
        assert budget["mismatch"] == pytest.approx(budget["unsteadiness"] + budget["residual"],
                                                   abs=1e-12)
        residuals.append(abs(budget["residual"]))
    assert residuals[0] < 1.25e-4, residuals
    assert 1.4 < residuals[0] / residuals[1] < 2.5, residuals


def test_uniform_heated_granular_gas_follows_the_heated_law_in_every_cell():
    """The same periodic box with the heat bath tau = 0.3 (integrating-factor RK4): T rises
    from 1.012 to 1.386 by the exact law dT/dt = -rho (1-e^2) T/4 + 2 tau in every cell to
    9.1e-6, which is the homogeneous run's own distance from the law on this grid (N = 32,
    S = 4; the hotter gas fills more of the box), to round-off."""
    description = _cooling(True).replace(heat_bath=0.3, integrator="if_rk4")
    ds = Simulation(description).run(None, progress=False).dataset
    law = heated_maxwell_law(gf.collision_kernel("maxwell"), description.build("restitution"),
                             0.3, 1.0)
    t, T, rho = ds.step_time.values, ds.temperature.values, ds.density.values
    exact = law(t[:, None], T[0][None, :], rho[0][None, :])
    assert T[-1].min() > 1.3 * T[0].max()
    error = numpy.abs(T / exact - 1).max()
    assert error < 1e-5
    assert numpy.ptp(T, axis=1).max() <= 1e-14
    homogeneous = Simulation(_cooling(False).replace(heat_bath=0.3, integrator="if_rk4")).run(
        None, progress=False).dataset
    T_h = homogeneous.temperature.values
    assert error == pytest.approx(numpy.abs(T_h / law(t, T_h[0], 1.0) - 1).max(), rel=1e-6)


def test_sod_tube_at_eps_1e_8_with_the_cfl_step():
    """20 cells, t = 0.1, dt = the transport's CFL limit = 6.7e5 eps: the penalised ARS(2,2,2)
    step with the discrete-Maxwellian penalisation runs to the end with mass and energy
    conserved to round-off (measured 6.7e-16 and 0), the negative mass share 2.0e-4 (the
    Nyquist projection's ringing, as at eps = 1e-2), L1 errors against the exact Euler
    solution 1.97e-2, 4.28e-2, 5.43e-2 (rho, u, T) and distances to the eps -> 0 limit of the
    same transport (f set to its discrete Maxwellian in every cell) 7.2e-4, 2.7e-3, 3.4e-3.
    The bounds are 1.5 times these."""
    study = _study("euler_limit")
    run = study.sod_run(20, 1e-8, final=0.1)
    assert run["dt"] / 1e-8 > 6e5 and run["steps"] == 15
    assert run["energy_drift"] < 1e-13 and run["mass_drift"] < 1e-13, run
    assert run["negative"] < 3e-4, run
    errors, limit = run["exact"], mean_distances(run["fields"], study.limit_fields(20, final=0.1))
    assert errors["rho"] < 0.03 and errors["u"] < 0.065 and errors["T"] < 0.082, errors
    assert limit["rho"] < 1.1e-3 and limit["u"] < 4.1e-3 and limit["T"] < 5.1e-3, limit


def test_a_penalised_step_of_many_collision_times_needs_the_conservative_correction():
    """Without the correction the penalised scheme amplifies the operator's energy defect by
    nu dt/eps (the Sod tube drifts 1.7e-3 in energy by t = 0.1 at eps = 1e-4, nu dt/eps = 67,
    and loses positivity at 1e-5): above 100 the run is refused, naming the parameters."""
    with pytest.raises(ValueError, match="time_step.*collision times.*conservative = true"):
        Simulation(SPACE.sod_description(20, 1e-5, final=0.1, conservative=False))
    Simulation(SPACE.sod_description(20, 1e-4, final=0.1, conservative=False))
