"""Walls that know the time and their side; the vibrating diffuse wall (docs/space.md,
"Moving and vibrating walls"); the momentum through the walls and the cell next to a wall
(docs/space.md, "Wall pressure and shear stress").

1. The energy a vibrating wall puts per period into a given incoming distribution: the
   grid wall (``emit`` at M times of a period) against the closed form with the grid's
   own sums (to round-off) and the continuous closed form (O(h^2), observed order).
2. Zero mass flux at every t on both sides; the right wall with the same lab-frame motion.
3. Constant arrays cached per wall, grid and array namespace: no host/device copies after
   the first call.
4. Bad parameters refused, naming them.
5. A collisionless space run between a vibrating and a specular wall: mass to round-off,
   and the energy the vibration puts in over a period as the closed form says.
6. Free-molecular Couette flow: the grid state is steady and its wall momentum (pressure
   and shear stress) the closed form to round-off, a run reaches it, the grid's shear
   stress converges to the continuum's at second order in h; the recorded wall momentum
   is the momentum change of the gas.
7. The ghost cells of an emitting wall extend the data linearly; the shear stress of the
   cell next to a wall is the wall's momentum flux in a Couette flow with collisions.

:func:`injected_energy_rows`, :func:`vibrating_run_energy` and
:func:`couette_refinement_rows` also make the tables of docs/space.md.
"""

import math

import numpy
import pytest

import granframe as gf
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import exact
from granframe.space.boundaries import Diffuse, Specular, Vibrating
from granframe.space.transport import reflect, upwind_speeds
from granframe.testing import conformance as kit
from granframe.testing.transfers import CountingBackend

#: the wall of the energy check: T_w = 1, A omega = 0.5 (eps = 0.5), period 2 pi / 5
WALL = {"temperature": 1.0, "amplitude": 0.1, "frequency": 5.0}
#: the arriving gas: a Maxwellian of density 1, temperature 0.5, drifting into the wall
T_IN, U_IN = 0.5, -0.2
#: the fixed box of the refinement: S = 3.5 (L = 7.72)
SUPPORT = 3.5


def _incoming(grid):
    return grid.maxwellian(1.0, [U_IN] + [0.0] * (grid.dimension - 1), T_IN)


def grid_wall_energy(wall, grid, incoming, times: int, side: str = "left") -> float:
    """The energy the grid wall puts in over one period, sum_k (P/M) sum_v F |v|^2/2 dv with
    F = c^+ emit(t_k) + c^- in at t_k = k P / M: the periodic trapezoid rule in time,
    spectrally accurate for the smooth periodic flux."""
    positive, negative = upwind_speeds(grid)
    weight = 0.5 * grid.speed_squared() * grid.cell_volume
    step = wall.period / times
    total = math.fsum(float(numpy.sum((positive * wall.emit(incoming, grid, numpy, t=k * step,
                                                                 side=side)
                                       + negative * incoming) * weight))
                      for k in range(times))
    return step * total


def injected_energy_rows(sizes=(16, 32, 64), dimension=2, times=16):
    """For each N on the box S = SUPPORT: h, the grid wall's energy per period (``emit`` at
    ``times`` points), its relative distance from the closed form with the grid's sums and
    from the continuous closed form, and the change when the time points double."""
    wall = Vibrating(**WALL)
    j0, j2 = exact.half_range_maxwellian_fluxes(dimension, T_IN, -U_IN)
    continuous = exact.vibrating_wall_energy_per_period(dimension, **WALL, incoming_flux=j0,
                                                        incoming_energy_flux=j2)["energy"]
    rows = []
    for n in sizes:
        grid = gf.VelocityGrid(dimension, n, SUPPORT)
        wall.check(grid)
        f = _incoming(grid)
        energy = grid_wall_energy(wall, grid, f, times)
        closed = exact.vibrating_wall_energy_per_period_grid(grid, **WALL, incoming=f)["energy"]
        rows.append({"N": n, "h": grid.spacing, "energy": energy,
                     "grid": (energy - closed) / abs(closed),
                     "continuum": (energy - continuous) / abs(continuous),
                     "time": abs(grid_wall_energy(wall, grid, f, 2 * times) - energy)
                     / abs(energy)})
    return rows, continuous


def test_the_injected_energy_per_period_is_the_closed_form():
    """Against the grid's closed form to 1e-12 (measured 2e-16 to 3e-16), and against the
    continuous one to O(h^2): measured -0.115, -0.0228, -0.0055 at N = 16, 32, 64
    (orders 2.34, 2.05)."""
    rows, continuous = injected_energy_rows()
    assert continuous > 0.3                          # the hotter wall heats the gas
    for row in rows:
        assert abs(row["grid"]) < 1e-12, row
        assert row["time"] < 1e-13, row              # 16 time points are converged
    errors = [abs(row["continuum"]) for row in rows]
    orders = [math.log2(a / b) for a, b in zip(errors[:-1], errors[1:])]
    assert errors[-1] < 1e-2, errors
    assert all(1.8 < p < 2.6 for p in orders), (errors, orders)


def test_the_energy_of_the_vibration_is_its_closed_form_and_series():
    """The half-range fluxes against quadrature; the period mean of J_2/J_0 against its
    series in eps = A omega / sqrt(T_w): the remainder falls like eps^6 (measured ratios
    63.9, 64.0 when eps halves), and the vibration's share is (1/2 - pi/8) eps^2 T_w Phi_in P
    at second order."""
    from scipy import integrate

    for d, T, u in ((2, 1.3, 0.7), (3, 0.4, -0.9), (2, 2.0, 0.0)):
        sigma = math.sqrt(T)

        def m(v):
            return math.exp(-(v - u) ** 2 / (2 * T)) / math.sqrt(2 * math.pi * T)
        j0 = integrate.quad(lambda v: v * m(v), 0.0, u + 40 * sigma, epsabs=0, epsrel=1e-13)[0]
        j2 = (0.5 * integrate.quad(lambda v: v ** 3 * m(v), 0.0, u + 40 * sigma, epsabs=0,
                                   epsrel=1e-13)[0] + 0.5 * (d - 1) * T * j0)
        assert exact.half_range_maxwellian_fluxes(d, T, u) == pytest.approx((j0, j2), rel=1e-12)
    T, omega, flux = 1.3, 5.0, 0.8
    remainders = []
    for eps in (0.2, 0.1, 0.05):
        amplitude = eps * math.sqrt(T) / omega
        result = exact.vibrating_wall_energy_per_period(2, T, amplitude, omega, flux, 0.0)
        remainders.append(result["energy"] - result["expansion"])
        rest = exact.vibrating_wall_energy_per_period(2, T, 0.0, omega, flux, 0.0)["energy"]
        heating = (0.5 - math.pi / 8) * eps ** 2 * T * flux * result["period"]
        assert result["energy"] - rest == pytest.approx(heating, rel=eps ** 2 / 50)
    ratios = [a / b for a, b in zip(remainders[:-1], remainders[1:])]
    assert all(55 < r < 70 for r in ratios), (remainders, ratios)


# -- mass, sides, device -------------------------------------------------------------------

MASS_GRIDS = ((2, 32, 5.0), (3, 16, 5.0))


@pytest.mark.parametrize("d,n,support", MASS_GRIDS)
def test_zero_mass_flux_at_every_time_on_both_sides(d, n, support):
    """sum_v F dv = 0 to 1e-14 of the arriving flux at 40 times over three periods and at
    the eighths of a period, on both sides, for random and drifting incoming values."""
    grid = gf.VelocityGrid(d, n, support)
    wall = Vibrating(**WALL)
    wall.check(grid)
    positive, negative = upwind_speeds(grid)
    rng = numpy.random.default_rng(1)
    times = numpy.concatenate([rng.uniform(0.0, 3 * wall.period, 40),
                               numpy.arange(8) * wall.period / 8])
    for incoming in (rng.uniform(0.1, 1.0, grid.shape), _incoming(grid)):
        arriving = float(numpy.sum(-negative * incoming))
        for t in times:
            for side in ("left", "right"):
                out = wall.emit(incoming, grid, numpy, t=float(t), side=side)
                net = float(numpy.sum(positive * out + negative * incoming))
                assert abs(net) <= 1e-14 * arriving, (t, side, net / arriving)


def _lab_emission(grid, incoming_lab, temperature, velocity, into):
    """What a diffuse wall moving with lab velocity ``velocity`` along x sends into the
    domain from scratch: the grid Maxwellian of that velocity on the nodes of c^± (``into``
    "+" for the left wall, "-" for the right one), scaled so that it carries away the lab
    flux that arrives (c^∓)."""
    positive, negative = (numpy.broadcast_to(c, grid.shape) for c in upwind_speeds(grid))
    leave, arrive = (positive, -negative) if into == "+" else (-negative, positive)
    m = grid.maxwellian(1.0, [velocity] + [0.0] * (grid.dimension - 1), temperature)
    if into == "+":
        # the node -L leaves the left wall at +L: the Maxwellian there at v_1 = +L
        m[0] = grid.maxwellian(1.0, [-velocity] + [0.0] * (grid.dimension - 1), temperature)[0]
    m = numpy.where(leave > 0, m, 0.0)
    return m * numpy.sum(arrive * incoming_lab) / numpy.sum(leave * m), leave > 0


@pytest.mark.parametrize("d,n,support", MASS_GRIDS)
def test_the_right_wall_moves_with_the_same_lab_velocity(d, n, support):
    """A wall moving with U(t) along +x in the lab: the left one (x = 0) emits the lab
    Maxwellian of velocity U(t) into v_1 > 0, the right one (x = ell, called on the
    reflected values and reflected back) the same Maxwellian into v_1 < 0, each with the
    flux that arrives (to 1e-13); the right wall at t is the left one at t + P/2; at a time
    of U = 0 both are the resting diffuse wall."""
    grid = gf.VelocityGrid(d, n, support)
    wall = Vibrating(**WALL)
    lab = numpy.random.default_rng(2).uniform(0.1, 1.0, grid.shape)
    for t in numpy.arange(8) * wall.period / 8 + 0.1:
        t = float(t)
        velocity = wall.speed * math.cos(wall.frequency * t)
        left = wall.emit(lab, grid, numpy, t=t, side="left")
        expected, leaving = _lab_emission(grid, lab, wall.temperature, velocity, "+")
        assert numpy.allclose(left[leaving], expected[leaving], rtol=1e-13, atol=0.0)
        right = reflect(wall.emit(reflect(lab, d), grid, numpy, t=t, side="right"), d)
        expected, leaving = _lab_emission(grid, lab, wall.temperature, velocity, "-")
        assert numpy.allclose(right[leaving], expected[leaving], rtol=1e-13, atol=0.0)
        mirrored = wall.emit(lab, grid, numpy, t=t + 0.5 * wall.period, side="left")
        assert numpy.allclose(wall.emit(lab, grid, numpy, t=t, side="right"), mirrored,
                              rtol=1e-13, atol=0.0)
    resting = Diffuse(temperature=wall.temperature)
    for side in ("left", "right"):
        assert numpy.allclose(wall.emit(lab, grid, numpy, t=wall.period / 4, side=side),
                              resting.emit(lab, grid, numpy), rtol=1e-13, atol=0.0)


def test_the_grid_energy_per_period_is_the_same_on_both_sides():
    """The right wall puts per period into the mirrored incoming values what the left one
    puts into them (U and -U alternate over a period), to round-off."""
    grid = gf.VelocityGrid(2, 32, SUPPORT)
    wall = Vibrating(**WALL)
    f = _incoming(grid)
    left = grid_wall_energy(wall, grid, f, 16, "left")
    assert grid_wall_energy(wall, grid, f, 16, "right") == pytest.approx(left, rel=1e-13)


@pytest.mark.parametrize("wall", [Specular(), Diffuse(temperature=1.5, velocity=0.3,
                                                      accommodation=0.5), Vibrating(**WALL)],
                         ids=["specular", "diffuse", "vibrating"])
def test_walls_copy_nothing_between_host_and_device_after_their_first_call(wall):
    """On the counting backend (NumPy standing for a device): after one call of ``emit``
    and ``ghosts``, twelve more at other times and sides cross nothing."""
    grid = gf.VelocityGrid(2, 32, 5.0)
    backend = CountingBackend()
    xp = backend.xp
    incoming = xp.asarray(_incoming(grid))
    cells = xp.asarray(numpy.stack([_incoming(grid)] * 2))
    wall.emit(incoming, grid, xp, t=0.0, side="left")
    wall.ghosts(cells, grid, xp, t=0.0, side="left")
    before = len(backend.log)
    for k in range(6):
        for side in ("left", "right"):
            wall.emit(incoming, grid, xp, t=0.37 * k, side=side)
            wall.ghosts(cells, grid, xp, t=0.37 * k, side=side)
    assert backend.log[before:] == []
    out = wall.emit(incoming, grid, xp, t=0.2, side="right").get()
    assert numpy.array_equal(out, wall.emit(_incoming(grid), grid, numpy, t=0.2, side="right"))


# -- the conformance kit on time-dependent walls ---------------------------------------------

class WrongPeriod(Vibrating):
    """Declares half its period."""

    @property
    def period(self):
        return math.pi / self.frequency


class LeakyOnTheRight(Vibrating):
    """Loses 1 % of what arrives, on the right only."""

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        out = super().emit(incoming, grid, xp, t=t, side=side)
        return 0.99 * out if side == "right" else out


def test_the_kit_checks_walls_over_their_period_and_on_both_sides():
    kit.check_boundary(Vibrating(**WALL))
    with pytest.raises(AssertionError, match=r"WrongPeriod: the emission at t \+ period "
                                             r"\(period = 0\.628319\) differs"):
        kit.check_wall_period(WrongPeriod(**WALL))
    with pytest.raises(AssertionError, match=r"LeakyOnTheRight: net mass flux through the wall "
                                             r".* at t = 0 on the right, 0\.01 of the arriving"):
        kit.check_wall_mass_flux(LeakyOnTheRight(**WALL))
    eighths = [k * 2 * math.pi / 40 for k in range(8)]
    assert kit._wall_times(Vibrating(**WALL)) == pytest.approx(eighths)
    assert kit._wall_times(Specular()) == kit.WALL_TIMES


# -- bad input -----------------------------------------------------------------------------

@pytest.mark.parametrize("params,name,error", [
    ({"amplitude": -0.1, "frequency": 5.0}, "amplitude", ValueError),
    ({"amplitude": math.inf, "frequency": 5.0}, "amplitude", ValueError),
    ({"amplitude": 0.1, "frequency": 0.0}, "frequency", ValueError),
    ({"amplitude": 0.1, "frequency": -2.0}, "frequency", ValueError),
    ({"amplitude": 0.1, "frequency": "fast"}, "frequency", TypeError),
    ({"amplitude": 0.1, "frequency": 5.0, "temperature": 0.0}, "temperature", ValueError),
    ({"amplitude": True, "frequency": 5.0}, "amplitude", TypeError),
])
def test_bad_parameters_are_refused_naming_them(params, name, error):
    with pytest.raises(error, match=rf"^Vibrating: parameter '{name}' = .* is invalid; "):
        Vibrating(**params)


@pytest.mark.parametrize("params,support,name,what", [
    ({"amplitude": 0.5, "frequency": 10.0}, 3.5, "amplitude", r"A omega must be <= 1\.655"),
    ({"amplitude": 1e200, "frequency": 1e200}, 3.5, "amplitude", "does not fit the velocity box"),
    ({"amplitude": 0.3, "frequency": 5.0}, 5.0, "amplitude",
     r"is not resolved by the nodes \(h = 1\.379\): its discrete half-range flux is off by 58 %"),
    ({"amplitude": 0.01, "frequency": 5.0, "temperature": 0.2}, 3.5, "temperature",
     r"must be >= h\^2 / 4 = 0\.2331"),
    ({"amplitude": 0.01, "frequency": 5.0, "temperature": 3.0}, 3.5, "temperature",
     "does not fit the velocity box"),
])
def test_walls_that_do_not_fit_the_grid_are_refused(params, support, name, what):
    grid = gf.VelocityGrid(2, 16, support)
    with pytest.raises(ValueError, match=rf"^Vibrating: parameter '{name}' = .* is invalid; "
                                         rf".*{what}"):
        Vibrating(**params).check(grid)


def test_a_bad_side_and_bad_closed_form_arguments_are_refused():
    grid = gf.VelocityGrid(2, 16, SUPPORT)
    wall = Vibrating(**WALL)
    with pytest.raises(ValueError, match=r"^Vibrating: parameter 'side' = 'top' is invalid; "
                                         r"must be 'left' .* or 'right'"):
        wall.emit(_incoming(grid), grid, numpy, t=0.0, side="top")
    owner = "vibrating_wall_energy_per_period"
    for args, name in (((4, 1.0, 0.1, 5.0, 1.0, 1.0), "dimension"),
                       ((2, -1.0, 0.1, 5.0, 1.0, 1.0), "temperature"),
                       ((2, 1.0, -0.1, 5.0, 1.0, 1.0), "amplitude"),
                       ((2, 1.0, 0.1, 0.0, 1.0, 1.0), "frequency"),
                       ((2, 1.0, 0.1, 5.0, 0.0, 1.0), "incoming_flux"),
                       ((2, 1.0, 0.1, 5.0, 1.0, -1.0), "incoming_energy_flux")):
        with pytest.raises(ValueError, match=rf"^{owner}: parameter '{name}'"):
            exact.vibrating_wall_energy_per_period(*args)
    for incoming, what in ((numpy.ones((16, 8)), "grid's shape"),
                           (numpy.where(grid.mesh()[0] < 0, 0.0, 1.0) * numpy.ones(grid.shape),
                            "positive arriving flux")):
        with pytest.raises(ValueError, match=rf"(?s)^{owner}_grid: parameter 'incoming' .*{what}"):
            exact.vibrating_wall_energy_per_period_grid(grid, 1.0, 0.1, 5.0, incoming)
    with pytest.raises(ValueError, match=r"^half_range_maxwellian_fluxes: parameter 'velocity'"):
        exact.half_range_maxwellian_fluxes(2, 1.0, math.nan)


def test_a_description_with_a_wall_that_does_not_fit_is_refused():
    space = {"cells": 8, "left": {"name": "vibrating", "amplitude": 0.5, "frequency": 10.0},
             "right": "specular", "collisions": False}
    with pytest.raises(ValueError, match=r"Vibrating: parameter 'amplitude' = 0\.5 is invalid"):
        Simulation(RunDescription.from_dict(_description(space, 0.01, 0.01)))


# -- a space run ---------------------------------------------------------------------------

RUN_GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.5}
#: the run's wall: T_w = 1, A omega = 0.5, period pi / 10 (0.31)
RUN_WALL = {"name": "vibrating", "temperature": 1.0, "amplitude": 0.025, "frequency": 20.0}
RESTING = {"name": "diffuse", "temperature": 1.0}


def _description(space, final_time, time_step):
    return {"final_time": final_time, "time_step": time_step, "grid": RUN_GRID,
            "kernel": {"name": "maxwell"}, "restitution": {"name": "constant", "value": 1.0},
            "initial": {"name": "maxwellian", "temperature": 1.0},
            "output": {"snapshot_interval": final_time}, "space": space}


def vibrating_run_energy(side: str, cells: int = 8):
    """Collisionless runs over one period from the Maxwellian at the wall's temperature,
    MUSCL, dt = P / ceil(P / CFL limit), with the vibrating wall on ``side`` and a specular
    one on the other, and the same with a resting diffuse wall: the datasets, and the
    closed form's energy per period of the vibration, Delta E_h(A) - Delta E_h(0), for the
    initial face values (:func:`exact.vibrating_wall_energy_per_period_grid`)."""
    grid = gf.VelocityGrid(**RUN_GRID)
    period = 2 * math.pi / RUN_WALL["frequency"]
    limit = 2 * 0.5 * (1.0 / cells) / (grid.half_width - grid.spacing)
    dt = period / math.ceil(period / limit)

    def run(wall):
        ends = {"left": wall, "right": "specular"} if side == "left" else \
            {"left": "specular", "right": wall}
        space = {"cells": cells, "reconstruction": "muscl", "collisions": False, **ends}
        return Simulation(RunDescription.from_dict(_description(space, period, dt))).run(
            None, progress=False).dataset

    vibrating, resting = run(RUN_WALL), run(RESTING)
    face = vibrating.f.values[0, 0 if side == "left" else -1]
    face = face if side == "left" else reflect(face, grid.dimension)
    params = {k: RUN_WALL[k] for k in ("temperature", "amplitude", "frequency")}
    closed = (exact.vibrating_wall_energy_per_period_grid(grid, **params, incoming=face)["energy"]
              - exact.vibrating_wall_energy_per_period_grid(
                  grid, **{**params, "amplitude": 0.0}, incoming=face)["energy"])
    return vibrating, resting, closed, dt


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_run_with_a_vibrating_wall_keeps_its_mass_and_gets_the_energy_of_the_vibration(side):
    """Mass to round-off, the energy balance of the walls to round-off; the step's energy
    from the vibration (vibrating run minus resting run) follows the wall's lab velocity:
    +cos(omega t) on the left, -cos on the right (the right wall moving along +x recedes
    from the gas); over the period it is the closed form for the initial face values, to
    3 % (measured -0.50 % on the left, +1.40 % on the right; -0.28 %, +1.28 % on 32 cells:
    the arriving flux changes a little within the period in the run, and the closed form
    holds it fixed). A transport that did not tell the wall its time would put in a
    first-order energy (about 0.04 here against 0.0032), one that did not tell its side
    the opposite sign of cos."""
    vibrating, resting, closed, dt = vibrating_run_energy(side)
    wall = 0 if side == "left" else 1
    mass = vibrating.mass.values
    assert numpy.abs(mass / mass[0] - 1).max() < 1e-13
    assert numpy.abs(vibrating.wall_mass.values).max() < 1e-15 * mass[0]
    energy = vibrating.kinetic_energy.values
    assert abs(energy[-1] - energy[0] - vibrating.wall_energy.values.sum()) < 1e-14 * energy[0]
    times = vibrating.step_time.values
    assert times[-1] == pytest.approx(2 * math.pi / RUN_WALL["frequency"], rel=1e-12)
    extra = (vibrating.wall_energy.values[1:, wall] - resting.wall_energy.values[1:, wall])
    lab = numpy.cos(RUN_WALL["frequency"] * (times[1:] - 0.5 * dt))
    sign = 1.0 if side == "left" else -1.0
    strong = numpy.abs(lab) > 0.25
    assert numpy.all(numpy.sign(extra[strong]) == sign * numpy.sign(lab[strong])), (extra, lab)
    assert sign * numpy.sum(extra * lab) > 0.95 * numpy.linalg.norm(extra) * numpy.linalg.norm(lab)
    assert closed > 0
    assert extra.sum() == pytest.approx(closed, rel=0.03), (extra.sum(), closed)


# -- the momentum through the walls: pressure and shear stress -----------------------------

COUETTE_GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.5}


def _couette(grid, cells, reconstruction, accommodation, final, time_step, speed=1.0):
    """Collisionless plane Couette flow: diffuse walls at T_w = 1 moving along v_2 with
    -speed/2 (x = 0) and +speed/2 (x = 1)."""
    walls = {side: {"name": "diffuse", "temperature": 1.0, "velocity": sign * 0.5 * speed,
                    "accommodation": accommodation}
             for side, sign in (("left", -1.0), ("right", 1.0))}
    return RunDescription.from_dict({
        "final_time": final, "time_step": time_step, "grid": grid,
        "kernel": {"name": "maxwell"}, "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "maxwellian", "temperature": 1.0},
        "output": {"snapshot_interval": final},
        "space": {"cells": cells, "reconstruction": reconstruction, "collisions": False,
                  **walls}})


@pytest.mark.parametrize("d,n,reconstruction,accommodation", [
    (2, 16, "muscl", 1.0), (2, 24, "weno5", 0.6), (3, 16, "upwind", 0.8)])
def test_the_grid_couette_state_is_steady_and_its_wall_momentum_is_the_closed_form(
        d, n, reconstruction, accommodation):
    """The free-molecular Couette state on the grid (:func:`exact.free_molecular_couette_grid`)
    in every cell stays put over 5 steps (to 1e-13 of max f; measured 2e-14), the fields
    are its fields (to 1e-13) and the recorded wall momentum per unit time is its closed
    form (P_11, P_12, 0) through the wall at x = 0 and its negative at x = ell, to 1e-11
    (measured 2.5e-12: the node -L, which moves both ways, holds the mean of the two walls'
    emissions, exp(-L^2/2) = 1e-13 of the peak, and its arriving flux enters the
    emission's Phi with the weight L/2); no mass or energy goes through the walls."""
    from granframe.run.problems import make_problem

    grid = gf.VelocityGrid(d, n, 3.5)
    cells = 8
    dt = 0.5 * (1.0 / cells) / (grid.half_width - grid.spacing)
    problem = make_problem(_couette({"dimension": d, "n_modes": n, "support_radius": 3.5},
                                    cells, reconstruction, accommodation, 10 * dt, dt))
    closed = exact.free_molecular_couette_grid(grid, 1.0, 1.0, 1.0, accommodation)
    state = problem.state(numpy.stack([closed["f"]] * cells))
    for k in range(5):
        state = problem.step(k * dt, state, dt)
        record = problem.record(state)
    f = problem.snapshot(state)
    assert numpy.abs(f - closed["f"]).max() < 1e-13 * closed["f"].max()
    assert numpy.abs(record["pressure_tensor"] - closed["P"]).max() < 1e-13
    assert record["wall_momentum"].shape == (2, d)
    assert numpy.abs(record["wall_momentum"] / dt - closed["wall_momentum"]).max() < 1e-11
    assert numpy.abs(record["wall_mass"]).max() < 1e-17
    assert numpy.abs(record["wall_energy"]).max() < 1e-10 * dt      # measured 2e-11 dt


def test_a_collisionless_couette_run_reaches_the_free_molecular_shear_stress():
    """Between diffuse walls at +-U/2 (U = 1, T_w = 1) from the Maxwellian at rest, the
    run (8 cells, upwind, 2D N = 16, t = 8) reaches the grid closed form with the run's
    mass and its resting nodes v_1 = 0: the last step's wall momentum per unit time to
    1e-11 (measured 2.5e-12; 7.6e-9 at t = 4.35, 1.4e-10 at t = 5.45), and P_12 of every
    cell (to 1e-12 of it; measured 3.2e-13). Against the continuum's
    P_12 = -rho U sqrt(T_w / (2 pi))
    it is the trapezoidal rule's 1 - h^2 / (12 T_w) - h^4 / (240 T_w^2) (-8.18 % at
    h = 0.966); the pressure rho T_w is spectrally accurate (the wall P_11 is the grid's
    P_11 of the state, whose resting nodes keep the initial Maxwellian)."""
    grid = gf.VelocityGrid(**COUETTE_GRID)
    cells, final = 8, 8.0
    dt = final / math.ceil(final / (0.9 * (1.0 / cells) / (grid.half_width - grid.spacing)))
    ds = Simulation(_couette(COUETTE_GRID, cells, "upwind", 1.0, final, dt)).run(
        None, progress=False).dataset
    closed = exact.free_molecular_couette_grid(grid, 1.0, 1.0, float(ds.mass[0]),
                                               rest=ds.f.values[0, 0])
    rate = ds.wall_momentum.values[-1] / dt
    assert numpy.abs(rate - closed["wall_momentum"]).max() < 1e-11, (rate, closed)
    shear = ds.pressure_tensor.values[-1, :, 0, 1]
    assert numpy.abs(shear - closed["P12"]).max() < 1e-12 * abs(closed["P12"])
    continuum = exact.free_molecular_couette(2, 1.0, 1.0, 1.0)
    h2 = grid.spacing ** 2
    assert closed["P12"] / continuum["P12"] == pytest.approx(1 - h2 / 12 - h2 * h2 / 240,
                                                             abs=1e-3)
    assert rate[0, 1] == pytest.approx(-rate[1, 1], rel=1e-12)      # the drag on both walls


def couette_refinement_rows(sizes=(16, 32, 64, 128), dimension=2, accommodation=1.0):
    """For each N on the box S = 3.5 (T_w = 1, U = 1, rho = 1): h, the grid closed form's
    P_12 and P_11 and their relative distances from the continuum, and the observed order
    log2 of the ratio of successive P_12 errors."""
    continuum = exact.free_molecular_couette(dimension, 1.0, 1.0, 1.0, accommodation)
    rows = []
    for n in sizes:
        grid = gf.VelocityGrid(dimension, n, 3.5)
        closed = exact.free_molecular_couette_grid(grid, 1.0, 1.0, 1.0, accommodation)
        rows.append({"N": n, "h": grid.spacing, "P12": closed["P12"], "P11": closed["P11"],
                     "shear": closed["P12"] / continuum["P12"] - 1,
                     "pressure": closed["P11"] / continuum["P11"] - 1})
    for a, b in zip(rows[:-1], rows[1:]):
        b["order"] = math.log2(a["shear"] / b["shear"])
    return rows, continuum


@pytest.mark.parametrize("accommodation", [1.0, 0.5])
def test_the_grid_shear_stress_converges_to_the_continuum_at_second_order(accommodation):
    """The grid's P_12 against -alpha/(2 - alpha) rho U sqrt(T_w/(2 pi)): relative errors
    -8.18e-2, -1.97e-2, -4.87e-3, -1.21e-3 at N = 16 .. 128 (orders 2.06, 2.01, 2.00, for
    both accommodations: the tangential profiles are spectrally accurate, the half-range
    sum in v_1 is the trapezoidal rule with its kink at v_1 = 0); P_11 = rho T_w to 1e-11
    from N = 32 on (5.4e-8 at N = 16)."""
    rows, continuum = couette_refinement_rows(accommodation=accommodation)
    assert continuum["P12"] == pytest.approx(-accommodation / (2 - accommodation)
                                             / math.sqrt(2 * math.pi), rel=1e-15)
    for row in rows:
        h2 = row["h"] ** 2
        assert row["shear"] == pytest.approx(-h2 / 12 - h2 * h2 / 240, abs=2e-3 * h2), row
        assert abs(row["pressure"]) < (1e-7 if row["N"] == 16 else 1e-11), row
    assert all(1.95 < row["order"] < 2.1 for row in rows[1:]), rows


def test_the_free_molecular_couette_flow_is_its_two_streams():
    """The closed form against quadrature of the two half-range streams
    rho M(v_1) t^±(v_t): P_12, P_11, P_22, T and q for alpha = 1, 0.5 in 2D and 3D."""
    from scipy import integrate

    for d, alpha, (T, U, rho) in ((2, 1.0, (1.3, 0.8, 0.7)), (3, 0.5, (0.6, -1.1, 2.0))):
        result = exact.free_molecular_couette(d, T, U, rho, alpha)

        # the mean and mean square of v_2 of the streams leaving each wall, by iterating
        # the walls' reflection: t^+ = (1 - alpha) t^- + alpha m_{-U/2}, and back
        plus = minus = (0.0, T)
        for _ in range(200):
            plus = tuple((1 - alpha) * a + alpha * b
                         for a, b in zip(minus, (-U / 2, T + U * U / 4)))
            minus = tuple((1 - alpha) * a + alpha * b
                          for a, b in zip(plus, (U / 2, T + U * U / 4)))

        def m(v):
            return math.exp(-v * v / (2 * T)) / math.sqrt(2 * math.pi * T)
        half = [integrate.quad(lambda v: v ** k * m(v), 0, 40 * math.sqrt(T), epsabs=0,
                               epsrel=1e-13)[0] for k in (0, 1, 2)]
        shear = rho * half[1] * (plus[0] - minus[0])    # v_1 > 0 with t^+, v_1 < 0 with t^-
        square = 0.5 * (plus[1] + minus[1])
        assert result["P12"] == pytest.approx(shear, rel=1e-12)
        assert result["P11"] == pytest.approx(2 * rho * half[2], rel=1e-12)
        assert result["P"][1, 1] == pytest.approx(2 * rho * half[0] * square, rel=1e-12)
        assert result["T"] == pytest.approx(T + U * U / (4 * d), rel=1e-14)
        assert numpy.all(result["q"] == 0.0) and numpy.all(result["u"] == 0.0)
        assert result["wall_momentum"][0, :2] == pytest.approx([result["P11"], result["P12"]])
        assert numpy.array_equal(result["wall_momentum"][1], -result["wall_momentum"][0])
    for args, name in (((4, 1.0, 1.0, 1.0), "dimension"), ((2, 0.0, 1.0, 1.0), "temperature"),
                       ((2, 1.0, math.inf, 1.0), "velocity"), ((2, 1.0, 1.0, -1.0), "density"),
                       ((2, 1.0, 1.0, 1.0, 0.0), "accommodation")):
        with pytest.raises(ValueError, match=rf"^free_molecular_couette: parameter '{name}'"):
            exact.free_molecular_couette(*args)
    grid = gf.VelocityGrid(2, 16, 3.5)
    with pytest.raises(ValueError, match=r"^free_molecular_couette_grid: parameter 'rest'"):
        exact.free_molecular_couette_grid(grid, 1.0, 1.0, 1.0, rest=numpy.ones(3))


def test_the_wall_momentum_is_the_momentum_change_of_the_gas():
    """Collisionless, MUSCL, 8 cells: a moving diffuse wall (alpha = 0.7) on the left and a
    specular one on the right, from a Riemann problem moving along v_1 and v_2. The
    momentum of the gas, sum_x rho u dx, changes by what the walls let in (both
    components, to 1e-15 of the largest; measured 1e-16), and the mass stays; the record is
    (step_time, wall, axis) with the axis names v1, v2 and its long name."""
    initial = {"name": "riemann", "left": {"density": 1.0, "velocity": [0.3, 0.2]},
               "right": {"density": 0.5, "velocity": [-0.2, 0.0], "temperature": 0.8}}
    data = {"final_time": 0.4, "time_step": 0.01, "grid": COUETTE_GRID,
            "kernel": {"name": "maxwell"}, "restitution": {"name": "constant", "value": 1.0},
            "initial": initial, "output": {"snapshot_interval": 0.4},
            "space": {"cells": 8, "reconstruction": "muscl", "collisions": False,
                      "left": {"name": "diffuse", "temperature": 1.2, "velocity": 0.4,
                               "accommodation": 0.7},
                      "right": "specular"}}
    ds = Simulation(RunDescription.from_dict(data)).run(None, progress=False).dataset
    assert ds.wall_momentum.dims == ("step_time", "wall", "axis")
    assert list(ds.axis.values) == ["v1", "v2"]
    assert ds.wall_momentum.attrs["long_name"].startswith("momentum (components v1 ... vd)")
    momentum = (ds.density * ds.velocity).sum("x").values / 8
    entered = numpy.cumsum(ds.wall_momentum.sum("wall").values, axis=0)
    assert numpy.all(ds.wall_momentum.values[0] == 0.0)
    scale = numpy.abs(entered).max()
    assert scale > 1e-2                                  # the walls push and drag the gas
    assert numpy.abs(momentum - momentum[0] - entered).max() < 1e-15 * max(scale, 1.0)
    specular = ds.wall_momentum.sel(wall="right").values[1:]
    assert numpy.all(specular[:, 0] < 0) and numpy.abs(specular[:, 1]).max() < 1e-17
    mass = ds.mass.values
    assert numpy.abs(mass / mass[0] - 1).max() < 1e-14


# -- the cell next to a wall ---------------------------------------------------------------

@pytest.mark.parametrize("wall", [Diffuse(temperature=1.2, velocity=0.3, accommodation=0.6),
                                  Vibrating(**WALL)], ids=["diffuse", "vibrating"])
def test_the_ghost_cells_of_an_emitting_wall_extend_the_data_linearly(wall):
    """Cells linear in x at every node: the ghosts of the arriving nodes continue them, so
    MUSCL's face value at the wall is the linear value (3 f_0 - f_1)/2 (the even extension
    f_{-1} = f_0 gave f_0); those of the leaving nodes are max(2 f_w - f_k, 0) about the wall's
    emission f_w of that face value; steep data give ghosts clipped at 0, never negative."""
    from granframe.space.reconstruction import MUSCL

    grid = gf.VelocityGrid(2, 16, 3.5)
    positive, negative = (numpy.broadcast_to(c, grid.shape) for c in upwind_speeds(grid))
    rng = numpy.random.default_rng(3)
    base = _incoming(grid) + 0.1
    gradient = rng.uniform(-0.2, 0.2, grid.shape) * base
    inside = numpy.stack([base + (k + 0.5) * gradient for k in range(2)])    # f_0, f_1
    ghosts = wall.ghosts(inside, grid, numpy, t=0.3, side="left")
    leaving = positive > 0                         # the node -L, which moves both ways, too
    arriving = (negative < 0) & ~leaving
    for k in range(2):
        assert numpy.allclose(ghosts[k][arriving], (base - (k + 0.5) * gradient)[arriving],
                              rtol=1e-13, atol=0)
    face = base                                   # the linear data at x = 0
    value = wall.emit(face, grid, numpy, t=0.3, side="left")
    for k in range(2):
        odd = numpy.maximum(2 * value - inside[k], 0.0)
        assert numpy.allclose(ghosts[k][leaving], odd[leaving], rtol=1e-13, atol=1e-15)
    cells = numpy.concatenate([ghosts[::-1], inside, inside[-1:] + gradient])
    _, plus = MUSCL().faces(cells, numpy)
    assert numpy.allclose(plus[0][arriving], face[arriving], rtol=1e-13, atol=0)
    steep = numpy.stack([base, 5.0 * base])
    assert wall.ghosts(steep, grid, numpy, t=0.3, side="left").min() >= 0.0
    assert numpy.array_equal(wall.ghosts(inside[:1], grid, numpy, t=0.3, side="left"),
                             wall.emit(inside[:1], grid, numpy, t=0.3, side="left"))


def shear_maxwellian(x, v1, v2):
    """The unit Maxwellian at T = 1 moving along v_2 with 0.38 (x - 1/2): near the steady
    Couette flow between walls at -+0.25 with eps = 0.08."""
    return numpy.exp(-(v1 ** 2 + (v2 - 0.38 * (x - 0.5)) ** 2) / 2) / (2 * math.pi)


def test_the_shear_stress_of_the_cell_next_to_a_wall_is_the_wall_flux():
    """An elastic Couette flow with collisions (Maxwell molecules, eps = 0.08: mean free path
    0.1, 8 cells: dx = 1.25 mean free paths; 2D N = 16, MUSCL, walls at +-0.25, from the
    linear shear Maxwellian) at t = 1.2: P_12 of each cell next to a wall is the momentum
    flux through that wall to 3 % (measured 1.0061 and 1.0038); with the even extension
    of the arriving values (f_{-1} = f_0, the limited slope 0) and the leaving ghosts the
    emission of the cell averages it is 0.852 and 0.847 of it."""
    grid = dict(COUETTE_GRID)
    final = 1.2
    limit = (1.0 / 8) / (gf.VelocityGrid(**grid).half_width - gf.VelocityGrid(**grid).spacing)
    dt = final / math.ceil(final / limit)
    description = RunDescription(
        grid=grid, kernel="maxwell", restitution={"name": "constant", "value": 1.0},
        initial={"name": "space_function", "function": shear_maxwellian},
        operator={"name": "fast_spectral"},
        integrator="ssp_rk2", conservative=True, knudsen=0.08, time_step=dt,
        final_time=final, output={"snapshot_interval": final},
        space={"cells": 8, "reconstruction": "muscl",
               "left": {"name": "diffuse", "temperature": 1.0, "velocity": -0.25},
               "right": {"name": "diffuse", "temperature": 1.0, "velocity": 0.25}})
    ds = Simulation(description).run(None, progress=False).dataset
    shear = ds.pressure_tensor.values[-1, :, 0, 1]
    flux = ds.wall_momentum.values[-1, :, 1] / dt          # P_12 in, -P_12 out
    ratios = shear[0] / flux[0], -shear[-1] / flux[1]
    assert all(abs(r - 1) < 0.03 for r in ratios), ratios
