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
"""

from __future__ import annotations

import functools
import math

import attrs
import numpy
import scipy.integrate
import scipy.special

from granframe import validators as check
from granframe.run.description import (COMPONENT_FAMILIES, Component, Health, RunDescription,
                                       component_field)
from granframe.equations.homogeneous import collision_frequency
from granframe.velocity.estimators import (TAIL_ERROR_FACTOR, mass_beyond, pair_share_beyond,
                                          spectral_tail)
from granframe.model.exact import heated_maxwell_law
from granframe.velocity.grid import VelocityGrid
from granframe.model.initial import check_fits, face_share
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

    @quantity.validator
    def _check_quantity(self, attribute, value):
        if value not in QUANTITIES:
            check.reject("Scene", "quantity", value, f"must be one of {', '.join(QUANTITIES)}")

    def __attrs_post_init__(self):
        for field in ("kernel", "restitution", "initial"):
            self.build(field)

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
        """The fields a run description takes from the scene."""
        return {"kernel": self.kernel.to_dict("kernel"),
                "restitution": self.restitution.to_dict("restitution"),
                "initial": self.initial.to_dict("initial"),
                "heat_bath": self.heat_bath, "knudsen": self.knudsen}


@attrs.frozen
class Advice:
    """A proposed configuration with its predicted error and cost.

    ``description`` is None when ``closed_form`` names an exact law that answers the scene.
    ``errors`` holds the predicted relative error of each discretisation (``resolution``,
    ``support``, ``quadrature``, ``time``) and their sum ``total``.
    """

    scene: Scene
    description: RunDescription | None
    closed_form: str | None
    errors: dict
    evaluation_seconds: float
    evaluations: int
    reasons: tuple

    @property
    def predicted_seconds(self) -> float:
        """Predicted run time: time per evaluation times evaluations."""
        return self.evaluation_seconds * self.evaluations

    @property
    def meets_tolerance(self) -> bool:
        return self.errors.get("total", math.inf) <= self.scene.tolerance

    def report(self) -> str:
        lines = [f"scene: {self.scene.dimension}D {self.scene.kernel.name}, "
                 f"{self.scene.restitution.name} restitution, tau = {self.scene.heat_bath:g}, "
                 f"eps = {self.scene.knudsen:g}, t <= {self.scene.final_time:g}; "
                 f"{self.scene.quantity} to {self.scene.tolerance:g}"]
        if self.closed_form:
            lines.append(f"answer: the closed form {self.closed_form} (no simulation needed)")
        else:
            lines.append(f"predicted error {self.errors['total']:.2g} ("
                         + ", ".join(f"{k} {v:.2g}" for k, v in self.errors.items()
                                     if k != "total") + ")"
                         + ("" if self.meets_tolerance else "; ABOVE the tolerance"))
            lines.append(f"predicted cost {self.predicted_seconds:.3g} s = {self.evaluations} "
                         f"evaluations x {1e3 * self.evaluation_seconds:.3g} ms on this machine")
        lines += [f"- {reason}" for reason in self.reasons]
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
    cooling state of a rescaled run. Returns (S, predicted error: the largest share times
    ``amplification``).
    """
    power = probe.kernel.speed_exponent + (2.0 if probe.scene.quantity == "temperature" else 0.0)
    allowed = budget / max(amplification, 1e-300)
    scale = math.sqrt(max(hottest, probe.t0))
    for multiple in numpy.arange(2.0, 12.01, 0.25):
        support = float(round(multiple * scale, 3))
        shares = [scipy.special.gammaincc((probe.d + power) / 2, support ** 2 / hottest)]
        shares += [pair_share_beyond(grid, f, 2 * support, power) for grid, f in states]
        if max(shares) <= allowed and all(mass_beyond(grid, f, 2.4 * support) <= budget
                                          for grid, f in states):
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
    the default health limits, which :func:`_health` writes into the description)."""
    health = Health()
    try:
        check_fits(grid, probe.initial.sample(grid), probe.initial, health.edge_tolerance,
                   health.initial_mass_tolerance)
    except ValueError:
        return False
    return True


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

    ``closed_forms=False`` always proposes a simulation (to compare with one).
    """
    if not isinstance(scene, Scene):
        check.reject("advise", "scene", scene, "must be a Scene", error=TypeError)
    from granframe.backends import resolve_backend
    backend_name = resolve_backend(backend)
    array_backend = default_registries().create("array_backends", backend_name)
    probe = _Probe(scene, array_backend)
    tol, reasons = scene.tolerance, []
    law_t = heated_maxwell_law(probe.kernel, probe.law, scene.heat_bath, scene.knudsen)
    if closed_forms and scene.quantity == "temperature" and law_t is not None:
        reasons.append("Maxwell molecules with a constant restitution coefficient: "
                       "T(t) is known exactly whatever f0 is (review, eq. (ext_temp))")
        return Advice(scene, None, "granframe.model.exact.heated_maxwell_law", {"total": 0.0}, 0.0, 0,
                      tuple(reasons))
    coldest, hottest, final_t, zeta0, zeta = probe.temperature_history()
    reasons.append(f"Maxwellian closure: T from {probe.t0:.4g} to {final_t:.4g} "
                   f"(range {coldest:.3g} ... {hottest:.3g})")
    rescaled = (scene.heat_bath == 0.0 and probe.law.is_constant and zeta0 > 0.0
                and probe.degree >= 0.0 and coldest < probe.t0 / 4)
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
    states = [(probe.fine_grid, probe.f0)]
    if rescaled:
        states.append(_cooling_state(probe, final))
    support, support_error = _support(probe, hottest, tol / 10, amplification, states)
    grid, resolution_error = _resolution(probe, support, coldest, tol)
    reasons.append(f"S = {support:g} (truncation at R = 2S: <= {tol / 10:.2g} after an "
                   f"amplification {amplification:.3g}); N = {grid.n_modes}: spectral tail x "
                   f"{TAIL_ERROR_FACTOR:g} = {resolution_error:.2g} at T = {coldest:.3g}")
    # what the resolution and the support leave of the tolerance: half to the quadratures,
    # the rest to the time step
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
