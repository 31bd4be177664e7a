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

The probe of a scene and the choices of rules 1 and 3 to 8 are in
:mod:`granframe.tools.advise_numerics`, the record of a space run's price in
:mod:`granframe.tools.advise_price`; this module proposes the run and prices it.
"""

from __future__ import annotations

import functools
import math
import typing

import attrs
import numpy

from granframe import validators as check
from granframe.run.description import (COMPONENT_FAMILIES, Component, Hierarchy,
                                       RunDescription, Space, component_field)
from granframe.velocity.estimators import TAIL_ERROR_FACTOR
from granframe.model.exact import heated_maxwell_law
from granframe.velocity.grid import VelocityGrid
from granframe.theory.euler import euler_riemann_star
from granframe.space.initial import RiemannProblem, SpaceCondition
from granframe.registry import default_registries
from granframe.tools.advise_numerics import (Probe, choose_modes, choose_quadrature,
                                             choose_support, choose_time_step, cooling_state,
                                             health_table, mass_drift_bound)
from granframe.tools.advise_price import HierarchyPrice

QUANTITIES = ("temperature", "distribution")
#: loosest tolerance float32 is considered for (its measured floor against an exact solution
#: is 4.3e-6, on BKW 2D: docs/accuracy-vs-cost.md, "float32")
FLOAT32_TOLERANCE = 1e-4
#: the space price's timings: medians of this many, each after one warm-up call
SPACE_REPEATS = 5
#: the largest batch of cells each collision model is timed on (and a batch of one)
BATCH_CELLS = 8


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
        if value.dimension > 1:
            check.reject("Scene", "space.cells", list(value.cells), "must be one number: advise "
                         "prices runs on an interval, not yet on a rectangle (its hierarchy "
                         "and its costs per axis are not modelled); use granframe limits for "
                         "the step limits and the estimated cost of a run on a rectangle")
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
    space: HierarchyPrice | None = None

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


def evaluation_seconds(problem, repeats: int = 7) -> float:
    """Median seconds of one evaluation of a problem's right-hand side on f0 (the
    collision operator, and the drift of a rescaled run), after two warm-up evaluations,
    timed by the backend (:func:`granframe.tools.bench.median_time`)."""
    from granframe.tools.bench import median_time

    f = problem.backend.asarray(problem.f0)

    def evaluate():
        problem.equation.nonlinear(0.0, f)

    for _ in range(2):
        evaluate()
    return median_time(evaluate, repeats, problem.backend)


def _time_evaluation(description) -> float:
    """:func:`evaluation_seconds` of a description."""
    from granframe.run.runner import Simulation

    return evaluation_seconds(Simulation(description).problem)


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
    probe = Probe(scene, array_backend)
    reasons = []
    law_t = heated_maxwell_law(probe.kernel, probe.law, scene.heat_bath, scene.knudsen)
    if (closed_forms and scene.space is None and scene.quantity == "temperature"
            and law_t is not None):
        reasons.append("Maxwell molecules with a constant restitution coefficient: "
                       "T(t) is known exactly whatever f0 is (review, eq. (ext_temp))")
        return Advice(scene, None, "granframe.model.exact.heated_maxwell_law", {"total": 0.0},
                      0.0, 0, tuple(reasons))
    span = _temperature_span(probe, reasons)
    grid_table, operator, errors = _velocity_discretisation(probe, span, reasons)
    if scene.space is not None:
        errors["total"] = sum(errors.values())
        return _advise_space(scene, {"grid": grid_table, "operator": operator,
                                     "backend": backend_name, **scene.physics()},
                             errors, reasons)
    base = {"final_time": span.final, "time_step": span.final, "grid": grid_table,
            "operator": operator, "backend": backend_name, "rescaled": span.rescaled,
            **scene.physics(), "health": {"step_limit": False}}
    return _advise_homogeneous(probe, span, base, errors, reasons)


class _Span(typing.NamedTuple):
    """What the temperature history of a scene sets (:func:`_temperature_span`)."""

    #: the temperature range the grid must hold
    coldest: float
    hottest: float
    #: the final time of the run (the rescaled time s of a rescaled run)
    final: float
    #: the time over which an error in the rate acts on the quantity, and how much it grows
    horizon: float
    amplification: float
    #: whether the run is rescaled (rule 2)
    rescaled: bool


def _temperature_span(probe, reasons: list) -> _Span:
    """Rules 1 and 2: the temperature range of the Maxwellian closure (widened to the cells,
    waves and walls of a space scene), the formulation, and the horizon over which an error
    in the rate acts, with its amplification; each choice said in ``reasons``."""
    scene = probe.scene
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
    return _Span(coldest, hottest, final, horizon, amplification, rescaled)


def _velocity_discretisation(probe, span: _Span, reasons: list) -> tuple[dict, dict, dict]:
    """Rules 3 to 5: the support, the modes and the quadratures, as the ``grid`` and
    ``operator`` tables of a description, and their predicted errors (``resolution``,
    ``support``, ``quadrature``); each choice said in ``reasons``."""
    tol = probe.scene.tolerance
    states = [(probe.fine_grid, probe.f0)] + [
        (probe.fine_grid, probe.fine_grid.maxwellian(rho, u, temperature))
        for rho, u, temperature in probe.star_states]
    if span.rescaled:
        states.append(cooling_state(probe, span.final))
    support, support_error = choose_support(probe, span.hottest, tol / 10, span.amplification,
                                            states)
    grid, resolution_error = choose_modes(probe, support, span.coldest, tol)
    reasons.append(f"S = {support:g} (truncation at R = 2S: <= {tol / 10:.2g} after an "
                   f"amplification {span.amplification:.3g}); N = {grid.n_modes}: spectral "
                   f"tail x {TAIL_ERROR_FACTOR:g} = {resolution_error:.2g} at T = "
                   f"{span.coldest:.3g}")
    # what the resolution and the support leave of the tolerance: half to the quadratures,
    # the rest to the time step (in a space run: to x, the splitting and time, unpredicted)
    radial, size, quadrature_error = choose_quadrature(
        probe, grid, span.coldest, (tol - resolution_error - support_error) / 2, span.horizon)
    rule = f"M = {size}" if probe.d == 2 else f"Lebedev {size}"
    reasons.append(f"N_rho = {radial}, {rule}: operator error x horizon {span.horizon:.3g} = "
                   f"{quadrature_error:.2g}")
    operator = {"name": "fast_spectral", "radial_points": radial,
                "sphere": ({"name": "circle_trapezoid", "n_points": size} if probe.d == 2
                           else {"name": "lebedev", "order": size})}
    grid_table = {"dimension": probe.d, "n_modes": grid.n_modes, "support_radius": support}
    return grid_table, operator, {"resolution": resolution_error, "support": support_error,
                                  "quadrature": quadrature_error}


def _advise_homogeneous(probe, span: _Span, base: dict, errors: dict, reasons: list) -> Advice:
    """The proposal for a space-homogeneous scene: rules 6 (the time step) and 7 (the
    precision) on the description ``base``, whose discretisation in velocity has the
    predicted ``errors``."""
    scene, tol, final = probe.scene, probe.scene.tolerance, span.final
    description = RunDescription.from_dict(base)
    dt, integrator, time_error = choose_time_step(description, probe, final, span.horizon,
                                                  tol - errors["resolution"] - errors["support"]
                                                  - errors["quadrature"])
    steps = max(1, math.ceil(final / dt - 1e-9))
    dt = final / steps
    reasons.append(f"{integrator}, dt = {dt:.4g} ({steps} steps; RK4 error by step doubling "
                   f"{time_error:.2g})")
    # the collision times the run spans: the mass round-off of the operator acts over them
    collision_times = probe.collision_frequency(span.hottest) / scene.knudsen * steps * dt
    operator = base["operator"]

    def proposal(precision):
        """The description in ``precision``; the moments (temperature) are written every
        step, f at the start and the end."""
        return RunDescription.from_dict(
            {**base, "final_time": steps * dt, "time_step": dt, "integrator": integrator,
             "operator": (operator if precision == "float64"
                          else {**operator, "precision": precision}),
             "health": health_table(precision, collision_times)})

    description, seconds = _precision(proposal, tol, collision_times, reasons)
    errors["time"] = time_error
    errors["total"] = sum(errors.values())
    return Advice(scene, description, None, errors, seconds, 4 * steps, tuple(reasons))


def _precision(proposal, tol: float, collision_times: float, reasons: list):
    """Rule 7: (description, seconds per evaluation) of ``proposal("float64")``, or of
    ``proposal("float32")`` where the tolerance and the mass drift over ``collision_times``
    allow float32 and it is measured faster here."""
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
    return description, seconds


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


def _swept_levels(description, levels):
    """The levels at the final time t_f of a run from a ``riemann`` initial condition,
    estimated: every cell the waves of the Euler Riemann problem (the limit eps -> 0,
    gamma = (d + 2)/d; :func:`granframe.theory.euler.euler_riemann_star`) have swept by then,
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
    models (:class:`~granframe.tools.advise_price.HierarchyPrice` gives the formulas).

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

    priced = _priced(description, repeats)
    problem = make_problem(priced, communicator=SerialCommunicator())
    hybrid = problem.hierarchy
    f0 = problem.backend.asarray(problem.f0)
    hybrid.measure(f0)
    hybrid.choose()

    def count(levels):
        return tuple(int(numpy.count_nonzero(levels == k)) for k in range(len(hybrid.models)))

    swept = _swept_levels(priced, hybrid.levels)
    counts, final = count(hybrid.levels), None if swept is None else count(swept)
    cells = description.space.cells
    batch = min(cells, BATCH_CELLS)
    transport_seconds, level_seconds, measure_seconds, choose_seconds = _timings(
        problem, f0, priced.time_step, cells, batch, repeats)
    return HierarchyPrice(description, priced, counts, transport_seconds, level_seconds,
                          measure_seconds, choose_seconds, batch, repeats, final)


def _priced(description, repeats):
    """The run :func:`price_hierarchy` prices: ``description`` (checked) with its hierarchy,
    or with the default one and ``conservative`` set when it has none."""
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
    if description.rescaled:
        check.reject("advise", "rescaled", True, "must be false to price a hierarchy of "
                     "collision models, which a rescaled run cannot take (its fluid levels "
                     "have no self-similar drift); run_cost prices the rescaled run as it is "
                     "(granframe advise does so for a rescaled description)")
    if space.hierarchy is not None:
        return description
    data = description.to_dict()
    data["space"]["hierarchy"] = Hierarchy().to_dict()
    data["conservative"] = description.conservative or True
    return RunDescription.from_dict(data)


def _timings(problem, f0, dt, cells, batch, repeats):
    """(transport_seconds, level_seconds, measure_seconds, choose_seconds) of
    :class:`~granframe.tools.advise_price.HierarchyPrice`, measured on the problem built
    for the run and its f0 on the backend (:func:`price_hierarchy`)."""
    backend, hybrid = problem.backend, problem.hierarchy
    picks = backend.xp.asarray(numpy.round(numpy.linspace(0, cells - 1, batch))
                               .astype(numpy.int64))
    one, many = f0[picks[:1]], f0[picks]
    state = problem.state(problem.f0)

    def transport():
        problem.integrator.transport_stage(state, 0.0, 0.5 * dt)
        problem.integrator.transport_stage(state, 0.5 * dt, 0.5 * dt)

    level_seconds = tuple(
        _affine(_median_seconds(functools.partial(model.advance, one, 0.0, dt), repeats,
                                backend),
                _median_seconds(functools.partial(model.advance, many, 0.0, dt), repeats,
                                backend), batch)
        for model in hybrid.models)
    transport_seconds, measure_seconds, choose_seconds = (
        _median_seconds(function, repeats, backend)
        for function in (transport, functools.partial(hybrid.measure, f0), hybrid.choose))
    return transport_seconds, level_seconds, measure_seconds, choose_seconds
