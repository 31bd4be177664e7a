"""The measurements and choices behind ``granframe advise``'s rules 1 and 3-8
(:mod:`granframe.tools.advise`): the probe of a scene (its objects, the temperature closure,
the temperature range of a space scene), and the support, the modes, the quadratures, the
time step and the health limits chosen against the tolerance.
"""

from __future__ import annotations

import functools
import math

import attrs
import numpy
import scipy.integrate
import scipy.special

from granframe import validators as check
from granframe.run.description import Health
from granframe.equations.homogeneous import collision_frequency
from granframe.velocity.estimators import (TAIL_ERROR_FACTOR, mass_beyond, pair_share_beyond,
                                          spectral_tail)
from granframe.velocity.grid import VelocityGrid
from granframe.model.initial import check_fits, face_share
from granframe.velocity.moments import FieldMoments
from granframe.theory.euler import euler_riemann_star
from granframe.space.initial import RiemannProblem, SpaceCondition
from granframe.velocity.quadratures import LEBEDEV_ORDERS, CircleTrapezoid, Lebedev
from granframe.registry import default_registries
from granframe.stepping.stability import step_limit

#: the modes per axis advise chooses from: sizes with factors 2, 3 and 5 only (in 2D, N = 28
#: took 3.5 ms per evaluation where N = 32 with 1.5x the quadrature points took 1.2 ms)
MODES = (8, 12, 16, 20, 24, 32, 40, 48, 64, 80, 96, 128)
RADIAL = (8, 12, 16, 24, 32, 48, 64)
CIRCLE = (8, 12, 16, 24, 32, 48, 64)
SPHERE = tuple(o for o in (3, 5, 7, 11, 17, 23, 29) if o in LEBEDEV_ORDERS)
#: share of the tolerance given to the resolution; the quadratures and the time step share
#: what it leaves
SHARE = 1.0 / 3.0
#: largest max-norm error of a quadrature on anisotropic data, relative to max |Q|: above it
#: the rule is not a consistent approximation (Lebedev 5 and 7: 0.4-0.9, unstable in a run;
#: Lebedev 11: 0.01-0.04; docs/advise.md)
CONSISTENCY = 0.1
#: |int Q| / (rho nu) of the fast operator, its mass round-off floor per evaluation, in machine
#: epsilons of its precision: measured 5.2e-7 in float32 (4.4 eps) and 1e-15 in float64
#: (4.5 eps), docs/accuracy-vs-cost.md, "float32"; tests/test_operators.py bounds float32 by
#: 5e-6 rho nu (42 eps), the bound taken here
MASS_FLOOR_EPSILONS = 42


def _probe_operator(grid, kernel, law, backend, radial, sphere, precision="float64"):
    return default_registries().create(
        "collision_operators", "fast_spectral", grid=grid, kernel=kernel, restitution=law,
        backend=backend, radial_points=radial, sphere=sphere, precision=precision)


def _sphere(dimension: int, size: int):
    return CircleTrapezoid(size) if dimension == 2 else Lebedev(size)


def _sphere_points(dimension: int, size: int) -> int:
    return size if dimension == 2 else Lebedev(size).n_points


class Probe:
    """The scene's objects and the measurements advise makes on them."""

    def __init__(self, scene, backend):
        self.scene, self.backend = scene, backend
        self.d = scene.dimension
        self.kernel, self.law, self.initial = (scene.build(f) for f in
                                               ("kernel", "restitution", "initial"))
        self.degree = self.kernel.speed_exponent + 2.0 * self.kernel.energy_exponent
        #: the ends of a space scene's interval, which must accept the grid
        self.walls = ([] if scene.space is None else
                      [scene.space.build(side) for side in ("left", "right")])
        self._sample_initial()

    def _sample_initial(self):
        """f0 on a fine grid large enough for it: its mass, mean velocity and temperature."""
        support = 4.0
        for _ in range(12):
            grid = VelocityGrid(self.d, 96 if self.d == 2 else 48, support)
            f = self.initial.sample(grid)
            if face_share(f) <= 1e-12:
                break
            support *= 1.5
        else:
            check.reject("advise", "initial", self.scene.initial, "does not decay within |v| < "
                         f"{support:g}")
        self.fine_grid, self.f0 = grid, f
        self.mass = grid.mass(f)
        self.velocity = grid.bulk_velocity(f)
        self.t0 = grid.temperature(f)

    @functools.lru_cache(maxsize=64)
    def cooling_rate(self, temperature: float) -> float:
        """zeta(T) = -int Q(M_T) |v|^2 / (d rho T) of the discrete operator (rate of ln T, eps = 1)."""
        speeds = numpy.linspace(0.0, 10.0 * math.sqrt(temperature), 65)
        if numpy.all(self.law(speeds) == 1.0):
            return 0.0
        grid = VelocityGrid(self.d, 32 if self.d == 2 else 24, 5.0 * math.sqrt(temperature))
        operator = _probe_operator(grid, self.kernel, self.law, self.backend, 32,
                                   _sphere(self.d, 32 if self.d == 2 else 17))
        m = grid.maxwellian(self.mass, None, temperature)
        q = self.backend.to_numpy(operator(self.backend.asarray(m)))
        return -float(numpy.sum(q * grid.speed_squared())) * grid.cell_volume / (
            self.d * self.mass * temperature)

    def temperature_history(self):
        """(T_min, T_max, T_end, zeta at T0) of dT/dt = -zeta(T) T / eps + 2 tau."""
        scene, t0 = self.scene, self.t0
        zeta0 = self.cooling_rate(t0)
        if self.law.is_constant:
            def zeta(temperature):
                return zeta0 * (temperature / t0) ** (self.degree / 2)
        else:
            table_t = t0 * numpy.logspace(-4, 2, 13)
            table = numpy.log([max(self.cooling_rate(float(x)), 1e-300) for x in table_t])

            def zeta(temperature):
                return math.exp(numpy.interp(math.log(temperature), numpy.log(table_t), table))

        def rate(t, log_t):
            temperature = math.exp(log_t[0])
            return [-zeta(temperature) / scene.knudsen + 2.0 * scene.heat_bath / temperature]

        solution = scipy.integrate.solve_ivp(rate, (0.0, scene.final_time), [math.log(t0)],
                                             rtol=1e-8, atol=1e-10, dense_output=True)
        values = numpy.exp(solution.sol(numpy.linspace(0.0, scene.final_time, 401))[0])
        return float(values.min()), float(values.max()), float(values[-1]), zeta0, zeta

    def space_range(self, coldest: float, hottest: float) -> tuple[float, float, str]:
        """The temperature range (T_min, T_max) of a space scene and a line saying why.

        The closure's range of the interval's mean f0 scaled by the spread about the mean's
        T0 of the cells' temperatures at t = 0 (:meth:`cells`) and of the star states of a
        Riemann problem (:attr:`star_states`), and widened to the temperature of every wall
        that has one (the gas next to a diffuse wall tends to it):
        T_min = min(T_min, T_min min_i T_i / T0, T_w),
        T_max = max(T_max, T_max max_i T_i / T0, T_w).
        """
        if isinstance(self.initial, SpaceCondition):
            f, _ = self.cells(self.fine_grid)
            temperatures = FieldMoments(self.fine_grid, 1.0)(f)["temperature"]
            stars = [temperature for _, _, temperature in self.star_states]
            low = min([float(temperatures.min())] + stars)
            high = max([float(temperatures.max())] + stars)
        else:
            low = high = self.t0
        walls = [float(wall.temperature) for wall in self.walls
                 if getattr(wall, "temperature", None) is not None]
        coldest = min([coldest, coldest * low / self.t0] + walls)
        hottest = max([hottest, hottest * high / self.t0] + walls)
        behind = " and behind the Euler waves" if self.star_states else ""
        return coldest, hottest, (
            f"space: cells at t = 0{behind} from T = {low:.4g} to {high:.4g}"
            + (f", walls at T = {', '.join(f'{t:g}' for t in walls)}" if walls else "")
            + f": range {coldest:.3g} ... {hottest:.3g}")

    @functools.cached_property
    def star_states(self) -> list:
        """[(rho, u, T)] of the star states of a ``riemann`` initial condition, left and
        right of the contact: the states the gas reaches behind the waves of the Euler
        Riemann problem (the limit eps -> 0, gamma = (d + 2)/d;
        :func:`granframe.theory.euler.euler_riemann_star`), u with the tangential components
        of its side. Hotter or colder than f0 behind a shock or a rarefaction, and moving:
        the grid must hold them too. Empty for other initial conditions, and for states
        that open a vacuum."""
        if not isinstance(self.initial, RiemannProblem):
            return []
        sides = [self.initial.left, self.initial.right]
        velocities = [list(side["velocity"]) + [0.0] * (self.d - len(side["velocity"]))
                      for side in sides]
        try:
            star = euler_riemann_star(*[(side["density"], u[0],
                                         side["density"] * side["temperature"])
                                        for side, u in zip(sides, velocities)],
                                      (self.d + 2.0) / self.d)
        except ValueError:
            return []
        return [(star[f"rho_{name}"], (star["u"], *u[1:]), star["p"] / star[f"rho_{name}"])
                for name, u in zip(("left", "right"), velocities)]

    def cells(self, grid):
        """(f0, intended masses) of a space scene's cells on ``grid``, for an initial
        condition that depends on x (:meth:`~granframe.space.initial.SpaceCondition.sample_cells`):
        the scene's cells, or as many equal ones as keep the sample within 2^22 values (cell
        averages, so the extremes of a wave shorter than such a cell are averaged)."""
        space = self.scene.space
        count = min(space.cells, max(1, 2 ** 22 // grid.n_modes ** grid.dimension))
        return self.initial.sample_cells(grid, numpy.linspace(0.0, space.length, count + 1))

    def walls_accept(self, grid) -> bool:
        """Whether both ends of a space scene accept ``grid`` (their own check: a wall
        Maxwellian that fits the box and is resolved); always for a homogeneous scene."""
        try:
            for wall in self.walls:
                wall.check(grid)
        except ValueError:
            return False
        return True

    def collision_frequency(self, temperature: float) -> float:
        """The loss frequency of the Maxwellian of f0's mass at ``temperature``."""
        energy = self.mass * self.d * temperature / 2
        return collision_frequency(self.kernel, self.d, self.mass, temperature, energy)


def choose_support(probe, hottest: float, budget: float, amplification: float,
                   states) -> tuple[float, float]:
    """Smallest S (a multiple of sqrt(T)/4) such that

    - truncating relative speeds at R = 2S removes a share of the rate that matters (the
      energy dissipation, weight |g|^(lambda+2), for the temperature; the loss frequency,
      |g|^lambda, for f) of at most ``budget`` / ``amplification``;
    - at most ``budget`` of |f| lies beyond 2.4 S, where the box L = 2.207 S starts to alias
      (docs/stability.md);

    for the hottest Maxwellian (closed form) and for ``states``: (grid, f) pairs, f0 and the
    cooling state of a rescaled run; and such that the walls of a space scene accept the box
    (:meth:`Probe.walls_accept` on the finest grid of :data:`MODES`: the wall Maxwellians
    fit inside it). Returns (S, predicted error: the largest share times ``amplification``).
    """
    power = probe.kernel.speed_exponent + (2.0 if probe.scene.quantity == "temperature" else 0.0)
    allowed = budget / max(amplification, 1e-300)
    scale = math.sqrt(max(hottest, probe.t0))
    for multiple in numpy.arange(2.0, 12.01, 0.25):
        support = float(round(multiple * scale, 3))
        shares = [scipy.special.gammaincc((probe.d + power) / 2, support ** 2 / hottest)]
        shares += [pair_share_beyond(grid, f, 2 * support, power) for grid, f in states]
        if (max(shares) <= allowed
                and all(mass_beyond(grid, f, 2.4 * support) <= budget for grid, f in states)
                and probe.walls_accept(VelocityGrid(probe.d, MODES[-1], support))):
            break
    return support, max(shares) * amplification


def cooling_state(probe, final_s: float):
    """(grid, g) of a rescaled probe run to min(s_final, 10 collision times): the cooling
    state's profile, whose tails are fatter than a Maxwellian's."""
    from granframe.equations.rescaled import RescaledBoltzmann

    temperature = probe.t0
    grid = VelocityGrid(probe.d, 48 if probe.d == 2 else 32, 4.0 * math.sqrt(temperature))
    operator = _probe_operator(grid, probe.kernel, probe.law, probe.backend, 16,
                               _sphere(probe.d, 16 if probe.d == 2 else 11))
    g = probe.backend.asarray(grid.maxwellian(probe.mass, probe.velocity, temperature))
    equation = RescaledBoltzmann(operator, g, probe.scene.knudsen)
    rk4 = default_registries().create("time_integrators", "rk4")
    nu = probe.collision_frequency(temperature) / probe.scene.knudsen
    span = min(final_s, 10.0 / nu)
    limit = step_limit(rk4, equation, g)
    steps = max(1, math.ceil(span / (0.9 * limit.limit)))
    for i in range(steps):
        g = rk4.step(equation, i * span / steps, g, span / steps)
    return grid, probe.backend.to_numpy(g)


def _states(probe, grid, coldest: float):
    """f0 (projected) and the Maxwellian at the coldest temperature, on ``grid``."""
    f0 = grid.project(probe.initial.sample(grid))
    cold = grid.maxwellian(probe.mass, probe.velocity, coldest)
    return [f0, cold]


def _anisotropic(probe, grid, temperature: float):
    """A Gaussian with temperatures (1.25, 0.75) T in 2D and (1.3, 1, 0.7) T in 3D."""
    factors = (1.25, 0.75) if probe.d == 2 else (1.3, 1.0, 0.7)
    f = probe.mass
    for c, u, factor in zip(grid.mesh(), probe.velocity, factors):
        f = f * numpy.exp(-(c - u) ** 2 / (2 * factor * temperature)) / math.sqrt(
            2 * math.pi * factor * temperature)
    return f


def _fits(probe, grid) -> bool:
    """Whether the runner accepts f0 on ``grid`` (:func:`granframe.model.initial.check_fits` with
    the default health limits, which :func:`health_table` writes into the description): in a
    space scene f0 of every cell (:meth:`Probe.cells`, as the space run checks it, each
    against its intended mass), and the walls (:meth:`Probe.walls_accept`)."""
    health = Health()
    if isinstance(probe.initial, SpaceCondition):
        f, masses = probe.cells(grid)
        pairs = zip(f, [None] * len(f) if masses is None else masses)
    else:
        pairs = [(probe.initial.sample(grid), probe.initial.intended_mass)]
    try:
        for f, mass in pairs:
            check_fits(grid, f, _Mass(mass), health.edge_tolerance,
                       health.initial_mass_tolerance)
    except ValueError:
        return False
    return probe.walls_accept(grid)


@attrs.frozen
class _Mass:
    """What :func:`check_fits` reads of an initial condition: its intended mass (None when
    unknown)."""

    intended_mass: float | None


def mass_drift_bound(precision: str, collision_times: float) -> float:
    """The largest relative mass drift of a run of the fast operator.

    Parameters
    ----------
    precision : str
        The operator's precision, ``float64`` or ``float32``.
    collision_times : float
        nu t / eps of the run: its length in units of the mean free time.

    Returns
    -------
    float
        :data:`MASS_FLOOR_EPSILONS` machine epsilons of ``precision`` times
        ``collision_times``: |d ln rho / dt| = |int Q| / (eps rho) <= MASS_FLOOR_EPSILONS
        eps nu / eps at every evaluation, summed over the run.
    """
    return MASS_FLOOR_EPSILONS * float(numpy.finfo(precision).eps) * collision_times


def health_table(precision: str, collision_times: float) -> dict:
    """The health table of a proposed run, consistent with its precision.

    ``mass_tolerance`` is :func:`mass_drift_bound`, or the runner's default where that is
    looser (in float64 the bound is 9e-15 per collision time, and the default also covers the
    round-off of the time integration). ``initial_mass_tolerance`` is the limit
    :func:`_fits` chose the grid against, the runner's default: f0 is sampled and checked in
    float64 whatever the operator's precision.
    """
    default = Health()
    return {"mass_tolerance": max(default.mass_tolerance,
                                  mass_drift_bound(precision, collision_times)),
            "initial_mass_tolerance": default.initial_mass_tolerance}


def choose_modes(probe, support, coldest, tolerance):
    """Smallest N with spectral tail <= tol / TAIL_ERROR_FACTOR for f0 and the coldest state, among
    the grids the runner accepts f0 on."""
    best = None
    for n in MODES:
        grid = VelocityGrid(probe.d, n, support)
        if not _fits(probe, grid) and n != MODES[-1]:
            continue
        tail = max(spectral_tail(grid, f) for f in _states(probe, grid, coldest))
        best = (grid, TAIL_ERROR_FACTOR * tail)
        if TAIL_ERROR_FACTOR * tail <= SHARE * tolerance:
            break
    return best


def _quadrature_error(probe, grid, states, radial, size, reference, quantity, horizon):
    """The predicted error of the rule (radial, size) against the reference operator, or inf
    when the rule is not consistent: max |Q - Q_ref| / max |Q_ref| > CONSISTENCY on the
    anisotropic state (the last of ``states``)."""
    operator = _probe_operator(grid, probe.kernel, probe.law, probe.backend, radial,
                               _sphere(probe.d, size))
    worst = 0.0
    weight = grid.speed_squared() * grid.cell_volume
    q = probe.backend.to_numpy(operator(probe.backend.asarray(states[-1])))
    if float(numpy.max(numpy.abs(q - reference[-1]))) > CONSISTENCY * float(
            numpy.max(numpy.abs(reference[-1]))):
        return math.inf
    for f, q_ref in zip(states, reference):
        q = probe.backend.to_numpy(operator(probe.backend.asarray(f)))
        if quantity == "temperature":
            rate = abs(float(numpy.sum((q - q_ref) * weight))) / (
                probe.d * grid.mass(f) * grid.temperature(f))
        else:
            rate = float(numpy.max(numpy.abs(q - q_ref))) / float(numpy.max(numpy.abs(f)))
        worst = max(worst, rate / probe.scene.knudsen * horizon)
    return worst


def choose_quadrature(probe, grid, coldest, budget, horizon):
    """The cheapest (N_rho, rule size) whose predicted error is within ``budget``."""
    d, n = probe.d, grid.n_modes
    states = _states(probe, grid, coldest) + [_anisotropic(probe, grid, coldest)]
    radial_ref = max(n, 32)
    size_ref = 64 if d == 2 else 29
    operator = _probe_operator(grid, probe.kernel, probe.law, probe.backend, radial_ref,
                               _sphere(d, size_ref))
    reference = [probe.backend.to_numpy(operator(probe.backend.asarray(f))) for f in states]
    sizes = CIRCLE if d == 2 else SPHERE
    pairs = sorted(((r, s) for r in RADIAL if r <= radial_ref for s in sizes),
                   key=lambda p: (p[0] * _sphere_points(d, p[1]), p[0]))
    for radial, size in pairs:
        error = _quadrature_error(probe, grid, states, radial, size, reference,
                                  probe.scene.quantity, horizon)
        if error <= budget:
            break
    return radial, size, error     # none within budget: the most accurate pair, flagged


def choose_time_step(description, probe, final, horizon, budget):
    """(dt, integrator, predicted time error).

    The largest of 0.9 x the explicit limit (:mod:`granframe.stepping.stability`), halved as often
    as needed, whose RK4 error is within ``budget``. The error is
    measured by step doubling over a window of 8 steps at the start (where f0 relaxes),
    err = |q_dt - q_dt/2| 16/15 (RK4), and scaled by horizon / window.
    """
    from granframe.run.runner import Simulation

    problem = Simulation(description).problem
    equation, backend = problem.equation, problem.backend
    grid, xp = problem.grid, backend.xp
    f0 = backend.asarray(problem.f0)
    schemes = ["rk4"]
    if description.heat_bath > 0 and not description.rescaled:
        schemes.append("if_rk4")
    best = None
    for name in schemes:
        integrator = default_registries().create("time_integrators", name)
        limit = step_limit(integrator, equation, problem.f0)
        dt = min(0.9 * limit.limit if limit is not None else math.inf, final)
        if best is None or dt > best[0] * 1.01:
            best = (dt, name, integrator)
    dt, name, integrator = best

    def march(steps, window):
        f, step = f0, window / steps
        for i in range(steps):
            f = integrator.step(equation, i * step, f, step)
        return f

    def quantity(f):
        return (grid.temperature(f, xp) if probe.scene.quantity == "temperature"
                else backend.to_numpy(f))

    error = math.inf
    for _ in range(8):
        window = min(final, 8 * dt)
        steps = max(1, round(window / dt))
        coarse, fine = quantity(march(steps, window)), quantity(march(2 * steps, window))
        if probe.scene.quantity == "temperature":
            difference = abs(coarse / fine - 1)
        else:
            difference = float(numpy.max(numpy.abs(coarse - fine)) / numpy.max(numpy.abs(fine)))
        error = 16 / 15 * difference * max(1.0, horizon / window)
        if error <= budget:
            break
        dt /= 2
    return dt, name, error
