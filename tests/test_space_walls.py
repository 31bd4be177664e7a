"""Walls that know the time and their side; the vibrating wall in the limit of small
amplitude (docs/space.md, "Vibrating walls"); the momentum through the walls and the cell
next to a wall (docs/space.md, "Wall pressure and shear stress").

1. The layer a vibrating wall sweeps: the escape slope, the density of first hits (one
   hit per arriving particle), the catch moment <(S - cos)^2> = 1/2.
2. On the grid: zero mass flux to round-off, on both sides, diffuse and specular; the
   specular wall's energy per arriving node its closed form 2 V^2 to round-off; the
   diffuse wall at a vanishing speed the resting diffuse wall.
3. The heating against the layer's integral (O(h^2), observed order), the layer's integral
   against its series (the odd V^3 term of the diffuse wall, V^4 of the specular), and
   both against a particle simulation of a piston that really oscillates, which also
   tells them from the count of hits (U - v_1)_+ on the arriving gas alone.
4. Constant arrays cached per wall, grid and array namespace: no host/device copies after
   the first call; the conformance kit on time-dependent walls.
5. Bad parameters refused, naming them.
6. A collisionless space run between a vibrating and a specular wall: mass and the
   energy balance to round-off, and the energy of the vibration as the grid wall says.
7. Free-molecular Couette flow: the grid state is steady and its wall momentum (pressure
   and shear stress) the closed form to round-off, a run reaches it, the grid's shear
   stress converges to the continuum's at second order in h; the recorded wall momentum
   is the momentum change of the gas.
8. The ghost cells of an emitting wall extend the data linearly; the shear stress of the
   cell next to a wall is the wall's momentum flux in a Couette flow with collisions.

:func:`heating_rows`, :func:`vibrating_run_energy` and :func:`couette_refinement_rows`
also make the tables of docs/space.md.
"""

import math

import attrs
import numpy
import pytest

import granframe as gf
from granframe import abc as contracts
from granframe import validators as check
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import exact, vibration
from granframe.space.boundaries import Diffuse, Reservoir, Specular, Vibrating
from granframe.space.transport import upwind_speeds
from granframe.testing import conformance as kit
from granframe.testing.piston import oscillating_piston
from granframe.testing.transfers import CountingBackend

#: the wall of the grid checks: V = A omega = 0.4, T_w = 1
WALL = {"speed": 0.4, "temperature": 1.0}
#: the fixed box of the refinement: S = 3.5 (L = 7.72)
SUPPORT = 3.5


def _incoming(grid, temperature=1.0, velocity=0.0):
    return grid.maxwellian(1.0, [velocity] + [0.0] * (grid.dimension - 1), temperature)


# -- the layer -------------------------------------------------------------------------------

def test_the_escape_slope_is_the_tangent_from_the_wall():
    """S(theta) >= max(cos theta, 0); S = cos theta where the tangent stays above the wall
    (theta in [0, pi/2]: the wall decelerates away for good), S(pi) = the slope of the
    tangent from (pi, 0) to the next rise, found independently by brute force on 2e6
    points; <(S - cos)^2> = 1/2 to 1e-12 on 4096 phases."""
    theta = vibration.phases(4096)
    s = vibration.escape_slope(theta)
    assert numpy.all(s >= numpy.maximum(numpy.cos(theta), 0.0) - 1e-15)
    quarter = theta <= 0.5 * math.pi
    assert numpy.allclose(s[quarter], numpy.cos(theta[quarter]), rtol=0, atol=1e-14)
    u = numpy.linspace(1e-6, 3 * math.pi, 2_000_001)
    brute = float(numpy.max(numpy.sin(math.pi + u) / u))
    assert vibration.escape_slope(math.pi) == pytest.approx(brute, rel=1e-9)
    assert numpy.mean((s - numpy.cos(theta)) ** 2) == pytest.approx(exact.CATCH_MOMENT,
                                                                    abs=1e-12)


def test_every_arriving_particle_hits_the_wall_once_first():
    """(1/2 pi) int p_a = 1 for every arriving speed a: exactly (to round-off) for a >= 1,
    where nothing is hidden, and to the midpoint rule's error at the visibility edges for
    slower particles (measured 8e-4 at a = 0.05 on 4096 phases)."""
    theta = vibration.phases(4096)
    for a in (1.0, 1.5, 4.0):
        assert vibration.first_hit_density(a, theta).mean() == pytest.approx(1.0, abs=1e-14)
    for a in (0.05, 0.3, 0.7):
        assert vibration.first_hit_density(a, theta).mean() == pytest.approx(1.0, abs=2e-3)


# -- on the grid -----------------------------------------------------------------------------

MASS_GRIDS = ((2, 32, 5.0), (3, 16, 5.0))
REFLECTIONS = ("diffuse", "specular")


@pytest.mark.parametrize("reflection", REFLECTIONS)
@pytest.mark.parametrize("d,n,support", MASS_GRIDS)
def test_zero_mass_flux_on_both_sides(d, n, support, reflection):
    """sum_v F dv = 0 to 1e-14 of the arriving flux on both sides, for random and drifting
    incoming values; a specular wall also at every tangential node."""
    grid = gf.VelocityGrid(d, n, support)
    wall = Vibrating(**WALL, reflection=reflection)
    wall.check(grid)
    positive, negative = upwind_speeds(grid)
    rng = numpy.random.default_rng(1)
    for incoming in (rng.uniform(0.1, 1.0, grid.shape), _incoming(grid, 0.7, -0.3)):
        arriving = float(numpy.sum(-negative * incoming))
        for side in ("left", "right"):
            out = wall.emit(incoming, grid, numpy, t=0.3, side=side)
            net = positive * out + negative * incoming
            assert abs(float(net.sum())) <= 1e-14 * arriving, (side, net.sum() / arriving)
            if reflection == "specular":
                assert numpy.abs(net.sum(axis=0)).max() <= 1e-14 * arriving


def _node_energies(wall, grid):
    """For each arriving node j (c^- < 0) alone: the normal energy that leaves per arriving
    particle minus what arrived, sum_i c^+_i f_out,i v_i^2/2 / (|c^-_j| f_j) - v_j^2/2, and
    the node's speed |v_1j| (the node -L arrives at L)."""
    positive, negative = (c.ravel() for c in upwind_speeds(grid))
    speed = numpy.abs(grid.points())
    rows = []
    for j in numpy.nonzero(negative < 0)[0]:
        f = numpy.zeros(grid.shape)
        f[j] = 1.0
        out = wall.emit(f, grid, numpy).sum(axis=tuple(range(1, grid.dimension)))
        leaving = numpy.where(positive > 0, out, 0.0)
        gained = (positive * leaving * 0.5 * speed ** 2).sum() / (-negative[j] * grid.n_modes
                                                                   ** (grid.dimension - 1))
        rows.append((speed[j], gained - 0.5 * speed[j] ** 2))
    return numpy.array(rows)


@pytest.mark.parametrize("d,n", [(2, 32), (3, 16)])
def test_the_specular_wall_gives_every_fast_node_its_closed_form(d, n):
    """Each arriving node with a >= 3V leaves with 2 V^2 more normal energy per particle,
    to round-off (the phase rule is exact on cos^k, and the shares between leaving nodes
    keep the energy flux); slower nodes (shadowed, caught again) gain more; the tangential
    velocity is kept."""
    grid = gf.VelocityGrid(d, n, 5.0)
    wall = Vibrating(speed=0.5, reflection="specular")
    rows = _node_energies(wall, grid)
    fast = (rows[:, 0] >= 1.5) & (rows[:, 0] < grid.half_width - 1.0)
    assert fast.sum() >= 5
    assert numpy.allclose(rows[fast, 1], 2 * 0.5 ** 2, rtol=1e-13, atol=0), rows[fast]
    # every node but -L (whose faster escapes have no node above) leaves with the energy
    # of its escapes, the slow ones too (what leaves below the slowest node h is put on h
    # and the energy it gains there taken back in its column)
    below = rows[:, 0] < grid.half_width - 1e-9
    exits, weight = vibration.Layer(0.5, 1.0).specular_escape(rows[below, 0])
    layer = (0.5 * exits ** 2 * weight).sum(axis=0) / weight.sum(axis=0) \
        - 0.5 * rows[below, 0] ** 2
    assert numpy.allclose(rows[below, 1], layer, rtol=1e-12, atol=1e-14)
    assert rows[below, 1].max() > 2 * 0.5 ** 2      # the slow nodes are caught, and gain more
    f = numpy.random.default_rng(4).uniform(0.1, 1.0, grid.shape)
    out = wall.emit(f, grid, numpy)
    positive, negative = upwind_speeds(grid)
    tangential = tuple(range(1, d))
    assert numpy.allclose((positive * out).sum(axis=0), (-negative * f).sum(axis=0),
                          rtol=1e-13), tangential


def test_the_diffuse_wall_at_a_vanishing_speed_is_the_resting_diffuse_wall():
    """V = 1e-3: the emission differs from the resting diffuse wall's by O(V) (measured
    4e-4 of its largest value)."""
    grid = gf.VelocityGrid(2, 32, SUPPORT)
    f = _incoming(grid, 0.6, -0.2)
    moving = Vibrating(speed=1e-3).emit(f, grid, numpy)
    resting = Diffuse().emit(f, grid, numpy)
    assert numpy.abs(moving - resting).max() < 2e-3 * numpy.abs(resting).max()


def grid_heating(wall, grid, incoming) -> float:
    """The energy the grid wall adds per arriving particle to what the resting wall of the
    same reflection sends back: sum_v (F_wall - F_rest) |v|^2/2 dv / sum_v |c^-| f dv."""
    positive, negative = upwind_speeds(grid)
    resting = Diffuse(temperature=wall.temperature) if wall.reflection == "diffuse" \
        else Specular()
    energy = 0.5 * grid.speed_squared()
    out = wall.emit(incoming, grid, numpy) - resting.emit(incoming, grid, numpy)
    return float((positive * out * energy).sum() / (-negative * incoming).sum())


def heating_rows(sizes=(16, 32, 64), reflection="diffuse", gas_temperature=1.0):
    """For each N on the box S = SUPPORT (2D, gas at rest at T, the wall :data:`WALL`): h,
    the grid heating per arriving particle, and its relative distance from the layer's
    integral (:func:`exact.vibrating_wall_heating`)."""
    layer = exact.vibrating_wall_heating(WALL["speed"], WALL["temperature"], gas_temperature,
                                         reflection)
    wall = Vibrating(**WALL, reflection=reflection)
    rows = []
    for n in sizes:
        grid = gf.VelocityGrid(2, n, SUPPORT)
        heating = grid_heating(wall, grid, _incoming(grid, gas_temperature))
        rows.append({"N": n, "h": grid.spacing, "heating": heating,
                     "error": heating / layer - 1.0})
    return rows, layer


@pytest.mark.parametrize("reflection", REFLECTIONS)
def test_the_grid_heating_converges_to_the_layer_at_second_order(reflection):
    """Gas at rest at T = T_w = 1, V = 0.4, the box S = 3.5: relative errors (measured) at
    N = 64, 128, 256, diffuse -9.3e-3, -8.6e-4, -2.2e-4 (orders 3.44, 1.99), specular
    4.0e-3, 1.3e-3, 3.5e-4 (1.60, 1.93): second order once h < V (docs/space.md)."""
    rows, _ = heating_rows((64, 128, 256), reflection=reflection)
    errors = [abs(row["error"]) for row in rows]
    orders = [math.log2(a / b) for a, b in zip(errors[:-1], errors[1:])]
    assert errors[-1] < 5e-4, rows
    assert all(p > 1.5 for p in orders), (errors, orders)
    assert 1.8 < orders[-1] < 2.3, (errors, orders)


def test_the_layer_against_its_series():
    """(Delta e - series) / V^3 -> a constant (about -0.23 / sqrt(T)) for the diffuse wall:
    an odd term in V; the specular remainder falls like V^4."""
    diffuse, specular = [], []
    for V in (0.05, 0.1, 0.2):
        for reflection, out in (("diffuse", diffuse), ("specular", specular)):
            value = exact.vibrating_wall_heating(V, 1.0, 1.0, reflection)
            out.append((value - exact.vibrating_wall_heating_series(V, 1.0, 1.0, reflection))
                       / V ** 3)
    assert all(-0.27 < c < -0.2 for c in diffuse), diffuse
    assert diffuse[0] - diffuse[-1] < 0.03
    assert specular[1] / specular[0] == pytest.approx(2.0, rel=0.1), specular
    assert specular[2] / specular[1] == pytest.approx(2.0, rel=0.1), specular


@pytest.mark.parametrize("reflection,gas,speed,count", [("diffuse", 2.0, 0.3, 400_000),
                                                        ("specular", 1.0, 0.4, 400_000)])
def test_a_piston_that_really_oscillates_heats_as_the_layer_says(reflection, gas, speed, count):
    """A = 1e-3, omega = V / A (the particle simulation of granframe.testing.piston): its
    heating per arriving particle within 3 standard errors of the layer's integral; for
    the diffuse wall with T = 2 T_w the count of hits (U - v_1)_+ on the arriving gas
    alone, V^2 (pi/4 sqrt(T_w/T) + 1/4 + (d+1) T_w / (8T) - (d-1)/8) = 0.868 V^2, is
    more than 10 errors away (the wall catches what it sent back, not the gas)."""
    result = oscillating_piston(count, 1e-3, speed / 1e-3, reflection=reflection,
                                gas_temperature=gas, seed=7)
    layer = exact.vibrating_wall_heating(speed, 1.0, gas, reflection, speeds=1000)
    error = result["heating_error"]
    assert abs(result["heating"] - layer) < 3 * error, (result["heating"], layer, error)
    if reflection == "diffuse":
        count_only = speed ** 2 * (0.25 * math.pi * math.sqrt(1 / gas) + 0.25
                                   + 3 / (8 * gas) - 1 / 8)
        assert abs(result["heating"] - count_only) > 10 * error


# -- device, conformance ---------------------------------------------------------------------

@pytest.mark.parametrize("wall", [Specular(), Diffuse(temperature=1.5, velocity=0.3,
                                                      accommodation=0.5),
                                  Vibrating(**WALL), Vibrating(**WALL, reflection="specular"),
                                  Reservoir(density=1.2, velocity=-0.5, temperature=1.1)],
                         ids=["specular", "diffuse", "vibrating", "vibrating-specular",
                              "reservoir"])
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


@attrs.frozen
class Pulsing(contracts.Boundary):
    """A wall that depends on t: fully diffuse at the temperature T_0 (1 + sin(omega t) / 2)
    (a test double of a time-periodic wall), refusing a period shorter than 8 steps."""

    frequency: float = 5.0

    @property
    def period(self):
        return 2 * math.pi / self.frequency

    def check_time_step(self, time_step):
        if self.period < 8 * time_step:
            check.reject("Pulsing", "frequency", self.frequency, "must give a period of at "
                         "least 8 time steps")

    def _wall(self, t):
        return Diffuse(temperature=1.0 + 0.5 * math.sin(self.frequency * t))

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        return self._wall(t).ghosts(inside, grid, xp, t=t, side=side)

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        return self._wall(t).emit(incoming, grid, xp, t=t, side=side)


class WrongPeriod(Pulsing):
    """Declares half its period."""

    @property
    def period(self):
        return math.pi / self.frequency


class LeakyOnTheRight(Pulsing):
    """Loses 1 % of what arrives, on the right only."""

    def emit(self, incoming, grid, xp, *, t=0.0, side="left"):
        out = super().emit(incoming, grid, xp, t=t, side=side)
        return 0.99 * out if side == "right" else out


@pytest.mark.parametrize("reflection", REFLECTIONS)
def test_the_vibrating_wall_passes_the_conformance_kit(reflection):
    kit.check_boundary(Vibrating(**WALL, reflection=reflection))


def test_the_kit_checks_walls_over_their_period_and_on_both_sides():
    kit.check_boundary(Pulsing())
    with pytest.raises(AssertionError, match=r"WrongPeriod: the emission at t \+ period "
                                             r"\(period = 0\.628319\) differs"):
        kit.check_wall_period(WrongPeriod())
    with pytest.raises(AssertionError, match=r"LeakyOnTheRight: net mass flux through the wall "
                                             r".* at t = 0 on the right, 0\.01 of the arriving"):
        kit.check_wall_mass_flux(LeakyOnTheRight())
    eighths = [k * 2 * math.pi / 40 for k in range(8)]
    assert kit._wall_times(Pulsing()) == pytest.approx(eighths)
    assert kit._wall_times(Vibrating(**WALL)) == kit.WALL_TIMES


def test_a_description_refuses_a_time_step_its_walls_cannot_follow(monkeypatch):
    """The space description asks each wall's check_time_step: a period of 2 pi / 400
    against dt = 0.01 (1.6 steps) is refused by name."""
    from granframe.run import space_description

    build = space_description.Space.build

    def with_pulsing(self, field):
        return Pulsing(frequency=400.0) if field == "left" else build(self, field)

    monkeypatch.setattr(space_description.Space, "build", with_pulsing)
    space = {"cells": 8, "left": "diffuse", "right": "specular", "collisions": False}
    with pytest.raises(ValueError, match=r"Pulsing: parameter 'frequency' = 400"):
        Simulation(RunDescription.from_dict(_description(space, 0.02, 0.01)))


# -- bad input -----------------------------------------------------------------------------

@pytest.mark.parametrize("params,name,error", [
    ({"speed": -0.1}, "speed", ValueError),
    ({"speed": 0.0}, "speed", ValueError),
    ({"speed": math.inf}, "speed", ValueError),
    ({"speed": "fast"}, "speed", TypeError),
    ({"speed": True}, "speed", TypeError),
    ({"speed": 0.1, "temperature": 0.0}, "temperature", ValueError),
    ({"speed": 0.1, "reflection": "elastic"}, "reflection", ValueError),
])
def test_bad_parameters_are_refused_naming_them(params, name, error):
    with pytest.raises(error, match=rf"^Vibrating: parameter '{name}' = .* is invalid; "):
        Vibrating(**params)


@pytest.mark.parametrize("params,support,name,what", [
    ({"speed": 7.0}, 3.5, "speed", r"must be below L - h = 6\.759"),
    ({"speed": 1e200}, 3.5, "speed", "must be below L - h"),
    ({"speed": 0.1, "temperature": 0.2}, 3.5, "temperature", r"must be >= h\^2 / 4 = 0\.2331"),
    ({"speed": 0.1, "temperature": 3.0}, 3.5, "temperature", "does not fit the velocity box"),
    ({"speed": 2.0}, 3.5, "temperature", "lower the speed"),
])
def test_walls_that_do_not_fit_the_grid_are_refused(params, support, name, what):
    grid = gf.VelocityGrid(2, 16, support)
    with pytest.raises(ValueError, match=rf"^Vibrating: parameter '{name}' = .* is invalid; "
                                         rf".*{what}"):
        Vibrating(**params).check(grid)


def test_bad_closed_form_arguments_are_refused():
    for function in (exact.vibrating_wall_heating, exact.vibrating_wall_heating_series):
        owner = function.__name__
        for args, name in (((0.0, 1.0, 1.0, "diffuse"), "speed"),
                           ((0.1, -1.0, 1.0, "diffuse"), "wall_temperature"),
                           ((0.1, 1.0, math.nan, "diffuse"), "gas_temperature"),
                           ((0.1, 1.0, 1.0, "sticky"), "reflection")):
            with pytest.raises(ValueError, match=rf"^{owner}: parameter '{name}'"):
                function(*args)


def test_a_description_with_a_wall_that_does_not_fit_is_refused():
    space = {"cells": 8, "left": {"name": "vibrating", "speed": 7.0},
             "right": "specular", "collisions": False}
    with pytest.raises(ValueError, match=r"Vibrating: parameter 'speed' = 7(\.0)? is invalid"):
        Simulation(RunDescription.from_dict(_description(space, 0.01, 0.01)))


# -- a space run ---------------------------------------------------------------------------

RUN_GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.5}
RUN_WALL = {"name": "vibrating", "temperature": 1.0, "speed": 0.5}
RESTING = {"name": "diffuse", "temperature": 1.0}


def _description(space, final_time, time_step):
    return {"final_time": final_time, "time_step": time_step, "grid": RUN_GRID,
            "kernel": {"name": "maxwell"}, "restitution": {"name": "constant", "value": 1.0},
            "initial": {"name": "maxwellian", "temperature": 1.0},
            "output": {"snapshot_interval": final_time}, "space": space}


def vibrating_run_energy(side: str, cells: int = 8, steps: int = 4):
    """Collisionless runs of ``steps`` steps at the MUSCL CFL limit from the Maxwellian at
    the wall's temperature, the vibrating wall on ``side`` and a specular one on the
    other, and the same with a resting diffuse wall: the datasets, and the grid wall's
    extra energy per unit time for the initial face values (:func:`grid_heating` times
    the arriving flux), times the run's duration."""
    grid = gf.VelocityGrid(**RUN_GRID)
    dt = 2 * 0.5 * (1.0 / cells) / (grid.half_width - grid.spacing)

    def run(wall):
        ends = {"left": wall, "right": "specular"} if side == "left" else \
            {"left": "specular", "right": wall}
        space = {"cells": cells, "reconstruction": "muscl", "collisions": False, **ends}
        return Simulation(RunDescription.from_dict(_description(space, steps * dt, dt))).run(
            None, progress=False).dataset

    vibrating, resting = run(RUN_WALL), run(RESTING)
    face = vibrating.f.values[0, 0]                      # even in v_1: the same on both sides
    wall = Vibrating(speed=RUN_WALL["speed"], temperature=RUN_WALL["temperature"])
    negative = upwind_speeds(grid)[1]
    arriving = float((-negative * face).sum() * grid.cell_volume)
    return vibrating, resting, grid_heating(wall, grid, face) * arriving * steps * dt


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_run_with_a_vibrating_wall_keeps_its_mass_and_gets_the_energy_of_the_vibration(side):
    """Mass to round-off, the energy balance of the walls to round-off; the energy of the
    vibration (vibrating run minus resting run, through the wall) is the grid wall's for
    the initial face values to 2 % (measured +0.35 % on both sides: the face values change
    a little over the four steps)."""
    vibrating, resting, closed = vibrating_run_energy(side)
    wall = 0 if side == "left" else 1
    mass = vibrating.mass.values
    assert numpy.abs(mass / mass[0] - 1).max() < 1e-13
    assert numpy.abs(vibrating.wall_mass.values).max() < 1e-15 * mass[0]
    energy = vibrating.kinetic_energy.values
    assert abs(energy[-1] - energy[0] - vibrating.wall_energy.values.sum()) < 1e-14 * energy[0]
    extra = (vibrating.wall_energy.values[1:, wall] - resting.wall_energy.values[1:, wall])
    assert closed > 0
    assert extra.sum() == pytest.approx(closed, rel=0.02), (extra.sum(), closed)


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


# -- open ends: the reservoir --------------------------------------------------------------

def _half_range_flux(density, velocity, temperature):
    """The exact flux n [sqrt(T/2pi) exp(-u^2/2T) + (u/2)(1 + erf(u/sqrt(2T)))] of the
    particles with v_1 > 0 of a Maxwellian drifting at u along v_1."""
    s = velocity / math.sqrt(2.0 * temperature)
    return density * (math.sqrt(temperature / (2.0 * math.pi)) * math.exp(-s * s)
                      + 0.5 * velocity * (1.0 + math.erf(s)))


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("velocity", [-0.8, 0.0, 1.3])
def test_a_reservoir_sends_in_the_half_range_flux_of_its_maxwellian(d, velocity):
    """What a reservoir (n, u, T) sends into the interval, sum_v c^+ M dv, is the exact
    half-range flux F of its Maxwellian at the left end for u and at the right end for -u
    (the lab velocity seen from the end), whatever arrives, to the order the nodes allow:
    the sum over v_1 = k h > 0 of g(v_1) = v_1 M_1(v_1) is a trapezoid rule over a kink
    at v_1 = 0 (g(0) = 0), so by Euler-Maclaurin
    sum = F - h^2 g'(0) / 12 + h^4 g'''(0) / 720 + O(h^6), g'(0) = M_1(0),
    g'''(0) = 3 M_1(0) (u^2/T^2 - 1/T), M_1(0) = n exp(-u^2/2T) / sqrt(2 pi T): the
    grid's flux is that to 5e-4 of F (the tangential sums are exact to spectral accuracy)."""
    from granframe.space.boundaries import Reservoir
    from granframe.velocity.grid import VelocityGrid

    grid = VelocityGrid(d, 64 if d == 2 else 32, 5.0)
    wall = Reservoir(density=1.7, velocity=velocity, temperature=1.5)
    wall.check(grid)
    positive = upwind_speeds(grid)[0]
    rng = numpy.random.default_rng(3)
    for side, seen in (("left", velocity), ("right", -velocity)):
        for incoming in (_incoming(grid), rng.uniform(0.0, 1.0, grid.shape)):
            sent = wall.emit(incoming, grid, numpy, side=side)
            flux = float((positive * sent).sum() * grid.cell_volume)
            h, m0 = grid.spacing, 1.7 * math.exp(-seen ** 2 / 3.0) / math.sqrt(3.0 * math.pi)
            kink = h ** 2 * m0 / 12.0 - h ** 4 * 3.0 * m0 * (seen ** 2 / 2.25 - 1.0 / 1.5) / 720.0
            exact_flux = _half_range_flux(1.7, seen, 1.5)
            assert abs(flux - exact_flux) == pytest.approx(kink, rel=0.1)
            assert flux == pytest.approx(exact_flux - kink, rel=5e-4)


def _reservoir_run(left, right, cells=8, steps=6, collisions=False, velocity=0.6):
    d = RunDescription.from_dict({
        "final_time": steps * 0.01, "time_step": 0.01,
        "grid": {"dimension": 2, "n_modes": 24, "support_radius": 4.0},
        "kernel": {"name": "maxwell"}, "restitution": {"name": "constant", "value": 1.0},
        "initial": {"name": "maxwellian", "velocity": [velocity, 0.0], "temperature": 1.0},
        "output": {"snapshot_interval": steps * 0.01}, "conservative": collisions,
        "space": {"cells": cells, "reconstruction": "muscl", "collisions": collisions,
                  "left": left, "right": right}})
    return d


def _run(description, tmp_path):
    store = tmp_path / "r.zarr"
    Simulation(description).run(store, progress=False)
    return gf.open_run(store, time_axis="steps")


@pytest.mark.parametrize("collisions", [False, True])
def test_a_gas_at_the_reservoirs_state_flows_through_unchanged(collisions, tmp_path):
    """A uniform gas at u = 0.6 between two reservoirs of its own state: the transport
    leaves it exactly as it is (the reservoir's Maxwellian is the grid's, without Nyquist
    modes as the initial one): without collisions f stays the initial f to round-off, and
    as much enters through one end as leaves through the other. With collisions the
    operator's Q(M) of this coarse grid (1e-6 of the peak over the run, the same in every
    cell of a periodic run) changes the gas inside but not the reservoirs' gas, so the run
    differs from the periodic one by less than that change."""
    state = {"name": "reservoir", "density": 1.0, "velocity": 0.6, "temperature": 1.0}
    ds = _run(_reservoir_run(state, state, collisions=collisions), tmp_path)
    periodic = _run(_reservoir_run("periodic", "periodic", collisions=collisions),
                    tmp_path / "periodic")
    f, g = ds.f.values, periodic.f.values
    drift = numpy.abs(g[-1] - g[0]).max() if collisions else 1e-13 * numpy.abs(f[0]).max()
    assert numpy.abs(f[-1] - g[-1]).max() < drift
    wall_mass = ds.wall_mass.values[1:]
    assert wall_mass[:, 0].min() > 0 and wall_mass[:, 1].max() < 0
    assert numpy.abs(wall_mass.sum(axis=1)).max() < (1e-14 if not collisions else
                                                     100 * drift * ds.dt.values[-1])


def test_mass_through_a_reservoir_is_what_the_store_records(tmp_path):
    """Gas at u = 0.6 flowing from a reservoir at rest into a specular wall: the mass of the
    interval changes by exactly what entered through the ends (to round-off), and the
    reservoir takes in gas (it is at lower pressure) while the wall sends nothing."""
    reservoir = {"name": "reservoir", "density": 0.5, "velocity": 0.0, "temperature": 1.0}
    ds = _run(_reservoir_run("specular", reservoir, collisions=True), tmp_path)
    mass = ds.mass.values
    entered = ds.wall_mass.values[1:].sum(axis=0)
    assert abs(mass[-1] - mass[0] - entered.sum()) < 1e-13 * mass[0]
    assert abs(entered[0]) < 1e-15 * mass[0] and entered[1] < 0


@pytest.mark.parametrize("params,name", [
    ({"velocity": 9.0}, "velocity"), ({"temperature": 1e-4}, "temperature"),
    ({"temperature": 9.0}, "temperature")])
def test_a_reservoir_that_does_not_fit_the_grid_is_refused_naming_it(params, name):
    from granframe.space.boundaries import Reservoir
    from granframe.velocity.grid import VelocityGrid

    with pytest.raises(ValueError, match=f"Reservoir.*'{name}'"):
        Reservoir(**params).check(VelocityGrid(2, 24, 3.5))


@pytest.mark.parametrize("params", [{"density": 0.0}, {"density": -1.0},
                                    {"temperature": float("nan")}, {"velocity": "fast"}])
def test_bad_reservoir_parameters_are_refused(params):
    from granframe.space.boundaries import Reservoir

    with pytest.raises((ValueError, TypeError), match=next(iter(params))):
        Reservoir(**params)
