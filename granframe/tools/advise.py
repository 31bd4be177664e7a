r"""``granframe advise``: the cheapest configuration predicted to meet a tolerance.

A :class:`Scene` says what is to be computed, without numerics: the physics (dimension,
kernel, restitution law, heat bath, Knudsen number, initial data, final time), the quantity
wanted, and a relative tolerance. :func:`advise` returns an :class:`Advice`. That is a full
:class:`~granframe.run.description.RunDescription`, or a closed form where one exists, with
the predicted error of each discretisation and the predicted cost.

How each choice is made (docs/advise.md):

1. **Temperature range.** T(t) of the Maxwellian closure dT/dt = -zeta(T) T / eps + 2 tau.
   zeta(T) = -int Q(M_T) |v|^2 / (d rho T) is measured with the discrete operator on a
   well-resolved Maxwellian. It is exact for Maxwell molecules; otherwise it gives the range.
2. **Formulation.** A closed form for the temperature of Maxwell molecules with a constant
   e (:func:`granframe.model.exact.heated_maxwell_law`). The rescaled formulation
   (:mod:`granframe.equations.rescaled`) for free cooling that would concentrate f by more than
   a factor 4 in T.
3. **Support S.** The smallest S whose truncation of relative speeds at R = 2S removes at
   most tol/10 of the rate that matters, after the amplification of a rate error over
   the run (zeta times the horizon). The rate is the energy dissipation (weight
   |g|^(lambda+2)) for the temperature and the loss frequency (weight |g|^lambda) for f.
   It is checked for f0, for the hottest Maxwellian and for the cooling state of a rescaled
   run (:func:`granframe.velocity.estimators.pair_share_beyond`). Also at most tol/10 of |f| may
   lie beyond 2.4 S, where the box aliases.
4. **Modes N.** The smallest N whose spectral tail (:func:`granframe.velocity.estimators.spectral_tail`)
   times 3 is below tol/3, for f0 and for the coldest Maxwellian, on a grid the runner
   accepts f0 on (:func:`granframe.model.initial.check_fits`). The factor 3 is calibrated on
   the free-cooling study: a temperature error of 1e-3 came with a tail of 3.5e-4.
5. **Quadratures** (N_rho, circle or Lebedev rule). The cheapest pair (cost ~ N_rho M) whose
   operator, applied to f0, to the coldest Maxwellian and to an anisotropic Gaussian,
   differs from a reference rule by less than half of what the resolution and the
   support leave of the tolerance. The difference is measured in the quantity's norm, times the horizon over
   which such an error acts. A rule whose error on the anisotropic Gaussian exceeds 10 % of
   max |Q| is not consistent and is never proposed.
6. **Time step.** RK4 (IF-RK4 when the heat bath sets the explicit limit). dt is 0.9 times
   the explicit limit (:mod:`granframe.stepping.stability`), halved until the error measured by
   step doubling over the first 8 steps, scaled to the horizon, is within what is left of
   the tolerance.
7. **Precision.** float32 where the tolerance is 1e-4 or looser (its measured floor is 4.3e-6
   on BKW 2D, docs/accuracy-vs-cost.md, "float32"), its bound on the mass drift (below) is
   within the tolerance, and it is measured faster than float64 for the proposed operator.
8. **Health.** The description carries health limits its own precision meets. The operator
   conserves mass to its round-off floor, |int Q| <= MASS_FLOOR_EPSILONS eps rho nu per
   evaluation, so over the nu t / eps collision times of the run the mass drifts by at most
   that floor times the collision times: ``health.mass_tolerance`` is that bound, or the
   runner's default where that is looser (in float64). ``health.initial_mass_tolerance`` is
   the limit the grid was chosen against (step 4).
9. **Cost.** The proposed right-hand side is built and timed on this machine (median of 7
   evaluations after 2 warm-ups), times the number of evaluations of the run.
10. **Space scenes** (a ``space`` table: cells, length, walls, reconstruction, and
    optionally a hierarchy of collision models; eps is the scene's ``knudsen``). Rules 1, 3,
    4 and 5 choose the velocity grid and the quadratures, with the temperature range widened
    to the cells' temperatures at t = 0, to the star states behind the Euler waves of a
    Riemann problem (which S must hold, moving) and to the temperatures of the walls, with
    every cell of f0 fitting the grid and every wall accepting it (its Maxwellian fits the
    box and is resolved).
    No closed form and no rescaled run apply. dt is the transport's CFL limit
    2 cfl dx / (L - h), lowered to divide the final time; the integrator is RK4 where its
    explicit limit in the stiffest cell allows that dt, else ``penalised_ars222`` (stable as
    eps -> 0), with ``conservative = true`` for it and for a hierarchy; float64. The errors
    of x and of the splitting are not predicted. The cost is measured by
    :func:`price_hierarchy`: the run all-kinetic and with the scene's hierarchy (or the
    default one, to say what it would save), from the levels chosen at t = 0 and, for a
    Riemann problem, from those estimated as its Euler waves spread.
"""

from __future__ import annotations

import functools
import json
import math

import attrs
import numpy
import scipy.integrate
import scipy.special

from granframe import validators as check
from granframe.run.description import (COMPONENT_FAMILIES, Component, Health, Hierarchy,
                                       RunDescription, Space, component_field, fixed_steps)
from granframe.equations.homogeneous import collision_frequency
from granframe.velocity.estimators import (TAIL_ERROR_FACTOR, mass_beyond, pair_share_beyond,
                                          spectral_tail)
from granframe.model.exact import heated_maxwell_law
from granframe.velocity.grid import VelocityGrid
from granframe.model.initial import check_fits, face_share
from granframe.velocity.moments import FieldMoments
from granframe.space.exact import euler_riemann_star
from granframe.space.initial import RiemannProblem, SpaceCondition
from granframe.velocity.quadratures import LEBEDEV_ORDERS, CircleTrapezoid, Lebedev
from granframe.registry import default_registries
from granframe.stepping.stability import step_limit

QUANTITIES = ("temperature", "distribution")
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
#: loosest tolerance float32 is considered for (its measured floor against an exact solution
#: is 4.3e-6, on BKW 2D: docs/accuracy-vs-cost.md, "float32")
FLOAT32_TOLERANCE = 1e-4
#: |int Q| / (rho nu) of the fast operator, its mass round-off floor per evaluation, in machine
#: epsilons of its precision: measured 5.2e-7 in float32 (4.4 eps) and 1e-15 in float64
#: (4.5 eps), docs/accuracy-vs-cost.md, "float32"; tests/test_operators.py bounds float32 by
#: 5e-6 rho nu (42 eps), the bound taken here
MASS_FLOOR_EPSILONS = 42


@attrs.frozen(kw_only=True)
class Scene:
    r"""What is to be computed: the physics, the quantity and the tolerance.

    Parameters
    ----------
    dimension : int
        2 or 3.
    kernel, restitution, initial : Component
        Registered names with their parameters, as in a run description.
    final_time : float
        The physical time to reach.
    quantity : str
        ``temperature`` (the history T(t), relative error) or ``distribution`` (f at the
        end, max-norm error relative to max f).
    tolerance : float
        Relative tolerance in (0, 0.1].
    heat_bath, knudsen : float
        tau >= 0 and eps > 0 of d_t f = Q/eps + tau Delta f.
    space : Space or None
        A space scene, d_t f + v_1 d_x f = Q/eps + tau Delta f on [0, length]: the
        ``[space]`` table of a run description (cells, length, left, right, reconstruction,
        and optionally a hierarchy of collision models), with collisions. None: a
        space-homogeneous scene. An initial condition that depends on x (``riemann``,
        ``sinusoidal_mode``, ``space_function``) needs one.
    """

    dimension: int = attrs.field(converter=check.to_int, validator=check.integer(choices=(2, 3)))
    kernel: Component = component_field()
    restitution: Component = component_field()
    initial: Component = component_field()
    final_time: float = attrs.field(converter=check.to_float,
                                    validator=check.real(0.0, math.inf, lower_open=True))
    quantity: str = attrs.field(validator=attrs.validators.instance_of(str))
    tolerance: float = attrs.field(converter=check.to_float,
                                   validator=check.real(0.0, 0.1, lower_open=True))
    heat_bath: float = attrs.field(default=0.0, converter=check.to_float,
                                   validator=check.real(0.0, math.inf))
    knudsen: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=check.real(0.0, math.inf, lower_open=True))
    space: Space | None = attrs.field(default=None, converter=lambda value: (
        check.from_table(Space, value, "Scene.space") if isinstance(value, dict) else value))

    @quantity.validator
    def _check_quantity(self, attribute, value):
        if value not in QUANTITIES:
            check.reject("Scene", "quantity", value, f"must be one of {', '.join(QUANTITIES)}")

    @space.validator
    def _check_space(self, attribute, value):
        if value is None:
            return
        if not isinstance(value, Space):
            check.reject("Scene", "space", value, "must be a table (cells, length, left, right, "
                         "reconstruction, hierarchy) or absent", error=TypeError)
        if not value.collisions:
            check.reject("Scene", "space.collisions", False, "must be true: advise chooses the "
                         "velocity grid and the operator of the collision step and prices it, "
                         "and a collisionless gas takes none")

    def __attrs_post_init__(self):
        for field in ("kernel", "restitution", "initial"):
            self.build(field)
        if self.space is None:
            if isinstance(self.build("initial"), SpaceCondition):
                check.reject("Scene", "initial", self.initial.name, "applies to space scenes "
                             "only: add a [space] table (cells, length, left, right), or use a "
                             "space-homogeneous initial condition (maxwellian, bkw, ...)")
            return
        # what the space table can be refused for without a velocity grid, before any probe
        # (the walls are checked against the grid advise chooses: Space.check)
        parts = {field: self.space.build(field) for field in ("reconstruction", "left", "right")}
        ghost = parts["reconstruction"].ghost
        if self.space.cells < 2 * ghost + 1:
            check.reject("Scene", "space.cells", self.space.cells,
                         f"must be >= {2 * ghost + 1}, the stencil of the reconstruction "
                         f"'{self.space.reconstruction.name}' (2 x {ghost} ghost cells + 1)")
        if parts["left"].periodic != parts["right"].periodic:
            check.reject("Scene", "space.right", self.space.right.name,
                         f"must be {'periodic' if parts['left'].periodic else 'a wall'} as "
                         f"space.left = '{self.space.left.name}' is: an interval is periodic "
                         "at both ends or at neither")

    def build(self, field: str):
        """The registered kernel, restitution law or initial condition."""
        component = getattr(self, field)
        return default_registries().create(COMPONENT_FAMILIES[field], component.name,
                                           **component.params)

    @classmethod
    def from_dict(cls, data: dict) -> "Scene":
        if not isinstance(data, dict):
            check.reject("Scene", "scene", data, "must be a table", error=TypeError)
        return check.from_table(cls, data, "Scene")

    def physics(self) -> dict:
        """The fields a run description takes from the scene (with its space table)."""
        return {"kernel": self.kernel.to_dict("kernel"),
                "restitution": self.restitution.to_dict("restitution"),
                "initial": self.initial.to_dict("initial"),
                "heat_bath": self.heat_bath, "knudsen": self.knudsen,
                **({} if self.space is None else {"space": self.space.to_dict()})}


@attrs.frozen
class Advice:
    """A proposed configuration with its predicted error and cost.

    ``description`` is None when ``closed_form`` names an exact law that answers the scene.
    ``errors`` holds the predicted relative error of each discretisation (``resolution``,
    ``support``, ``quadrature``, ``time``; a space scene's errors of x and of the splitting
    are not predicted) and their sum ``total``. For a space scene ``space`` is the
    :class:`HierarchyPrice` of the proposed run, ``evaluations`` its steps and
    ``evaluation_seconds`` the predicted seconds of one step: all-kinetic when the scene has
    no hierarchy; with its hierarchy, at the levels chosen at t = 0, or for a Riemann
    problem the mean of those and of the levels estimated at the end
    (:attr:`HierarchyPrice.estimated_seconds`).
    """

    scene: Scene
    description: RunDescription | None
    closed_form: str | None
    errors: dict
    evaluation_seconds: float
    evaluations: int
    reasons: tuple
    space: "HierarchyPrice | None" = None

    @property
    def predicted_seconds(self) -> float:
        """Predicted run time: time per evaluation (per step) times evaluations (steps)."""
        return self.evaluation_seconds * self.evaluations

    @property
    def meets_tolerance(self) -> bool:
        return self.errors.get("total", math.inf) <= self.scene.tolerance

    def report(self) -> str:
        scene = self.scene
        lines = [f"scene: {scene.dimension}D {scene.kernel.name}, "
                 f"{scene.restitution.name} restitution, tau = {scene.heat_bath:g}, "
                 f"eps = {scene.knudsen:g}, t <= {scene.final_time:g}"
                 + ("" if scene.space is None else
                    f", {scene.space.cells} cells on [0, {scene.space.length:g}]")
                 + f"; {scene.quantity} to {scene.tolerance:g}"]
        if self.closed_form:
            lines.append(f"answer: the closed form {self.closed_form} (no simulation needed)")
        else:
            lines.append(f"predicted error {self.errors['total']:.2g} ("
                         + ", ".join(f"{k} {v:.2g}" for k, v in self.errors.items()
                                     if k != "total") + ")"
                         + ("" if self.space is None else " in velocity; x and the splitting "
                            "not predicted")
                         + ("" if self.meets_tolerance else "; ABOVE the tolerance"))
            if self.space is None:
                lines.append(f"predicted cost {self.predicted_seconds:.3g} s = "
                             f"{self.evaluations} evaluations x "
                             f"{1e3 * self.evaluation_seconds:.3g} ms on this machine")
            else:
                how = ("all-kinetic" if not self.space.given else
                       "with the hierarchy, at its levels of t = 0"
                       if self.space.final_counts is None else
                       "with the hierarchy, as the Euler waves spread")
                lines.append(f"predicted cost {self.predicted_seconds:.3g} s = "
                             f"{self.evaluations} steps x {1e3 * self.evaluation_seconds:.3g} "
                             f"ms on this machine ({how})")
        lines += [f"- {reason}" for reason in self.reasons]
        if self.space is not None:
            lines.append(self.space.report())
        return "\n".join(lines)


def _probe_operator(grid, kernel, law, backend, radial, sphere, precision="float64"):
    return default_registries().create(
        "collision_operators", "fast_spectral", grid=grid, kernel=kernel, restitution=law,
        backend=backend, radial_points=radial, sphere=sphere, precision=precision)


def _sphere(dimension: int, size: int):
    return CircleTrapezoid(size) if dimension == 2 else Lebedev(size)


def _sphere_points(dimension: int, size: int) -> int:
    return size if dimension == 2 else Lebedev(size).n_points


class _Probe:
    """The scene's objects and the measurements advise makes on them."""

    def __init__(self, scene: Scene, backend):
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
        :func:`granframe.space.exact.euler_riemann_star`), u with the tangential components
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


def _support(probe, hottest: float, budget: float, amplification: float,
             states) -> tuple[float, float]:
    """Smallest S (a multiple of sqrt(T)/4) such that

    - truncating relative speeds at R = 2S removes a share of the rate that matters (the
      energy dissipation, weight |g|^(lambda+2), for the temperature; the loss frequency,
      |g|^lambda, for f) of at most ``budget`` / ``amplification``;
    - at most ``budget`` of |f| lies beyond 2.4 S, where the box L = 2.207 S starts to alias
      (docs/stability.md);

    for the hottest Maxwellian (closed form) and for ``states``: (grid, f) pairs, f0 and the
    cooling state of a rescaled run; and such that the walls of a space scene accept the box
    (:meth:`_Probe.walls_accept` on the finest grid of :data:`MODES`: the wall Maxwellians
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


def _cooling_state(probe, final_s: float):
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
    the default health limits, which :func:`_health` writes into the description): in a
    space scene f0 of every cell (:meth:`_Probe.cells`, as the space run checks it, each
    against its intended mass), and the walls (:meth:`_Probe.walls_accept`)."""
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


def _health(precision: str, collision_times: float) -> dict:
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


def _resolution(probe, support, coldest, tolerance):
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


def _quadrature(probe, grid, coldest, budget, horizon):
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


def evaluation_seconds(simulation, repeats: int = 7) -> float:
    """Median seconds of one evaluation of a simulation's right-hand side on f0 (the
    collision operator, and the drift of a rescaled run), after two warm-up evaluations,
    timed by the backend (:func:`granframe.tools.bench.median_time`)."""
    from granframe.tools.bench import median_time

    f = simulation.backend.asarray(simulation.f0)

    def evaluate():
        simulation.equation.nonlinear(0.0, f)

    for _ in range(2):
        evaluate()
    return median_time(evaluate, repeats, simulation.backend)


def _time_evaluation(description) -> float:
    """:func:`evaluation_seconds` of a description."""
    from granframe.run.runner import Simulation

    return evaluation_seconds(Simulation(description))


def advise(scene: Scene, *, backend: str = "auto", closed_forms: bool = True) -> Advice:
    """The cheapest configuration predicted to meet ``scene.tolerance`` (see the module notes).

    ``closed_forms=False`` always proposes a simulation (to compare with one). A space
    scene gets a space run (rule 10), priced all-kinetic and with a hierarchy of collision
    models (:func:`price_hierarchy`; :attr:`Advice.space`).
    """
    if not isinstance(scene, Scene):
        check.reject("advise", "scene", scene, "must be a Scene", error=TypeError)
    from granframe.backends import resolve_backend
    backend_name = resolve_backend(backend)
    array_backend = default_registries().create("array_backends", backend_name)
    probe = _Probe(scene, array_backend)
    tol, reasons = scene.tolerance, []
    law_t = heated_maxwell_law(probe.kernel, probe.law, scene.heat_bath, scene.knudsen)
    if (closed_forms and scene.space is None and scene.quantity == "temperature"
            and law_t is not None):
        reasons.append("Maxwell molecules with a constant restitution coefficient: "
                       "T(t) is known exactly whatever f0 is (review, eq. (ext_temp))")
        return Advice(scene, None, "granframe.model.exact.heated_maxwell_law", {"total": 0.0}, 0.0, 0,
                      tuple(reasons))
    coldest, hottest, final_t, zeta0, zeta = probe.temperature_history()
    reasons.append(f"Maxwellian closure: T from {probe.t0:.4g} to {final_t:.4g} "
                   f"(range {coldest:.3g} ... {hottest:.3g})")
    if scene.space is not None:
        coldest, hottest, reason = probe.space_range(coldest, hottest)
        reasons.append(reason)
    rescaled = (scene.space is None and scene.heat_bath == 0.0 and probe.law.is_constant
                and zeta0 > 0.0 and probe.degree >= 0.0 and coldest < probe.t0 / 4)
    if rescaled:
        reasons.append(f"free cooling concentrates f (T falls {probe.t0 / coldest:.3g}-fold): "
                       "rescaled formulation, whose profile keeps T ~ T0")
        coldest = hottest = probe.t0
        rate = zeta0 / (2 * scene.knudsen)
        growth = probe.degree * rate
        final = (scene.final_time if growth == 0.0
                 else math.log1p(growth * scene.final_time) / growth)
    else:
        final = scene.final_time
    # over what time an error in the rate acts on the quantity, and how much it grows
    if scene.quantity == "temperature":
        relax = (probe.degree / 2 * zeta(final_t) / scene.knudsen
                 + 2 * scene.heat_bath / final_t)
        horizon = final if scene.heat_bath == 0.0 else min(final, 1.0 / relax)
        amplification = max(zeta(hottest) / scene.knudsen * horizon, 0.1)
    else:
        nu = probe.collision_frequency(coldest if rescaled else hottest) / scene.knudsen
        horizon = min(final, 2.0 / nu)
        amplification = max(nu * horizon, 1.0)
    states = [(probe.fine_grid, probe.f0)] + [
        (probe.fine_grid, probe.fine_grid.maxwellian(rho, u, temperature))
        for rho, u, temperature in probe.star_states]
    if rescaled:
        states.append(_cooling_state(probe, final))
    support, support_error = _support(probe, hottest, tol / 10, amplification, states)
    grid, resolution_error = _resolution(probe, support, coldest, tol)
    reasons.append(f"S = {support:g} (truncation at R = 2S: <= {tol / 10:.2g} after an "
                   f"amplification {amplification:.3g}); N = {grid.n_modes}: spectral tail x "
                   f"{TAIL_ERROR_FACTOR:g} = {resolution_error:.2g} at T = {coldest:.3g}")
    # what the resolution and the support leave of the tolerance: half to the quadratures,
    # the rest to the time step (in a space run: to x, the splitting and time, unpredicted)
    radial, size, quadrature_error = _quadrature(probe, grid, coldest,
                                                 (tol - resolution_error - support_error) / 2,
                                                 horizon)
    rule = f"M = {size}" if probe.d == 2 else f"Lebedev {size}"
    reasons.append(f"N_rho = {radial}, {rule}: operator error x horizon {horizon:.3g} = "
                   f"{quadrature_error:.2g}")
    operator = {"name": "fast_spectral", "radial_points": radial,
                "sphere": ({"name": "circle_trapezoid", "n_points": size} if probe.d == 2
                           else {"name": "lebedev", "order": size})}
    grid_table = {"dimension": probe.d, "n_modes": grid.n_modes, "support_radius": support}
    if scene.space is not None:
        errors = {"resolution": resolution_error, "support": support_error,
                  "quadrature": quadrature_error}
        errors["total"] = sum(errors.values())
        return _advise_space(scene, {"grid": grid_table, "operator": operator,
                                     "backend": backend_name, **scene.physics()},
                             errors, reasons)
    base = {"final_time": final, "time_step": final, "grid": grid_table, "operator": operator,
            "backend": backend_name, "rescaled": rescaled, **scene.physics(),
            "health": {"step_limit": False}}
    description = RunDescription.from_dict(base)
    dt, integrator, time_error = _time_step(description, probe, final, horizon,
                                            tol - resolution_error - support_error
                                            - quadrature_error)
    steps = max(1, math.ceil(final / dt - 1e-9))
    dt = final / steps
    reasons.append(f"{integrator}, dt = {dt:.4g} ({steps} steps; RK4 error by step doubling "
                   f"{time_error:.2g})")
    # the collision times the run spans: the mass round-off of the operator acts over them
    collision_times = probe.collision_frequency(hottest) / scene.knudsen * steps * dt

    def proposal(precision):
        """The description in ``precision``; the moments (temperature) are written every
        step, f at the start and the end."""
        return RunDescription.from_dict(
            {**base, "final_time": steps * dt, "time_step": dt, "integrator": integrator,
             "operator": (operator if precision == "float64"
                          else {**operator, "precision": precision}),
             "health": _health(precision, collision_times)})

    description = proposal("float64")
    seconds = _time_evaluation(description)
    drift32 = mass_drift_bound("float32", collision_times)
    if tol >= FLOAT32_TOLERANCE and drift32 <= tol:
        single = proposal("float32")
        single_seconds = _time_evaluation(single)
        if single_seconds < seconds:
            reasons.append(f"float32: measured faster here ({1e3 * single_seconds:.3g} ms "
                           f"against {1e3 * seconds:.3g} ms); mass drift over "
                           f"{collision_times:.3g} collision times at most {drift32:.2g} "
                           "(health.mass_tolerance)")
            description, seconds = single, single_seconds
    errors = {"resolution": resolution_error, "support": support_error,
              "quadrature": quadrature_error, "time": time_error}
    errors["total"] = sum(errors.values())
    return Advice(scene, description, None, errors, seconds, 4 * steps, tuple(reasons))


def _time_step(description, probe, final, horizon, budget):
    """(dt, integrator, predicted time error).

    The largest of 0.9 x the explicit limit (:mod:`granframe.stepping.stability`), halved as often
    as needed, whose RK4 error is within ``budget``. The error is
    measured by step doubling over a window of 8 steps at the start (where f0 relaxes),
    err = |q_dt - q_dt/2| 16/15 (RK4), and scaled by horizon / window.
    """
    from granframe.run.runner import Simulation

    simulation = Simulation(description)
    equation, backend = simulation.equation, simulation.backend
    grid, xp = simulation.grid, backend.xp
    f0 = backend.asarray(simulation.f0)
    schemes = ["rk4"]
    if description.heat_bath > 0 and not description.rescaled:
        schemes.append("if_rk4")
    best = None
    for name in schemes:
        integrator = default_registries().create("time_integrators", name)
        limit = step_limit(integrator, equation, simulation.f0)
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


#: the space price's timings: medians of this many, each after one warm-up call
SPACE_REPEATS = 5
#: the largest batch of cells each collision model is timed on (and a batch of one)
BATCH_CELLS = 8


def _advise_space(scene: Scene, base: dict, errors: dict, reasons: list) -> Advice:
    """The proposal for a space scene (rule 10) with the velocity grid, the operator and the
    physics in ``base``, priced by :func:`price_hierarchy`.

    dt = t / ceil(t / dt_x), dt_x = 2 cfl dx / (L - h) the transport's CFL limit
    (:meth:`~granframe.run.description.Space.transport_limit`); RK4 when its explicit limit
    in the stiffest cell of f0 (:func:`~granframe.run.problems.time_step_limit`) is at least
    dt, else ``penalised_ars222``.
    """
    from granframe.run.problems import time_step_limit

    space, final = scene.space, scene.final_time
    limit = space.transport_limit(VelocityGrid(**base["grid"]))
    steps = max(1, math.ceil(final / limit * (1 - 1e-12)))
    dt = final / steps
    base = {**base, "final_time": final, "time_step": dt}
    explicit = time_step_limit(RunDescription.from_dict({**base, "integrator": "rk4",
                                                         "conservative": True}))
    if explicit is None or explicit.limit >= dt:
        integrator = "rk4"
        why = ("no explicit limit" if explicit is None else
               f"its explicit limit in the stiffest cell, {explicit.limit:.3g}, allows that dt")
    else:
        integrator = "penalised_ars222"
        why = (f"rk4's explicit limit in the stiffest cell, {explicit.limit:.3g}, is below "
               "that dt, and this scheme is stable as eps -> 0")
    conservative = integrator != "rk4" or space.hierarchy is not None
    description = RunDescription.from_dict({**base, "integrator": integrator,
                                            **({"conservative": True} if conservative else {})})
    reasons.append(f"space: dt = {dt:.4g} ({steps} steps), the transport's CFL limit "
                   f"2 cfl dx / (L - h) = {limit:.4g} lowered to divide t; {integrator}: {why}"
                   + ("; conservative = true" if conservative else ""))
    reasons.append(f"the errors of x (dx = {space.length / space.cells:.3g}, "
                   f"{space.reconstruction.name}) and of the splitting are not predicted: "
                   "compare with a run on twice the cells")
    price = price_hierarchy(description)
    if not price.given:
        seconds = price.kinetic_step_seconds
    elif price.estimated_seconds is None:
        seconds = price.hierarchy_step_seconds
    else:
        seconds = price.estimated_seconds / price.steps
    return Advice(scene, description, None, errors, seconds, price.steps, tuple(reasons), price)


@attrs.frozen
class HierarchyPrice:
    r"""What the steps of a space run cost on this machine, all-kinetic and with a hierarchy
    of collision models (:func:`price_hierarchy` measures it).

    With C cells, n_l of them at level l when the levels are chosen from f0 (as the run's
    first step chooses them), and K the full level (the last), one step costs

    .. math:: T_{kin} = \tau_x + a_K + b_K C, \qquad
              T_{hier} = \tau_x + \sum_{l:\,n_l > 0} (a_l + b_l n_l) + m + c / I,

    with tau_x the transport of all cells (two half steps), a_l + b_l n the collision step
    of a batch of n cells at level l (each level advances its cells in one call), m the
    indicators of all cells (measured every step), c the choice of the levels (every
    I = ``interval`` steps). The run costs its steps times that. The all-kinetic step is
    the full level on every cell, which is what a run without a hierarchy does.

    The levels change as waves move. For a Riemann problem the price also estimates them at
    the final time t_f (:func:`_swept_levels`): the cells the Euler waves have swept at the
    full level, the others as at t = 0, n_l(t_f). The swept region grows linearly in time,
    so the run is estimated at steps x (T_hier(n(0)) + T_hier(n(t_f))) / 2.

    Parameters
    ----------
    run : RunDescription
        The run as given.
    priced : RunDescription
        The run priced: ``run`` when it has a hierarchy; else ``run`` with the default
        :class:`~granframe.run.description.Hierarchy` and ``conservative`` set (which a
        hierarchy needs; the all-kinetic price then includes that correction too).
    counts : tuple of int
        n_l, the cells at each level chosen from f0.
    transport_seconds : float
        tau_x.
    level_seconds : tuple of (float, float)
        (a_l, b_l) of each level, from the levels' timings on 1 and ``batch`` cells.
    measure_seconds, choose_seconds : float
        m and c.
    batch, repeats : int
        The larger batch timed, and how many timings each median is of.
    final_counts : tuple of int or None
        n_l(t_f), the cells at each level at the final time estimated from the waves of a
        Riemann problem; None for other initial data.
    """

    run: RunDescription
    priced: RunDescription
    counts: tuple
    transport_seconds: float
    level_seconds: tuple
    measure_seconds: float
    choose_seconds: float
    batch: int
    repeats: int
    final_counts: tuple | None = None

    @property
    def given(self) -> bool:
        """Whether the hierarchy priced is the run's own (else the default one)."""
        return self.run.space.hierarchy is not None

    @property
    def hierarchy(self) -> Hierarchy:
        return self.priced.space.hierarchy

    @property
    def names(self) -> tuple:
        return tuple(level.name for level in self.hierarchy.levels)

    @property
    def cells(self) -> int:
        return self.priced.space.cells

    @property
    def steps(self) -> int:
        """The run's steps (:func:`~granframe.run.description.fixed_steps`; a short last step
        counts as one)."""
        full, last = fixed_steps(self.priced.final_time, self.priced.time_step)
        return full + (1 if last else 0)

    @property
    def shares(self) -> dict:
        """n_l / C of each level, at t = 0."""
        return {name: count / self.cells for name, count in zip(self.names, self.counts)}

    @property
    def choice_seconds(self) -> float:
        """m + c / I."""
        return self.measure_seconds + self.choose_seconds / self.hierarchy.interval

    @property
    def kinetic_step_seconds(self) -> float:
        """T_kin = tau_x + a_K + b_K C."""
        fixed, per_cell = self.level_seconds[-1]
        return self.transport_seconds + fixed + per_cell * self.cells

    @property
    def hierarchy_step_seconds(self) -> float:
        """T_hier(n(0)) = tau_x + sum over the levels with cells of (a_l + b_l n_l) + m + c / I,
        at the levels of t = 0."""
        return self.step_seconds(self.counts)

    def step_seconds(self, counts) -> float:
        """T_hier(n) with ``counts`` n_l cells at each level."""
        return (self.transport_seconds + self.choice_seconds
                + sum(fixed + per_cell * count for (fixed, per_cell), count
                      in zip(self.level_seconds, counts) if count))

    @property
    def estimated_seconds(self) -> float | None:
        """steps x (T_hier(n(0)) + T_hier(n(t_f))) / 2, the run with the hierarchy as the
        waves of a Riemann problem spread; None without :attr:`final_counts`."""
        if self.final_counts is None:
            return None
        return self.steps * 0.5 * (self.hierarchy_step_seconds
                                   + self.step_seconds(self.final_counts))

    @property
    def kinetic_seconds(self) -> float:
        return self.steps * self.kinetic_step_seconds

    @property
    def hierarchy_seconds(self) -> float:
        return self.steps * self.hierarchy_step_seconds

    @property
    def saving(self) -> float:
        """T_kin / T_hier: above 1 the hierarchy is predicted cheaper at its levels of t = 0."""
        return self.kinetic_step_seconds / self.hierarchy_step_seconds

    def fragment(self) -> str:
        """The TOML to add to the run for the hierarchy priced (with ``conservative = true``
        before it when the run has no correction), one line per parameter; a level without
        parameters by its name."""
        table = self.hierarchy.to_dict()
        table["levels"] = [level["name"] if set(level) == {"name"} else level
                           for level in table["levels"]]
        return "\n".join(([] if self.run.conservative else ["conservative = true"])
                         + ["[space.hierarchy]"]
                         + [f"{key} = {_toml_value(value)}" for key, value in table.items()])

    def to_dict(self) -> dict:
        """JSON-ready: the measurements, the levels at t = 0 and the predictions."""
        return {"cells": self.cells, "steps": self.steps, "time_step": self.priced.time_step,
                "hierarchy": self.hierarchy.to_dict(), "given": self.given,
                "shares_at_start": self.shares,
                "counts_at_start": dict(zip(self.names, self.counts)),
                "transport_seconds": self.transport_seconds,
                "level_seconds": {name: {"fixed": fixed, "per_cell": per_cell}
                                  for name, (fixed, per_cell)
                                  in zip(self.names, self.level_seconds)},
                "measure_seconds": self.measure_seconds,
                "choose_seconds": self.choose_seconds,
                "kinetic_step_seconds": self.kinetic_step_seconds,
                "hierarchy_step_seconds": self.hierarchy_step_seconds,
                "kinetic_seconds": self.kinetic_seconds,
                "hierarchy_seconds": self.hierarchy_seconds, "saving": self.saving,
                "counts_at_end": (None if self.final_counts is None
                                  else dict(zip(self.names, self.final_counts))),
                "estimated_seconds": self.estimated_seconds,
                "batch": self.batch, "repeats": self.repeats}

    def report(self) -> str:
        """The lines ``granframe advise`` prints: the run, what was measured, the levels of
        t = 0, both prices and their ratio, what the shares of t = 0 leave open, and the
        fragment to add when the run has no hierarchy."""
        d, space, h = self.priced, self.priced.space, self.hierarchy
        ms = 1e3
        levels = ", ".join(f"{name} {ms * fixed:.3g} ms + {ms * per_cell:.3g} ms x n"
                           for name, (fixed, per_cell) in zip(self.names, self.level_seconds))
        shares = ", ".join(f"{name} {100 * share:.0f} % ({count})" for (name, share), count
                           in zip(self.shares.items(), self.counts))
        verdict = (f"{self.saving:.3g}x cheaper" if self.saving >= 1
                   else f"{1 / self.saving:.3g}x dearer")
        full = self.steps * (self.kinetic_step_seconds + self.choice_seconds)
        ordered = all(low[0] <= high[0] and low[1] <= high[1] for low, high
                      in zip(self.level_seconds, self.level_seconds[1:]))
        lines = [
            f"space run: {self.cells} cells on [0, {space.length:g}] ({space.left.name} | "
            f"{space.right.name}, {space.reconstruction.name}), {d.grid.dimension}D N = "
            f"{d.grid.n_modes}, S = {d.grid.support_radius:g}, eps = {d.knudsen:g}, "
            f"{d.integrator.name}, dt = {d.time_step:.4g}: {self.steps} steps",
            f"measured here (medians of {self.repeats} after a warm-up): transport "
            f"{ms * self.transport_seconds / self.cells:.3g} ms per cell and step; collision "
            f"step of n cells: {levels}; indicators {ms * self.measure_seconds:.3g} ms per "
            f"step, choice {ms * self.choose_seconds:.3g} ms every {h.interval} step(s)",
            f"levels chosen from f0 (t = 0): {shares} of the cells",
            f"all-kinetic: {self.kinetic_step_seconds:.3g} s per step x {self.steps} = "
            f"{self.kinetic_seconds:.3g} s"
            + ("" if self.run.conservative else " (with the conservative correction a "
                                                "hierarchy needs, which the run has not)"),
            f"with the {'hierarchy' if self.given else 'default hierarchy'} "
            f"({' < '.join(self.names)}): {self.hierarchy_step_seconds:.3g} s per step x "
            f"{self.steps} = {self.hierarchy_seconds:.3g} s at the levels of t = 0: {verdict}",
            "- these shares are those of t = 0 and change as waves move: where the "
            "non-equilibrium spreads from the initial data, cells rise to higher levels; "
            f"with every cell at {self.names[-1]} the hierarchy costs {full:.3g} s (the "
            "all-kinetic price, the indicators and the choice). "
            + ("Each level costs more than the one below it, so the saving of t = 0 is then "
               "an upper bound. " if ordered else
               "The levels are not dearer in their order here (a + b n above), so cells that "
               "rise may lower the cost as well as raise it. ")
            + f"The all-kinetic price, {self.kinetic_seconds:.3g} s, holds whatever the "
            "levels."]
        if self.final_counts is not None:
            estimate = self.estimated_seconds
            lines.append(
                f"- at t = {d.final_time:g} the Euler waves of the Riemann problem have swept "
                f"{self.final_counts[-1] - self.counts[-1]} more cells (with the buffer): with "
                f"them at {self.names[-1]}, a step costs "
                f"{self.step_seconds(self.final_counts):.3g} s; as the waves spread linearly in "
                f"time the run costs about {estimate:.3g} s, "
                + (f"{self.kinetic_seconds / estimate:.3g}x cheaper" if estimate
                   <= self.kinetic_seconds else f"{estimate / self.kinetic_seconds:.3g}x dearer")
                + " than all-kinetic (an estimate: cells the waves have left may stay above "
                "the fluid level, and the fluid levels take longer on data far from "
                "equilibrium)")
        if not self.given:
            lines.append("- the run has no hierarchy; to use the default one, add:\n"
                         + "\n".join("    " + line for line in self.fragment().splitlines()))
        return "\n".join(lines)


def _swept_levels(description, levels):
    """The levels at the final time t_f of a run from a ``riemann`` initial condition,
    estimated: every cell the waves of the Euler Riemann problem (the limit eps -> 0,
    gamma = (d + 2)/d; :func:`granframe.space.exact.euler_riemann_star`) have swept by then,
    [x0 + s_min t_f, x0 + s_max t_f] with s the speeds of the slowest and the fastest wave,
    widened by the hierarchy's buffer, at the full level; the others at ``levels`` (those of
    t = 0). In a periodic interval the discontinuity at its ends (the right state left of
    it) sends waves too. Waves reflected by a wall stay inside the swept region. None for
    another initial condition, or states that open a vacuum."""
    initial = description.build("initial")
    if not isinstance(initial, RiemannProblem):
        return None
    space, d, t = description.space, description.grid.dimension, description.final_time
    periodic = description.build("space")["left"].periodic
    jumps = [(initial.interface * space.length, initial.left, initial.right)]
    if periodic:
        jumps.append((0.0, initial.right, initial.left))
    dx = space.length / space.cells
    edges = numpy.arange(space.cells) * dx
    swept = numpy.zeros(space.cells, dtype=bool)
    for x0, left, right in jumps:
        try:
            speeds = euler_riemann_star(*[(side["density"], side["velocity"][0],
                                           side["density"] * side["temperature"])
                                          for side in (left, right)], (d + 2.0) / d)["speeds"]
        except ValueError:
            return None
        low, width = x0 + min(speeds) * t, (max(speeds) - min(speeds)) * t
        if periodic:    # the cells [e, e + dx] that meet [low, low + width] modulo the length
            swept |= ((edges - low) % space.length < width) | (
                (low - edges) % space.length < dx)
        else:
            swept |= (edges + dx > low) & (edges < low + width)
    for _ in range(description.space.hierarchy.buffer):
        if periodic:
            left, right = numpy.roll(swept, 1), numpy.roll(swept, -1)
        else:
            left = numpy.concatenate([swept[:1], swept[:-1]])
            right = numpy.concatenate([swept[1:], swept[-1:]])
        swept = swept | left | right
    return numpy.where(swept, len(description.space.hierarchy.levels) - 1, levels)


def _toml_value(value) -> str:
    """``value`` (a string, number, boolean, list or table of them) as an inline TOML value."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{key} = {_toml_value(v)}" for key, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value)


def _median_seconds(function, repeats: int, backend) -> float:
    """The median of ``repeats`` timings of ``function`` by ``backend.elapsed`` (host clock
    with synchronisation, or device events) after one warm-up call. Each function is timed
    on its own, not in rounds with the others: the fast operator keeps the transforms of the
    last batch size it was called on, so alternating two batch sizes would time their
    planning."""
    from granframe.tools.bench import median_time

    function()
    return median_time(function, repeats, backend)


def _affine(single: float, batched: float, batch: int) -> tuple[float, float]:
    """(a, b) of the cost a + b n of a batch of n cells, through the timings of 1 and
    ``batch`` cells: b = (t_B - t_1) / (B - 1), a = t_1 - b, each at least 0 (timing noise
    that makes t_B < t_1 gives b = 0, a = t_1)."""
    per_cell = max(batched - single, 0.0) / (batch - 1)
    return max(single - per_cell, 0.0), per_cell


def price_hierarchy(description, *, repeats: int = SPACE_REPEATS) -> HierarchyPrice:
    """Price a space run on this machine, all-kinetic and with a hierarchy of collision
    models (:class:`HierarchyPrice` gives the formulas).

    The run is built as it would run in one process
    (:func:`~granframe.run.problems.make_problem`) with its hierarchy, or the default
    :class:`~granframe.run.description.Hierarchy` when it has none. Its levels are chosen
    from f0 (``measure`` then ``choose`` of
    :class:`~granframe.space.hierarchy.HybridCollisions`, what the first step does). Then,
    each the median of ``repeats`` timings by the backend after one warm-up call
    (:func:`_median_seconds`): each level's ``advance`` over dt on one cell and on
    B = min(C, BATCH_CELLS) cells of f0 spread over the interval; the transport of all
    cells (two half steps of dt/2); the indicators of all cells and the choice.

    Parameters
    ----------
    description : RunDescription
        A run with a ``space`` table, with collisions.
    repeats : int
        Timings per median, at least 1.
    """
    from granframe.parallel import SerialCommunicator
    from granframe.run.problems import make_problem

    if not isinstance(description, RunDescription):
        check.reject("advise", "description", description, "must be a RunDescription",
                     error=TypeError)
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        check.reject("advise", "repeats", repeats, "must be an integer >= 1")
    space = description.space
    if space is None:
        check.reject("advise", "space", None, "must be a table (cells, length, left, right): "
                     "a run description is priced for its space run, all-kinetic and with a "
                     "hierarchy of collision models; give a space-homogeneous case as a scene "
                     "(no grid: advise chooses it)")
    if not space.collisions:
        check.reject("advise", "space.collisions", False, "must be true: a collisionless run "
                     "takes no collision step to price")
    priced = description
    if space.hierarchy is None:
        data = description.to_dict()
        data["space"]["hierarchy"] = Hierarchy().to_dict()
        data["conservative"] = description.conservative or True
        priced = RunDescription.from_dict(data)
    problem = make_problem(priced, communicator=SerialCommunicator())
    backend, hybrid, dt = problem.backend, problem.hierarchy, priced.time_step
    f0 = backend.asarray(problem.f0)
    hybrid.measure(f0)
    hybrid.choose()
    def count(levels):
        return tuple(int(numpy.count_nonzero(levels == k)) for k in range(len(hybrid.models)))

    swept = _swept_levels(priced, hybrid.levels)
    counts, final = count(hybrid.levels), None if swept is None else count(swept)
    batch = min(space.cells, BATCH_CELLS)
    picks = backend.xp.asarray(numpy.round(numpy.linspace(0, space.cells - 1, batch))
                               .astype(numpy.int64))
    one, many = f0[picks[:1]], f0[picks]
    state = problem.state(problem.f0)

    def transport():
        problem.transport.advance(state, 0.5 * dt, 0.0)
        problem.transport.advance(state, 0.5 * dt, 0.5 * dt)

    level_seconds = tuple(
        _affine(_median_seconds(functools.partial(model.advance, one, 0.0, dt), repeats,
                                backend),
                _median_seconds(functools.partial(model.advance, many, 0.0, dt), repeats,
                                backend), batch)
        for model in hybrid.models)
    transport_seconds, measure_seconds, choose_seconds = (
        _median_seconds(function, repeats, backend)
        for function in (transport, functools.partial(hybrid.measure, f0), hybrid.choose))
    return HierarchyPrice(description, priced, counts, transport_seconds, level_seconds,
                          measure_seconds, choose_seconds, batch, repeats, final)
