r"""Run-time accuracy monitors: indicators of silent drift, checked while a run goes.

The health checks (:func:`granframe.run.runner.health_problem`) stop a run that breaks
down: f not finite, mass lost, f negative. A run can go wrong long before that: with a
sphere rule too coarse for the operator a rescaled Maxwell-molecule run lets its Sonine
coefficient a2 run away while min f / max f stays near -1e-4 (docs/runner.md,
"Accuracy monitors"). The monitors measure what an accurate run must keep, in the run's
own formulation (f, or the profile g of a rescaled run, and its time t or s):

``momentum``
    The shift of the mean velocity in units of the thermal speed,
    :math:`|J(t) - J(0)| / (\rho(0) \sqrt{T(t)})` with :math:`J = \int v f\,dv`. The
    collision operator, the heat bath and the rescaled drift conserve momentum
    exactly; the discrete operator conserves it to its quadrature's accuracy.
``temperature``
    The relative distance of T from its exact law, :math:`|T(t)/T_{law}(t) - 1|`, where
    the run has one (:func:`temperature_law`): Maxwell molecules with a constant e
    (heated or not, :func:`granframe.model.exact.heated_maxwell_law`), elastic
    collisions (:math:`T_0 + 2\tau t` for any kernel: Q conserves energy), and the
    profile g of a rescaled Maxwell-molecule run, whose temperature is stationary
    (a_0 is the exact cooling rate, :mod:`granframe.equations.rescaled`).
``edge_mass``, ``edge_energy``
    The shares of :math:`\int f` and of :math:`\int |v - u|^2 f` beyond the edge
    radius :math:`r_e = 2L - R - S` (:func:`edge_radius`; :math:`\sqrt 2 S` on the
    default box): a velocity there meets velocities of the ball B_S through the
    periodic boundary at a relative speed below the truncation R, so the operators
    make it collide with images that do not exist.
``spectral_tail``
    The error the spectral tail of :math:`\hat f` predicts, ``tail_error`` of
    :func:`granframe.velocity.estimators.resolution_report` (its value, not computed
    again); space-homogeneous runs.
``fields_shell``
    The largest change of a cell's fields (rho, u / sqrt(T), T, q / (rho T^{3/2})) when
    the outermost shell of modes is taken out of f
    (:meth:`granframe.velocity.moments.FieldMoments.resolution`): space runs, where a
    wall's jump of f at v_1 = 0 makes the spectral tail large at every N.

Each is compared with ``health.accuracy_tolerance``; above it the monitor warns and
names the setting to raise (:data:`REMEDIES`); with ``health.stop_on_accuracy`` it
stops the run. The drifts come from the moments the runner computes after every step
(no extra pass over f) and are checked after every step; the edge shares (a pass over
f) and the tail (the resolution report's) at the output points, where the shape of f
is looked at anyway.
"""

from __future__ import annotations

import math

import numpy

from granframe import validators as check
from granframe.model.restitution import is_elastic
from granframe.velocity.estimators import resolution_entry

#: The monitors, in the order they are reported.
MONITORS = ("momentum", "temperature", "edge_mass", "edge_energy", "spectral_tail",
            "fields_shell")

#: What each monitor measures, in words (warnings, ``granframe info``).
MEANINGS = {
    "momentum": "momentum drift |J - J(0)| / (rho(0) sqrt(T))",
    "temperature": "temperature drift |T / T_law - 1|",
    "edge_mass": "share of the mass beyond the edge radius r_e = 2L - R - S = {radius:.4g}",
    "edge_energy": "share of the energy int |v - u|^2 f beyond the edge radius "
                   "r_e = 2L - R - S = {radius:.4g}",
    "spectral_tail": "error predicted by the spectral tail of f-hat",
    "fields_shell": "change of the fields without the outermost shell of modes",
}

#: The setting to raise, per monitor: the operator's quadrature for the drifts (then the
#: time step), the box for the edge shares, the modes for the tail.
REMEDIES = {"momentum": "quadrature", "temperature": "quadrature",
            "edge_mass": "grid.support_radius", "edge_energy": "grid.support_radius",
            "spectral_tail": "grid.n_modes", "fields_shell": "grid.n_modes"}


def edge_radius(grid) -> float:
    r"""r_e = 2L - R - S: the radius beyond which a velocity collides with B_S's images.

    For |v| = r and |v_*| <= S on opposite sides of the box, the nearest periodic image
    of v_* is at distance 2L - r - |v_*| from v; the truncated operators count that
    pair when the distance is below R, i.e. when r > 2L - R - S. On the default box
    (L = (3 + sqrt 2) S / 2, R = 2S) r_e = sqrt(2) S, and f supported in B_S never
    meets an image [Filbet, Pareschi, Toscani 2005].
    """
    return 2.0 * grid.half_width - grid.truncation_radius - grid.support_radius


def edge_shares(grid, f, velocity, radius: float, xp=numpy) -> tuple[float, float]:
    r"""The shares of mass and energy of f beyond ``radius`` around ``velocity`` u:

    .. math:: \frac{\sum_{|v_j - u| > r} f_j}{\sum_j f_j}, \qquad
              \frac{\sum_{|v_j - u| > r} |v_j - u|^2 f_j}{\sum_j |v_j - u|^2 f_j}.

    Signed f, not |f|: the small oscillations of f over the box (the truncation error
    that the spectral tail measures) average out, while a tail that reaches r adds up;
    with |f| they would make the share of the energy, weighted by |v - u|^2 where the
    outer region of the box is large, ten times larger in converged 2D runs.

    NaN where a denominator is not positive (no mass, or no spread about u). For a
    Maxwellian of temperature T centred at u they are Q(d/2, r^2/(2T)) and
    Q(d/2 + 1, r^2/(2T)), Q the regularised upper incomplete gamma function, up to the
    error of counting grid points in a ball (not spectral: 1 % at 3D N = 32, S = 4,
    T = 1.3, r = sqrt(2) S; 0.4 % at N = 48).
    """
    grid.check_shape(f)
    if not check.is_real(radius) or not float(radius) > 0.0:
        check.reject("edge_shares", "radius", radius, "must be a positive real number")
    distance = sum((c - float(ui)) ** 2 for c, ui in zip(grid.mesh(xp), velocity))
    beyond = distance > float(radius) ** 2
    weighted = f * distance
    mass, energy = float(xp.sum(f)), float(xp.sum(weighted))
    return (float(xp.sum(f * beyond)) / mass if mass > 0.0 else math.nan,
            float(xp.sum(weighted * beyond)) / energy if energy > 0.0 else math.nan)


class TemperatureLaw:
    """The exact T of a run's own formulation: ``law(t, T0, rho0)`` and its name in words."""

    def __init__(self, name: str, law):
        self.name, self._law = name, law

    def __call__(self, time, initial_temperature, density):
        return self._law(time, initial_temperature, density)


def temperature_law(description) -> TemperatureLaw | None:
    r"""The exact temperature law of a run in its own formulation, or None.

    - rescaled Maxwell molecules (\lambda = \gamma = 0; any angular part b): the
      dissipation -(1 - e^2) C \beta \rho^2 d T / 4 is proportional to T, so the rate a_0
      the run uses is exact and T_g(s) = T_g(0) (:mod:`granframe.equations.rescaled`);
    - Maxwell molecules with the review's constant, isotropic b and a constant e:
      :func:`granframe.model.exact.heated_maxwell_law` (Haff's exponential law when
      tau = 0);
    - elastic collisions at every speed: Q conserves energy, so
      dT/dt = 2\tau, T = T_0 + 2\tau t, for any kernel.

    Other runs (inelastic hard spheres, a speed-dependent e) have no closed law and no
    temperature monitor.
    """
    from granframe.model.exact import heated_maxwell_law

    kernel, restitution = description.build("kernel"), description.build("restitution")
    if description.rescaled:
        if (getattr(kernel, "is_maxwellian", False)
                and getattr(kernel, "energy_exponent", 0.0) == 0.0):
            return TemperatureLaw("T_g(s) = T_g(0) (rescaled Maxwell molecules: a_0 is the "
                                  "exact cooling rate)",
                                  lambda s, T0, rho0: numpy.full_like(numpy.asarray(
                                      s, dtype=float), T0))
        return None
    law = heated_maxwell_law(kernel, restitution, description.heat_bath, description.knudsen)
    if law is not None:
        return TemperatureLaw("the exact Maxwell-molecule law (granframe.model.exact."
                              "heated_maxwell_temperature)", law)
    if is_elastic(restitution, description.grid):
        tau = description.heat_bath
        return TemperatureLaw("T = T0 + 2 tau t (elastic collisions conserve energy)",
                              lambda t, T0, rho0: T0 + 2.0 * tau * numpy.asarray(t, dtype=float))
    return None


def cooling_hint(description) -> str | None:
    """The hint for a space-homogeneous run that cools freely, or None.

    An inelastic gas without a heat bath cools without bound (Haff's law T ~ t^-2), so f
    narrows on a fixed grid until the grid no longer resolves it; the rescaled formulation
    (:mod:`granframe.equations.rescaled`) follows f in self-similar variables, where it
    keeps its width. A run that is already rescaled, heated, elastic or in space gets no
    hint, nor one the rescaled formulation does not hold for
    (:func:`~granframe.equations.rescaled.check_rescalable`: a speed-dependent e, a
    kernel that is not a power law).
    """
    from granframe.equations.rescaled import check_rescalable

    if description.rescaled or description.heat_bath or description.space is not None:
        return None
    restitution = description.build("restitution")
    if is_elastic(restitution, description.grid):
        return None
    try:
        check_rescalable(description.build("kernel"), restitution, 0.0, "cooling_hint")
    except (ValueError, TypeError):
        return None
    return ("free cooling (inelastic, no heat bath): T falls without bound and f narrows "
            "on the fixed grid until it is no longer resolved; rescaled = true solves it in "
            "self-similar variables, where f keeps its width (docs/stability.md, "
            "\"Concentration under free cooling\")")


def quadrature_settings(operator) -> str:
    """The operator's quadrature settings as a user writes them, with their values."""
    names = [name for name in ("sphere", "radial_points") if hasattr(operator, name)]
    if not names:
        return "the operator's quadrature (operator.*)"
    return " or ".join(f"operator.{name} (now {getattr(operator, name)!r})" for name in names)


class AccuracyMonitors:
    """The monitors of one run: their latest values, the largest so far, the warnings.

    Parameters
    ----------
    description : RunDescription
        Gives the grid, the law (:func:`temperature_law`), ``time_step`` and the health
        options ``accuracy_tolerance`` and ``stop_on_accuracy``.
    operator : CollisionOperator
        Its quadrature settings are named in the warnings.
    initial : dict
        ``mass``, ``momentum`` and ``temperature`` at t = 0 (the first record).
    state : dict or None
        The ``accuracy`` entry of the last commit (:meth:`report`) of a resumed run: the
        largest values and the first flag carry on.
    """

    def __init__(self, description, operator, initial: dict, state: dict | None = None):
        self._start(description, temperature_law(description), state)
        self.mass0 = float(initial["mass"])
        self.momentum0 = numpy.asarray(initial["momentum"], dtype=float)
        self.temperature0 = float(initial["temperature"])
        step = (f"lower time_step (now {description.time_step:g})"
                if description.time_step is not None else "lower tolerance")
        self._remedy["quadrature"] = (f"raise {quadrature_settings(operator)}; if it "
                                      f"persists, {step}")

    def _start(self, description, law, state: dict | None) -> None:
        """The settings of ``description``, the run's ``law``, and the values, largest
        values and first flag of ``state`` (a resumed run's last commit)."""
        health = description.health
        self.grid = description.grid
        self.tolerance = health.accuracy_tolerance
        self.resolution_tolerance = health.resolution_tolerance
        self.stop = health.stop_on_accuracy
        self.law = law
        self.radius = edge_radius(self.grid)
        self._remedy = {"grid.support_radius": f"raise grid.support_radius (now S = "
                                               f"{self.grid.support_radius:g})",
                        "grid.n_modes": f"raise grid.n_modes (now N = {self.grid.n_modes})"}
        state = state or {}
        self.values = {name: math.nan for name in MONITORS}
        self.values.update(state.get("values", {}))
        self.largest = dict(state.get("largest", {}))
        self.flagged = state.get("flagged")
        self._tail_warned = False
        self._under_resolved = False

    # -- measuring --------------------------------------------------------------------
    def drifts(self, record: dict, t: float) -> dict:
        """``momentum`` and (where the run has a law) ``temperature`` from a step's moments."""
        temperature = float(record["temperature"])
        if not temperature > 0.0:       # no thermal speed: the health checks judge such an f
            return {}
        shift = numpy.asarray(record["momentum"], dtype=float) - self.momentum0
        values = {"momentum": float(numpy.sqrt(shift @ shift))
                  / (self.mass0 * math.sqrt(temperature))}
        if self.law is not None:
            exact = float(self.law(t, self.temperature0, self.mass0))
            values["temperature"] = abs(temperature / exact - 1.0)
        return values

    def shape(self, f, record: dict, resolution: dict | None, xp=numpy) -> dict:
        """``edge_mass``, ``edge_energy`` of f and ``spectral_tail`` (from ``resolution``).

        A box so far below the anti-aliasing bound that r_e <= 0 (``allow_aliasing``) has
        no edge monitors: every velocity meets images there.
        """
        values = {}
        if self.radius > 0.0:
            velocity = numpy.asarray(record["momentum"], dtype=float) / float(record["mass"])
            values["edge_mass"], values["edge_energy"] = edge_shares(self.grid, f, velocity,
                                                                     self.radius, xp)
        if resolution is not None:
            values["spectral_tail"] = float(resolution["tail_error"])
            # the resolution report warned of it already (health.resolution_tolerance)
            self._tail_warned = values["spectral_tail"] > self.resolution_tolerance
            self._under_resolved = _names_modes(resolution)
        return values

    def update(self, values: dict, step: int, t: float) -> str | None:
        """Keep ``values``; the stop message when one exceeds the tolerance and the run
        stops on accuracy (:attr:`stop`), else None."""
        exceeded = None
        for name in MONITORS:
            if name not in values or math.isnan(values[name]):
                continue
            value = values[name]
            self.values[name] = value
            if not value <= self.largest.get(name, -math.inf):
                self.largest[name] = value
            if value > self.tolerance and exceeded is None:
                exceeded = name
        if exceeded is None:
            return None
        if self.flagged is None:
            self.flagged = {"monitor": exceeded, "step": int(step), "time": float(t),
                            "value": float(values[exceeded])}
        if self.stop:
            return self.warning(exceeded, values[exceeded])
        return None

    # -- reporting --------------------------------------------------------------------
    def warning(self, name: str, value: float) -> str:
        """One sentence: what drifts, by how much, against which tolerance, what to raise."""
        shown, limit = check.distinct(value, self.tolerance)
        measure = MEANINGS[name].format(radius=self.radius)
        if name == "temperature":
            measure += f" against {self.law.name}"
        remedy = self._remedy[REMEDIES[name]]
        if name.startswith("edge_") and self._under_resolved:
            remedy += (f", and grid.n_modes with it (now N = {self.grid.n_modes}): f is "
                       "under-resolved too, and at a fixed N a wider support coarsens h, "
                       "which can carry its oscillations further out")
        return (f"accuracy: {measure} = {shown} > health.accuracy_tolerance = {limit}; "
                f"{remedy}")

    def warnings(self) -> list[str]:
        """The warnings of the latest values (the tail only when the resolution report did
        not already warn of it)."""
        return [self.warning(name, self.values[name]) for name in MONITORS
                if self.values[name] > self.tolerance
                and not (name in ("spectral_tail", "fields_shell") and self._tail_warned)]

    def report(self) -> dict:
        """The ``accuracy`` entry of a commit (JSON-ready; NaN values left out)."""
        finite = {name: float(v) for name, v in self.values.items() if math.isfinite(v)}
        return {"tolerance": self.tolerance,
                **({"law": self.law.name} if self.law is not None else {}),
                "edge_radius": self.radius, "values": finite,
                "largest": {k: float(v) for k, v in self.largest.items() if math.isfinite(v)},
                **({"flagged": self.flagged} if self.flagged else {}),
                "warnings": self.warnings()}


def describe(entry: dict, time: float) -> list[str]:
    """The lines ``granframe info`` prints for the ``accuracy`` entry of a commit at ``time``."""
    names = [name for name in MONITORS if name in entry.get("values", {})]
    lines = [f"accuracy    at t = {time:g} (the last commit), against health.accuracy_tolerance"
             f" = {entry['tolerance']:g}: "
             + ", ".join(f"{name} {entry['values'][name]:.3g}" for name in names)]
    largest = entry.get("largest", {})
    if largest:
        lines.append("  largest     " + ", ".join(f"{name} {largest[name]:.3g}"
                                                  for name in MONITORS if name in largest))
    if entry.get("law"):
        lines.append(f"  law         {entry['law']}")
    flagged = entry.get("flagged")
    if flagged:
        lines.append(f"  first above the tolerance: {flagged['monitor']} {flagged['value']:.3g} "
                     f"at step {flagged['step']}, t = {flagged['time']:g}")
    lines.extend(f"  warning: {warning}" for warning in entry.get("warnings", ()))
    return lines


def _names_modes(resolution: dict) -> bool:
    """Whether a resolution report warns that N does not resolve f (a warning that says to
    raise grid.n_modes)."""
    return any("raise grid.n_modes" in w for w in resolution.get("warnings", ()))


#: The per-cell indicators of :meth:`granframe.velocity.moments.FieldMoments.resolution`, in
#: its column order.
CELL_INDICATORS = ("spectral_tail", "pairs_beyond_support", "negative_mass_fraction",
                   "heat_flux_shell", "fields_shell")

#: The opening words of each warning of
#: :func:`~granframe.velocity.estimators.resolution_entry`, and its indicator.
_WARNED = {"positivity": "negative_mass_fraction", "support": "pairs_beyond_support"}


def cell_resolution_report(grid, indicators, centres, tolerance: float) -> dict:
    r"""The resolution report of a space run from the indicators of every cell.

    ``indicators`` (cells, 5), the columns of :data:`CELL_INDICATORS`
    (:meth:`~granframe.velocity.moments.FieldMoments.resolution`); ``centres`` the cell
    centres. The report of a space-homogeneous run
    (:func:`~granframe.velocity.estimators.resolution_entry`) is made from the largest
    value of each indicator over the cells, and each warning names the cell it comes from,
    with one difference: the velocity resolution warns on ``fields_shell``, the largest
    change of a cell's fields without the outermost shell of modes (the estimated error
    of the fields on the grid), not on the spectral tail, which a wall's jump of f at
    v_1 = 0 keeps large at every N (docs/space.md, "Resolution indicators of a cell"); it
    names ``grid.n_modes``. Added to the report: ``heat_flux_shell`` and ``fields_shell``
    (their largest values), ``cells``, the index of the worst cell of each indicator;
    ``x``, its centre (``centres`` (cells,) on an interval), or ``position``, its centre
    (x, y) (``centres`` (cells, 2) on a rectangle, the cells in C order). Cells where an
    indicator is NaN (no mass) are left out of its largest value.
    """
    indicators = numpy.asarray(indicators, dtype=float)
    finite = numpy.where(numpy.isfinite(indicators), indicators, -numpy.inf)
    worst = {name: int(numpy.argmax(finite[:, k])) for k, name in enumerate(CELL_INDICATORS)}
    largest = {name: max(float(finite[worst[name], k]), 0.0)
               for k, name in enumerate(CELL_INDICATORS)}
    report = resolution_entry(grid, largest["spectral_tail"],
                              largest["pairs_beyond_support"],
                              largest["negative_mass_fraction"], tolerance)

    centres = numpy.asarray(centres, dtype=float)
    plane = centres.ndim > 1

    def where(name):
        if plane:
            x, y = centres[worst[name]]
            return f" (in cell {worst[name]}, (x, y) = ({x:.4g}, {y:.4g}))"
        return f" (in cell {worst[name]}, x = {float(centres[worst[name]]):.4g})"

    warnings = []
    fields = largest["fields_shell"]
    if fields > tolerance:
        shown, limit = check.distinct(fields, tolerance)
        warnings.append(f"velocity resolution: the outermost shell of modes changes the "
                        f"fields by {shown} (the largest of |d rho|/rho, |d u|/sqrt(T), "
                        f"|d T|/T, |q|/(rho T^(3/2))) > health.resolution_tolerance = "
                        f"{limit}; raise grid.n_modes (N = {grid.n_modes})"
                        + where("fields_shell"))
    warnings += [warning + where(_WARNED[warning.split(":")[0]])
                 for warning in report["warnings"]
                 if warning.split(":")[0] in _WARNED]
    return {**report, "heat_flux_shell": largest["heat_flux_shell"], "fields_shell": fields,
            "warnings": warnings, "cells": worst,
            **({"position": {name: [float(c) for c in centres[i]]
                             for name, i in worst.items()}} if plane else
               {"x": {name: float(centres[i]) for name, i in worst.items()}})}


class CellEdgeMonitors(AccuracyMonitors):
    """The edge monitors of a space run: ``edge_mass`` and ``edge_energy`` of every cell
    (:func:`edge_shares` about the cell's own bulk velocity), the largest over the cells,
    and the ``fields_shell`` of the worst cell (from :func:`cell_resolution_report`).

    The drifts and the temperature law of :class:`AccuracyMonitors` belong to a gas that
    conserves its momentum or follows a law as a whole, which walls break. ``state``: the
    ``accuracy`` entry of the last commit of a resumed run.
    """

    def __init__(self, description, state: dict | None = None):
        self._start(description, None, state)

    def drifts(self, record: dict, t: float) -> dict:
        """None: walls exchange momentum and energy with the gas, so neither is a drift."""
        return {}

    def shape(self, shares, resolution: dict | None = None) -> dict:
        """The largest ``edge_mass`` and ``edge_energy`` over the cells from ``shares``
        (cells, 2), each cell's about its own bulk velocity (computed for every cell at
        once on the backend, :meth:`granframe.velocity.moments.FieldMoments.edge_shares`;
        none when r_e <= 0, ``shares`` None), and ``spectral_tail`` and ``fields_shell``,
        the tail error and the change of the fields of the worst cells of ``resolution``
        (:func:`cell_resolution_report`); the latter is the one that warns."""
        values = {}
        if shares is not None:
            shares = numpy.asarray(shares, dtype=float)
            values = {name: float(numpy.nanmax(column)) if numpy.isfinite(column).any()
                      else math.nan
                      for name, column in zip(("edge_mass", "edge_energy"), shares.T)}
        if resolution is not None:
            values["fields_shell"] = float(resolution["fields_shell"])
            self._tail_warned = values["fields_shell"] > self.resolution_tolerance
            self._under_resolved = _names_modes(resolution)
        return values
