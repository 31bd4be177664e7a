"""The description of a run: what to solve, how, and what to write.

A :class:`RunDescription` is a frozen attrs object; every implementation in
it is a :class:`Component` (a registered name plus its parameters), so it
round-trips through TOML (:meth:`RunDescription.to_toml`,
:meth:`RunDescription.from_toml`) and is stored verbatim in the run's store.
Everything is checked when the description is made, before any file is
written; messages name the parameter, the value and what is allowed.

The description is split by concern: :mod:`granframe.run.components` (:class:`Component`,
its TOML form, :func:`check_component` and the attrs helpers of the fields),
:mod:`granframe.run.space_description` (:class:`Space` and its :class:`Hierarchy`) and this
module (the run's times and their limits, :class:`Output`, :class:`Health` and
:class:`RunDescription`), whose names include those of the other two.

Example (the review's heated Maxwell-molecule test)::

    title = "heated Maxwell molecules"
    final_time = 2.0
    time_step = 0.01
    heat_bath = 0.1

    [grid]
    dimension = 2
    n_modes = 64
    support_radius = 10.0

    [kernel]
    name = "maxwell"

    [restitution]
    name = "constant"
    value = 0.5

    [initial]
    name = "maxwellian"
    temperature = 8.0

    [operator]
    name = "fast_spectral"
    radial_points = 32
    sphere = { name = "circle_trapezoid", n_points = 16 }
"""

from __future__ import annotations

import json
import math
import tomllib

import attrs
import numpy
import tomli_w

from granframe import validators as check
from granframe.abc import PRECISIONS
from granframe.backends import AUTO, resolve_backend
from granframe.velocity.grid import VelocityGrid
from granframe.model.initial import resolve_callable
from granframe.registry import default_registries
from granframe.equations.rescaled import check_rescalable
from granframe.equations.conservative import WEIGHTS as CONSERVATIVE_WEIGHTS
from granframe.space.initial import SpaceCondition
from granframe.run.components import (Component, check_component, coerce_component,
                                      component_field, instance_of, table_of, to_plain)
from granframe.run.space_description import MAX_CELLS, Hierarchy, Space

__all__ = ["COMPONENT_FAMILIES", "LIGHT_COMPONENTS", "MAX_CELLS", "MAX_SNAPSHOTS", "MAX_STEPS",
           "RATE_RANGE", "TIME_RANGE", "TOLERANCE_FLOOR_EPSILONS", "Component", "Health",
           "Hierarchy", "Output", "RunDescription", "Space", "check_component",
           "coerce_component", "component_field", "fixed_steps", "instance_of"]

#: Tolerance on "final_time and snapshot_interval are whole multiples of time_step".
_MULTIPLE_TOLERANCE = 1e-9


def fixed_steps(final_time: float, time_step: float) -> tuple[int, float]:
    """The full steps of a fixed-step run to ``final_time``, and the short last step.

    Returns ``(full, last)``: ``full`` steps of ``time_step`` (step n ends at t = n
    time_step), then, when ``final_time`` is not a whole multiple of ``time_step``, one
    step of ``last`` = final_time - full time_step < time_step that ends at final_time
    exactly (``last`` = 0.0 when there is none), as ODE solvers shorten their last step. A
    ratio within :data:`_MULTIPLE_TOLERANCE` (relative) of a whole number counts as one.
    """
    ratio = final_time / time_step
    if abs(ratio - round(ratio)) <= _MULTIPLE_TOLERANCE * max(1.0, ratio):
        return round(ratio), 0.0
    full = math.floor(ratio)
    return full, final_time - full * time_step

#: Most fixed steps of a run. Every step writes a moment record (about 100 bytes) to the
#: store and takes at least a few operator evaluations (0.1 ms each on the smallest grids),
#: so 1e9 steps are 100 GB of records and days of computing: more is a mistake in
#: final_time or time_step (and it keeps the step counts exact in float64).
MAX_STEPS = 10 ** 9

#: Most snapshots of a run: each stores f (N^d values, 32 KiB at 2D N = 64), and the
#: schedule is a list of output points, so 1e6 snapshots are already 32 GB at that size.
MAX_SNAPSHOTS = 10 ** 6

#: Smallest tolerance of an adaptive integrator, in machine epsilons of the operator's
#: precision: the error estimate is the difference of two solutions of the same
#: precision, each carrying the round-off of the stages and the transforms (tens of
#: epsilons), so a tolerance below 100 eps (2.2e-14 in float64, 1.2e-5 in float32) is
#: met only by accident: steps shrink to round-off or are accepted on noise.
TOLERANCE_FLOOR_EPSILONS = 100

#: Range of the times (final_time, time_step, output.snapshot_interval) and of the
#: tolerance: their sums, ratios and products with the rates below stay finite in float64.
TIME_RANGE = (1e-100, 1e100)

#: Range of the Knudsen number eps and largest heat bath tau: the rates 1/eps and
#: tau |k|^2 times any step of TIME_RANGE stay finite in float64.
RATE_RANGE = (1e-100, 1e100)


def _in(lower: float, upper: float):
    """attrs validator: a finite real number in [lower, upper]."""
    return check.real(lower, upper)


def _optional_in(lower: float, upper: float):
    """attrs validator: None or a finite real number in [lower, upper]."""
    return attrs.validators.optional(check.real(lower, upper))


@attrs.frozen(kw_only=True)
class Output:
    """What is written: f every ``snapshot_interval`` in time (and at the start and end).

    Moments (mass, momentum, temperature, energy, min f, kurtosis, ...) are
    written for every step; they are cheap. ``snapshot_interval = None``
    keeps only the initial and final f.
    """

    snapshot_interval: float | None = attrs.field(default=None, converter=check.to_float,
                                                  validator=_optional_in(*TIME_RANGE))


@attrs.frozen(kw_only=True)
class Health:
    """Limits checked after every step (the run stops with a message) and on f0.

    Parameters
    ----------
    mass_tolerance : float
        Largest |mass(t)/mass(0) - 1|.
    positivity_tolerance : float
        Largest share of negative mass, int max(-f, 0) / int |f|.
    edge_tolerance : float
        Largest f0 on the faces of the box, relative to max f0.
    initial_mass_tolerance : float
        Largest relative error of the grid mass of f0 against its intended mass.
    projection_tolerance : float
        Largest relative change of the mass and temperature of f0 when its Nyquist modes
        are removed (:meth:`VelocityGrid.project`, which the operators need): a larger
        change means f0 is not resolved by the grid. The default 2e-2 lets every shipped
        study run; the largest change among them is 1.4e-2, the discontinuous box of
        review_test1's quick variant at N = 32 (the review's heated Maxwell problem: 3e-14).
    projection_kurtosis_tolerance : float
        The same for the kurtosis. The fourth moment weighs the corners of the box, where
        the Nyquist checkerboard is as large as anywhere, and moves 30 to 100 times more
        than T: 0.55 for that box, 0.32 for review_test3's 3D Maxwellian on the review's
        grid (S = 4); the default 1 lets them run.
    resolution_tolerance : float
        Largest value of each resolution indicator of f at an output point before the run
        warns (:func:`granframe.velocity.estimators.resolution_report`): the error the
        spectral tail predicts, the negative mass share and the share of pairs whose
        relative speed is beyond 2S (the operators cut those off). A warning does not stop
        the run; it is printed when the run ends, kept with each commit and shown by
        ``granframe info``, naming the grid parameter to raise.
    step_limit : bool
        Refuse, before the first step, a fixed time step above the integrator's
        explicit stability limit (:mod:`granframe.stepping.stability`). Set it false only to
        study the instability itself; the step-by-step checks then stop the run.
    accuracy_tolerance : float
        Largest value of each accuracy monitor (:mod:`granframe.run.monitors`) before the
        run warns: the momentum drift |J - J(0)| / (rho(0) sqrt T), the relative distance
        |T / T_law - 1| of the temperature from its exact law (where the run has one),
        the shares of mass and energy beyond the edge radius 2L - R - S, and the error the
        spectral tail predicts. The default 1e-3 is the resolution tolerance's: a
        converged run stays far below it (the heated 2D Maxwell law of the tests holds to
        5e-6), while the run-away of a rescaled 3D Maxwell run with Lebedev 11 passes it
        with a2 1.4 % off (docs/runner.md, "Accuracy monitors"). The warnings are kept with
        each commit and shown by ``granframe info`` and the figures' captions, naming the
        setting to raise.
    stop_on_accuracy : bool
        Stop the run (a failed health check, :class:`~granframe.run.runner.HealthError`)
        when a monitor exceeds ``accuracy_tolerance``, instead of warning.
    """

    mass_tolerance: float = attrs.field(default=1e-8, converter=check.to_float,
                                        validator=check.real(0.0, 1.0, lower_open=True))
    positivity_tolerance: float = attrs.field(default=1e-2, converter=check.to_float,
                                              validator=check.real(0.0, 1.0))
    edge_tolerance: float = attrs.field(default=1e-8, converter=check.to_float,
                                        validator=check.real(0.0, 1.0))
    initial_mass_tolerance: float = attrs.field(default=1e-6, converter=check.to_float,
                                                validator=check.real(0.0, 1.0, lower_open=True))
    resolution_tolerance: float = attrs.field(default=1e-3, converter=check.to_float,
                                              validator=check.real(0.0, 1.0, lower_open=True))
    projection_tolerance: float = attrs.field(default=2e-2, converter=check.to_float,
                                              validator=check.real(0.0, math.inf, lower_open=True))
    projection_kurtosis_tolerance: float = attrs.field(
        default=1.0, converter=check.to_float,
        validator=check.real(0.0, math.inf, lower_open=True))
    step_limit: bool = attrs.field(default=True, validator=check.boolean)
    accuracy_tolerance: float = attrs.field(default=1e-3, converter=check.to_float,
                                            validator=check.real(0.0, 1.0, lower_open=True))
    stop_on_accuracy: bool = attrs.field(default=False, validator=check.boolean)

    def to_dict(self) -> dict:
        """The options as a table; those added after stores began recording them
        (:data:`_LATER_HEALTH`) only when set, so that a store written before them is
        the same description and resumes."""
        return {key: value for key, value in attrs.asdict(self).items()
                if not (key in _LATER_HEALTH
                        and value == attrs.fields_dict(Health)[key].default)}


#: Health options a store written before them does not name (left out at their default).
_LATER_HEALTH = ("accuracy_tolerance", "stop_on_accuracy")


#: The registry family (:mod:`granframe.registry`) of each component of a description.
COMPONENT_FAMILIES = {"kernel": "collision_kernels", "restitution": "restitution_laws",
                      "initial": "initial_conditions", "operator": "collision_operators",
                      "integrator": "time_integrators", "backend": "array_backends"}

#: The components a description builds to validate them: small value objects (their
#: attrs validators are the checks). The operator and the backend are only checked
#: (:func:`check_component`); :class:`~granframe.run.runner.Simulation` builds them.
LIGHT_COMPONENTS = ("kernel", "restitution", "initial", "integrator")


def _conservative_weight(value):
    """``conservative`` as the weight name it means: true -> the default weight, false ->
    None (no correction); anything else is left for :func:`_check_conservative`."""
    if value is True:
        return CONSERVATIVE_WEIGHTS[0]
    return None if value is False else value


def _check_conservative(instance, attribute, value):
    """Refuse a ``conservative`` that is neither None nor a weight name."""
    if value is not None and (not isinstance(value, str) or value not in CONSERVATIVE_WEIGHTS):
        check.reject("RunDescription", attribute.name, value, "must be true, false or a "
                     f"weight name: {', '.join(CONSERVATIVE_WEIGHTS)}")


@attrs.frozen(kw_only=True)
class RunDescription:
    r"""A run of :math:`\partial_t f = Q(f, f)/\varepsilon + \tau \Delta_v f` from f0 to ``final_time``.

    Parameters
    ----------
    grid : VelocityGrid (or a table of its parameters)
    final_time : float
        End of the run (it starts at t = 0). The times (final_time, time_step, the
        snapshot interval) and the tolerance lie in :data:`TIME_RANGE`.
    kernel, restitution, initial : Component
        Registered collision kernel, restitution law and initial condition.
    operator : Component
        Collision operator and its options; an option given as a table with a
        ``name`` is a registered quadrature (e.g. ``sphere``).
    backend : Component
        Array backend; ``auto`` takes pyfftw when installed, else numpy.
    integrator : Component
        Registered time integrator (default ``rk4``, the review's).
    time_step : float or None
        dt of fixed-step integrators (required for them); the first trial step
        of adaptive ones. The snapshot interval must be a whole multiple of it, so
        that outputs fall on steps; a final_time that is not one ends with a shorter
        step (:func:`fixed_steps`).
    tolerance : float or None
        Error tolerance of adaptive integrators (required for them).
    heat_bath : float
        tau >= 0, at most the upper end of :data:`RATE_RANGE`.
    knudsen : float
        epsilon, in :data:`RATE_RANGE`.
    rescaled : bool
        Solve free cooling in self-similar variables (:mod:`granframe.equations.rescaled`):
        the stored f is g(s, xi) and the run's times are the rescaled time s
        (final_time, time_step and the snapshot interval too); the map to the physical
        t and f is stored with the run (``RunStore.metadata["rescaling"]``).
    conservative : bool or str
        Correct Q so that the grid conserves mass and momentum exactly and dissipates
        exactly the energy D(f) of the continuous operator
        (:class:`~granframe.equations.conservative.ConservativeCorrection`). ``true``
        takes the default weight ``"maxwellian"``; a weight name (``"maxwellian"``,
        ``"distribution"``, ``"uniform"``) chooses it; ``false`` (the default) leaves Q
        as the operator computes it. Stored as the weight name. The penalised
        integrators at dt >> eps need it: they amplify Q's energy defect by dt/eps
        (docs/conservative.md).
    output : Output
    health : Health
    title : str
    space : Space or None
        The interval in x of a space-inhomogeneous run (:class:`Space`); None (the
        default) for a space-homogeneous one.
    """

    grid: VelocityGrid = attrs.field(converter=table_of(VelocityGrid),
                                     validator=instance_of(VelocityGrid, "a VelocityGrid"))
    final_time: float = attrs.field(converter=check.to_float, validator=_in(*TIME_RANGE))
    kernel: Component = component_field()
    restitution: Component = component_field()
    initial: Component = component_field()
    operator: Component = component_field(default=Component("fast_spectral"))
    backend: Component = component_field(default=Component(AUTO))
    integrator: Component = component_field(default=Component("rk4"))
    time_step: float | None = attrs.field(default=None, converter=check.to_float,
                                          validator=_optional_in(*TIME_RANGE))
    tolerance: float | None = attrs.field(default=None, converter=check.to_float,
                                          validator=_optional_in(*TIME_RANGE))
    heat_bath: float = attrs.field(default=0.0, converter=check.to_float,
                                   validator=_in(0.0, RATE_RANGE[1]))
    knudsen: float = attrs.field(default=1.0, converter=check.to_float,
                                 validator=_in(*RATE_RANGE))
    rescaled: bool = attrs.field(default=False, validator=check.boolean)
    conservative: str | None = attrs.field(default=None, converter=_conservative_weight,
                                           validator=_check_conservative)
    output: Output = attrs.field(factory=Output, converter=table_of(Output),
                                 validator=instance_of(Output, "an Output table"))
    health: Health = attrs.field(factory=Health, converter=table_of(Health),
                                 validator=instance_of(Health, "a Health table"))
    title: str = attrs.field(default="", validator=instance_of(str, "a string"))
    space: Space | None = attrs.field(default=None, converter=table_of(Space),
                                      validator=attrs.validators.optional(
                                          instance_of(Space, "a Space table")))
    #: what validating built: the light components (:data:`LIGHT_COMPONENTS`), which
    #: :meth:`build` hands out instead of building them again, and the operator's options
    #: (:meth:`operator_options`)
    _light: dict = attrs.field(init=False, factory=dict, eq=False, repr=False)

    def __attrs_post_init__(self):
        self._check_grid()
        check_component("collision_operators", self.operator, grid=None, kernel=None,
                        restitution=None, backend=None)
        precision = self.operator.params.get("precision", "float64")
        if not (isinstance(precision, str) and precision in PRECISIONS):
            check.reject("RunDescription", "operator.precision", precision,
                         f"must be one of {list(PRECISIONS)}")
        check_component("array_backends", Component(resolve_backend(self.backend.name),
                                                    self.backend.params))
        for field in LIGHT_COMPONENTS:
            self._light[field] = self._create(field)
        if self.space is None and isinstance(self._light["initial"], SpaceCondition):
            check.reject("RunDescription", "initial", self.initial.name,
                         "applies to space runs only: add a [space] section (cells, length, "
                         "walls), or use a space-homogeneous initial condition (maxwellian, "
                         "bkw, ...)")
        if self.rescaled:
            check_rescalable(self._light["kernel"], self._light["restitution"],
                             self.heat_bath, "RunDescription")
        # quadratures given as tables are built (cheap), once
        self._light["operator_options"] = {
            key: (default_registries().create("quadratures", **value)
                  if isinstance(value, dict) and "name" in value else value)
            for key, value in self.operator.params.items()}
        self._check_time_stepping(self._light["integrator"].adaptive)
        if self.space is not None:
            self._check_space()
        self.to_dict()  # everything can be written to TOML and a store

    def _check_grid(self):
        """Refuse a truncation radius beyond the largest relative speed on the grid."""
        grid = self.grid
        reach = 2.0 * math.sqrt(grid.dimension) * grid.half_width
        if grid.truncation_radius > reach * (1.0 + 1e-12):
            check.reject("RunDescription", "grid.truncation_radius", grid.truncation_radius,
                         f"must be <= 2 sqrt(d) L = {reach:.6g}, the largest relative speed "
                         f"of two nodes of the box [-L, L]^d (L = grid.half_width = "
                         f"{grid.half_width:.6g}, d = {grid.dimension}): no pair of the grid "
                         "is faster, and the operators' quadratures grow with R")

    def _check_space(self):
        owner = "RunDescription"
        if self._light["integrator"].adaptive:
            check.reject(owner, "integrator", self.integrator.name,
                         "must be a fixed-step integrator in a space run (the transport's "
                         "CFL limit sets the step)")
        if not self.space.collisions and self.heat_bath:
            check.reject(owner, "heat_bath", self.heat_bath, "must be 0 in a collisionless "
                         "run (space.collisions = false solves free transport only)")
        if self.space.hierarchy is not None and self.conservative is None:
            check.reject(owner, "conservative", False,
                         "must be set (true, or a weight) with a space.hierarchy: the levels "
                         "keep every cell's mass and momentum to round-off and its energy to "
                         "the collisions' dissipation, and only the corrected operator does "
                         "so in the cells of the full level (docs/conservative.md)")
        self._light["space"] = self.space.check(self.grid, self.time_step,
                                                self.health.step_limit)
        if self.rescaled:
            self._check_rescaled_space()

    def _check_rescaled_space(self):
        """Refuse a rescaled space run that the self-similar variables do not hold for:
        walls with a temperature or a speed (their scale does not follow omega), a
        collisionless gas (nothing cools), a hierarchy of collision models (its levels
        have no drift), or lambda + 2 gamma > 1 (the transport's speed omega^(kappa - 1)
        xi_1 would grow without bound)."""
        owner = "RunDescription"
        if not self.space.collisions:
            check.reject(owner, "rescaled", True, "needs collisions (space.collisions = "
                         "true): a collisionless gas does not cool")
        if self.space.hierarchy is not None:
            check.reject(owner, "space.hierarchy", "a hierarchy", "must be left out of a "
                         "rescaled run: its fluid and relaxation levels have no "
                         "self-similar drift")
        for side in self.space.sides:
            if not self._light["space"][side].scale_free:
                check.reject(owner, f"space.{side}", getattr(self.space, side).name,
                             "must be a boundary that commutes with the scaling of the "
                             "velocities (periodic, specular) in a rescaled run: a wall with "
                             "a temperature or a speed sets a scale that the self-similar "
                             "variables do not keep")
        kernel = self._light["kernel"]
        degree = kernel.exponent + 2.0 * kernel.energy_exponent
        if degree > 1.0:
            check.reject(owner, "kernel", kernel,
                         f"has lambda + 2 gamma = {degree:g} > 1; a rescaled space run needs "
                         "<= 1 (its transport speed omega^(lambda + 2 gamma - 1) xi_1 would "
                         "grow without bound)")

    def _check_time_stepping(self, adaptive: bool):
        owner, name = "RunDescription", self.integrator.name
        if adaptive and self.tolerance is None:
            check.reject(owner, "tolerance", None,
                         f"is required by the adaptive integrator '{name}' (a positive number)")
        if adaptive:
            precision = self.operator.params.get("precision", "float64")
            epsilon = float(numpy.finfo(precision if precision in PRECISIONS else "float64").eps)
            floor = TOLERANCE_FLOOR_EPSILONS * epsilon
            if self.tolerance < floor:
                check.reject(owner, "tolerance", self.tolerance,
                             f"must be >= {floor:.3g} ({TOLERANCE_FLOOR_EPSILONS} machine "
                             f"epsilons of the operator's {precision}): a smaller error is "
                             "below round-off and cannot be controlled")
        interval = self.output.snapshot_interval
        if interval is not None and interval > self.final_time:
            check.reject(owner, "output.snapshot_interval", interval,
                         f"must be <= final_time = {self.final_time!r}")
        if not adaptive:
            if self.time_step is None:
                check.reject(owner, "time_step", None,
                             f"is required by the fixed-step integrator '{name}'")
            if not self.final_time / self.time_step <= MAX_STEPS:
                check.reject(owner, "final_time", self.final_time,
                             f"must be at most {MAX_STEPS:.0e} steps of time_step = "
                             f"{self.time_step!r} (it is {self.final_time / self.time_step:.3g} "
                             "steps); check final_time and time_step")
            if self.tolerance is not None:
                check.reject(owner, "tolerance", self.tolerance,
                             f"applies to adaptive integrators only, not to '{name}'")
            # final_time need not be a multiple: the last step is shortened (fixed_steps).
            # Snapshot times must be step ends: shortening a step before each of them
            # would make the solution depend on the output schedule.
            if interval is not None:
                whole, rest = fixed_steps(interval, self.time_step)
                if whole < 1 or rest:
                    ratio = interval / self.time_step
                    whole = max(1, round(ratio))
                    check.reject(owner, "snapshot_interval", interval,
                                 f"must be a whole multiple (>= 1) of time_step = "
                                 f"{self.time_step!r} (ratio {ratio:.12g}), so that snapshots "
                                 f"fall on step ends and the output schedule never changes "
                                 f"the steps; e.g. {whole * self.time_step:.12g}")
        if interval is not None and not self.final_time / interval <= MAX_SNAPSHOTS:
            check.reject(owner, "output.snapshot_interval", interval,
                         f"must give at most {MAX_SNAPSHOTS:.0e} snapshots up to final_time = "
                         f"{self.final_time!r} (it gives {self.final_time / interval:.3g})")

    # -- building ---------------------------------------------------------------------
    def build(self, field: str, **extra):
        """The registered implementation of ``field`` (kernel, restitution, initial, ...).

        The light components (:data:`LIGHT_COMPONENTS`) were built while validating and
        are handed out as they are (they are immutable); the operator and the backend are
        built by each call (:class:`~granframe.run.runner.Simulation` makes the one call).
        """
        if field in self._light and not extra:
            return self._light[field]
        return self._create(field, **extra)

    def _create(self, field: str, **extra):
        component = getattr(self, field)
        params = dict(component.params)
        if field == "kernel" and isinstance(params.get("angular"), str):
            params["angular"] = resolve_callable("kernel", "angular", params["angular"])
        if field == "operator":
            params = self.operator_options()
        if field == "backend":
            return default_registries().create("array_backends",
                                               resolve_backend(component.name), **params)
        return default_registries().create(COMPONENT_FAMILIES[field], component.name, **params,
                                           **extra)

    def operator_options(self) -> dict:
        """The operator's options, tables with a ``name`` as the registered quadratures
        built while validating."""
        return dict(self._light["operator_options"])

    # -- TOML / dict ------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON- and TOML-ready nested dict (None values, and ``rescaled = false``, left out)."""
        data = {"title": self.title, "final_time": self.final_time, "time_step": self.time_step,
                "tolerance": self.tolerance, "heat_bath": self.heat_bath,
                "knudsen": self.knudsen, "rescaled": self.rescaled or None,
                "conservative": self.conservative,
                "grid": attrs.asdict(self.grid),
                **{field: getattr(self, field).to_dict(field) for field in COMPONENT_FAMILIES},
                "output": attrs.asdict(self.output), "health": self.health.to_dict(),
                **({} if self.space is None else {"space": self.space.to_dict()})}
        return json.loads(json.dumps(to_plain("RunDescription", "description", data)))

    @classmethod
    def from_dict(cls, data: dict) -> "RunDescription":
        if not isinstance(data, dict):
            check.reject("RunDescription", "description", data, "must be a table",
                         error=TypeError)
        return check.from_table(cls, data, "RunDescription")

    def to_toml(self) -> str:
        return tomli_w.dumps(self.to_dict())

    @classmethod
    def from_toml(cls, text: str) -> "RunDescription":
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"RunDescription: the TOML text is invalid: {exc}") from None
        return cls.from_dict(data)

    def replace(self, **changes) -> "RunDescription":
        """A copy with some parameters changed (validated again)."""
        return attrs.evolve(self, **changes)
