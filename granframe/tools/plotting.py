"""Figures of a run: plotting functions on the xarray Dataset of a run store.

Each function takes the Dataset of a run store (``xarray.open_zarr(path)``, or
``granframe.open_run(path)``) and an optional matplotlib ``ax`` to draw into; without one
it makes a figure captioned with the run's parameters (:func:`caption`). Each returns the
axes it drew into. Every quantity granframe computes is dimensionless (the scaling of
the run description), and every axis label says so.

``granframe plot STORE --out DIR`` (:func:`plot`) checks the store's checksums, composes
the functions into five figures (:func:`figures`) and writes them as PNG, PDF or SVG:

- ``temperature``: T(t) with the exact law where one exists, and the relative error
  against it (otherwise the mass drift);
- ``entropy``: relative entropy of f(t) to the exact equilibrium where one is known
  (elastic collisions without a heat bath: the Maxwellian of the conserved moments),
  otherwise to the last snapshot, which the figure says makes it zero at t_end by
  construction;
- ``slices``: f(v1, 0, ...) at five times with a marker at each grid point, linear and
  logarithmic (-f where f < 0 as open markers);
- ``contour``: f in the (v1, v2) plane (through v3 = 0 in 3D), first and last snapshot,
  filled from f = 0 up, with f < 0 in grey;
- ``moments``: mass drift, kurtosis against the Maxwellian value, and the negative share
  of f on a log axis against the positivity health limit.

A space run (a description with a ``space`` section) has fields per cell instead, and
three figures of its own:

- ``maps``: x-t maps (:func:`field_map`) of the density rho, the bulk velocity u_1, the
  temperature T, the pressure P_11 and the heat flux q_1, cell by cell and step by step;
- ``profiles``: the same five fields against x (:func:`profiles`) at five of the
  snapshot times, a marker at each cell centre;
- ``totals``: the total mass and energy against t with what entered through the walls
  (:func:`total_mass`, :func:`total_energy`) and the negative share of f
  (:func:`positivity`).

A space run with a hierarchy of collision models (``space.hierarchy``) has a fourth:

- ``levels``: the x-t map of each cell's collision model (:func:`level_map`), the share
  of the cells at each level against t (:func:`level_shares`), and x-t maps of the two
  indicators that chose the levels (:func:`indicator_map`).
"""

from __future__ import annotations

import math
import pathlib
import textwrap

import numpy
import xarray
from matplotlib import colormaps, ticker
from matplotlib.colors import BoundaryNorm, LogNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from granframe import validators as check
from granframe.equations.rescaled import Rescaling
from granframe.model.exact import heated_maxwell_law
from granframe.run.dataset import committed
from granframe.run.description import RunDescription
from granframe.run.storage import RunStore, StoreDamagedError, summarise
from granframe.tools.analysis import relative_entropy

#: Largest max|f(t_end) - f(t_end - interval)| / max f for which f(t_end) is taken as f_infinity.
STATIONARY = 1e-6

#: File formats ``granframe plot --format`` writes.
FORMATS = ("png", "pdf", "svg")

#: Smallest and largest resolution, in dots per inch, of the raster parts of a figure.
DPI_RANGE = (10, 600)

#: Resolution of ``granframe plot`` unless ``--dpi`` says otherwise.
DEFAULT_DPI = 110

_TIME = "time t (dimensionless)"

_STYLE = {"axes.grid": True, "grid.alpha": 0.3, "font.size": 10, "axes.titlesize": 10,
          "legend.fontsize": 8}

#: Figure name -> (rows, columns), size in inches.
_LAYOUTS = {"temperature": ((1, 2), (11, 4.4)), "entropy": ((1, 1), (8, 5.2)),
            "slices": ((1, 2), (11, 4.4)), "contour": ((1, 2), (11, 5.8)),
            "moments": ((1, 3), (14, 4.2)), "maps": ((2, 3), (15, 8.6)),
            "profiles": ((2, 3), (15, 8.2)), "totals": ((1, 3), (14, 4.2)),
            "levels": ((2, 2), (11, 8.6))}

#: The fields of a space run that :func:`field_map` and :func:`profiles` draw: name ->
#: (stored array, component index, symbol, words, signed).
SPACE_FIELDS = {
    "density": ("density", (), r"$\rho$", "density", False),
    "velocity": ("velocity", (0,), r"$u_1$", "bulk velocity", True),
    "temperature": ("temperature", (), "$T$", "temperature", False),
    "pressure": ("pressure_tensor", (0, 0), r"$P_{11}$", "pressure", False),
    "heat_flux": ("heat_flux", (0,), r"$q_1$", "heat flux", True),
}

#: The totals a space run records after every step (integrals over x and v).
_SPACE_TOTALS = ("mass", "kinetic_energy", "min_f", "negative_mass_fraction")

#: The indicators of a hierarchy of collision models that :func:`indicator_map` draws:
#: stored array -> (symbol, words).
LEVEL_INDICATORS = {
    "realizability": (r"$\kappa$", "Navier-Stokes realizability"),
    "distance": (r"$\delta$", "distance from the local Maxwellian"),
}

#: The colour scale of :func:`indicator_map` starts at this share of the lowest threshold;
#: smaller values take its lowest colour.
INDICATOR_FLOOR = 1e-3


def _attribute(ds, name):
    """A run store's attribute ``name``, or None.

    Looked up at the top of ``ds.attrs``, then in its ``granframe`` entry (the metadata
    ``xarray.open_zarr`` shows), then as the flat attributes ``<name>_<key>`` that
    ``granframe.open_run`` gives for a table (``progress_records``, ``rescaling_rate``),
    returned as a table.
    """
    if name in ds.attrs:
        return ds.attrs[name]
    meta = ds.attrs.get("granframe")
    if isinstance(meta, dict) and name in meta:
        return meta[name]
    prefix = name + "_"
    flat = {key[len(prefix):]: value for key, value in ds.attrs.items()
            if key.startswith(prefix)}
    return flat or None


def _open(path) -> xarray.Dataset:
    """The Dataset of the store at ``path``, cut to its last commit, once every committed
    chunk passed its checksum."""
    store = RunStore.open(path, complete=False)
    problems = store.verify()
    if problems:
        raise StoreDamagedError(f"plot: store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    return committed(store)


class _Run:
    """What the figures read from the Dataset of a run store (or from a store's path).

    Records and snapshots are trimmed to the committed ones; a rescaled run's times and
    temperatures are converted to physical ones (f stays the profile g).
    """

    def __init__(self, data):
        name = None
        if not isinstance(data, xarray.Dataset):
            name = pathlib.Path(data).name
            data = _open(data)
        text = _attribute(data, "description_toml")
        if not isinstance(text, str):
            check.reject("plot", "ds", type(data).__name__,
                         "must be the Dataset of a granframe run store (an attribute "
                         "'description_toml' with the run description)", error=TypeError)
        progress = _attribute(data, "progress") or {}
        trim = {dim: slice(0, int(progress[key])) for dim, key in
                (("step_time", "records"), ("time", "snapshots")) if key in progress}
        self.ds = data.isel(trim)
        self.count = self.ds.sizes["time"]
        if self.count == 0:
            raise ValueError(f"plot: {'store ' + repr(name) if name else 'the dataset'} "
                             "has no snapshot yet")
        self.description = RunDescription.from_toml(text)
        self.title = self.description.title or name or "untitled run"
        self.grid = self.description.grid
        #: the description's space section; None for a space-homogeneous run
        self.space = getattr(self.description, "space", None)
        hierarchy = None if self.space is None else self.space.hierarchy
        #: the names of the levels of a hierarchy of collision models, cheapest first;
        #: None without one
        self.levels = None if hierarchy is None else [level.name for level in hierarchy.levels]
        self.status = progress.get("status")
        # the resolution warnings of the last commit: nested in the store's metadata, flat
        # (resolution_warnings) in granframe.open_run's attributes
        warnings = (progress.get("resolution") or {}).get("warnings",
                                                           progress.get("resolution_warnings"))
        self.warnings = [warnings] if isinstance(warnings, str) else list(warnings or ())
        # the same for the accuracy monitors' warnings (granframe.run.monitors)
        accuracy = (progress.get("accuracy") or {}).get("warnings",
                                                         progress.get("accuracy_warnings"))
        self.accuracy_warnings = ([accuracy] if isinstance(accuracy, str)
                                  else list(accuracy or ()))
        self.step_time = self.ds["step_time"].values
        self.moments = {key: self.ds[key].values for key in
                        (_SPACE_TOTALS if self.space is not None else
                         ("mass", "temperature", "kurtosis", "min_f", "negative_mass_fraction"))}
        self.times = self.ds["time"].values
        self.axes = [self.ds[f"v{i + 1}"].values for i in range(self.grid.dimension)]
        self.rescaled = _attribute(data, "rescaling") is not None
        if self.rescaled:
            law = Rescaling(**_attribute(data, "rescaling"))
            self.moments["temperature"] = law.temperature(self.step_time,
                                                          self.moments["temperature"])
            self.step_time = law.physical_time(self.step_time)
            self.times = law.physical_time(self.times)
            self.title += " (rescaled; f shown as the profile g)"
        #: the names of f and of the velocity in the figures: g and xi for a rescaled run
        self.f_name, self.v_name = ("g", "ξ") if self.rescaled else ("f", "v")
        self._extremes = None

    @classmethod
    def of(cls, data) -> "_Run":
        return data if isinstance(data, cls) else cls(data)

    def snapshot(self, index):
        return numpy.asarray(self.ds["f"].isel(time=index).values)

    def plane(self, index):
        """f in the (v1, v2) plane (through the middle of v3 in 3D)."""
        f = self.snapshot(index)
        return f if f.ndim == 2 else f[:, :, self.grid.n_modes // 2]

    def line(self, index):
        """f along v1 with the other components at the grid point v = 0."""
        f = self.snapshot(index)
        middle = self.grid.n_modes // 2
        return f[(slice(None),) + (middle,) * (f.ndim - 1)]

    def extremes(self):
        """(max f, min f) of every snapshot, read once."""
        if self._extremes is None:
            values = [(float(f.max()), float(f.min()))
                      for f in map(self.snapshot, range(self.count))]
            self._extremes = numpy.array(values).T
        return self._extremes

    def exact_temperature(self):
        d = self.description
        law = heated_maxwell_law(d.build("kernel"), d.build("restitution"), d.heat_bath,
                                 d.knudsen)
        if law is None:
            return None
        return law(self.step_time, self.moments["temperature"][0], self.moments["mass"][0])

    def equilibrium(self):
        """The exact equilibrium on the grid, or None where none is known.

        Elastic collisions (e = 1 at every speed) without a heat bath conserve mass,
        momentum and energy, and f tends to the Maxwellian of those moments of f(0).
        """
        d = self.description
        law = d.build("restitution")
        speeds = numpy.linspace(0.0, self.grid.truncation_radius, 65)
        if self.rescaled or d.heat_bath != 0.0 or not numpy.all(law(speeds) == 1.0):
            return None
        f0 = self.snapshot(0)
        return self.grid.maxwellian(density=self.grid.mass(f0),
                                    velocity=self.grid.bulk_velocity(f0),
                                    temperature=self.grid.temperature(f0))

    def snapshot_indices(self, count=5):
        return sorted(set(numpy.linspace(0, self.count - 1, min(count, self.count))
                          .round().astype(int)))

    def field(self, name):
        """The field ``name`` of :data:`SPACE_FIELDS` of a space run, (step_time, x)."""
        array, component = SPACE_FIELDS[name][:2]
        values = self.ds[array].values
        return values[(slice(None), slice(None)) + component]

    def homogeneous(self, owner):
        """Refuse a space run in the plotting function ``owner`` (drawn from f(v))."""
        if self.space is not None:
            check.reject(owner, "ds", self.title,
                         "must be a space-homogeneous run; a space run is drawn by "
                         "field_map, profiles, total_mass, total_energy and positivity "
                         "(with a hierarchy also level_map, level_shares and "
                         "indicator_map)")

    def inhomogeneous(self, owner):
        """Refuse a space-homogeneous run in the plotting function ``owner``."""
        if self.space is None:
            check.reject(owner, "ds", self.title,
                         "must be a space run (a description with a space section)")

    def hierarchical(self, owner):
        """Refuse a run without a hierarchy of collision models in the plotting function
        ``owner``."""
        self.inhomogeneous(owner)
        if self.levels is None:
            check.reject(owner, "ds", self.title, "must be a space run with a hierarchy of "
                                                  "collision models (space.hierarchy)")


def _component(component) -> str:
    """A component as ``name(key=value, ...)``, nested tables with a name the same way."""
    if isinstance(component, dict) and "name" in component:
        params = {k: v for k, v in component.items() if k != "name"}
        name = component["name"]
    else:
        name, params = component.name, component.params
    if not params:
        return name
    shown = ", ".join(f"{key}={_component(value) if isinstance(value, dict) else value}"
                      for key, value in params.items())
    return f"{name}({shown})"


def _wrapped(text: str, width: int = 110) -> str:
    """``text`` with every line longer than ``width`` characters broken at spaces, so that a
    figure's caption (a long warning above all) stays within the figure."""
    return "\n".join(textwrap.fill(line, width) if len(line) > width else line
                     for line in text.splitlines())


def caption(ds) -> str:
    """The caption of every figure of a run, from its stored description.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.

    Returns
    -------
    str
        Four lines: the run's title (and its status unless finished); the dimension, N,
        dt and integrator, heat bath tau and Knudsen number; the operator (then, for a
        space run, its cells, reconstruction and walls); the
        restitution law e and the kernel exponent lambda, and that every quantity is
        dimensionless. Then one line per resolution warning of the last commit
        (:func:`granframe.velocity.estimators.resolution_report`) and one per accuracy
        warning (:mod:`granframe.run.monitors`), each naming what to raise.
    """
    run = _Run.of(ds)
    d, grid = run.description, run.grid
    integrator = d.build("integrator")
    if getattr(integrator, "adaptive", False):
        steps = run.ds["dt"].values[1:]
        dt = (f"dt = {steps.min():.3g}..{steps.max():.3g} (adaptive {d.integrator.name}, "
              f"tolerance {d.tolerance:g})" if steps.size else
              f"dt adaptive ({d.integrator.name}, tolerance {d.tolerance:g})")
    else:
        dt = f"dt = {d.time_step:g} ({_component(d.integrator)})"
    kernel = d.build("kernel")
    exponent = getattr(kernel, "exponent", kernel.speed_exponent)
    energy = getattr(kernel, "energy_exponent", 0.0)
    status = "" if run.status in (None, "finished") else f" -- run status: {run.status}"
    return "\n".join([
        f"{run.title}{status}",
        f"{grid.dimension}D, N = {grid.n_modes}, R = {grid.truncation_radius:g}, "
        f"L = {grid.half_width:.4g}; {dt}; heat bath τ = {d.heat_bath:g}, "
        f"Knudsen number ε = {d.knudsen:g}",
        f"operator {_component(d.operator)}",
        *([_space_line(d.space)] if d.space is not None else []),
        f"restitution e: {_component(d.restitution)}; kernel {_component(d.kernel)}, "
        f"exponent λ = {exponent:g}" + (f", energy exponent γ = {energy:g}" if energy else "")
        + "; all quantities dimensionless"]
        + [f"UNDER-RESOLVED: {warning}" for warning in run.warnings]
        + [f"INACCURATE: {warning}" for warning in run.accuracy_warnings])


def _space_line(space) -> str:
    """The caption line of a space run: its interval, cells, reconstruction and walls."""
    collisions = "" if space.collisions else "; collisionless (free transport)"
    return (f"space: {space.cells} cells on [0, {space.length:g}] "
            f"(dx = {space.length / space.cells:.4g}), reconstruction "
            f"{_component(space.reconstruction)}, walls: left {_component(space.left)}, "
            f"right {_component(space.right)}{collisions}")


def _axes(ax, run):
    """``ax``, or the axes of a new figure captioned with the run's parameters."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.8), layout="constrained")
    fig.suptitle(_wrapped(caption(run)), fontsize=8)
    return ax


def _positive(values):
    """``values`` with its zeros and negative entries left out (for a logarithmic axis)."""
    values = numpy.asarray(values, dtype=float)
    return numpy.where(values > 0, values, numpy.nan)


def temperature(ds, ax=None):
    """T(t), with the exact law where one is known.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.homogeneous("temperature")
    ax = _axes(ax, run)
    t, T = run.step_time, run.moments["temperature"]
    exact = run.exact_temperature()
    if exact is not None:
        marks = max(1, len(t) // 40)
        ax.plot(t, exact, color="C0", lw=1.5, label="exact law")
        ax.plot(t[::marks], T[::marks], "o", color="C1", ms=3.5,
                label=f"granframe, every {marks} steps" if marks > 1 else "granframe")
    else:
        ax.plot(t, T, color="C1", label="granframe (no exact law for this kernel and law)")
    ax.set(xlabel=_TIME, ylabel="temperature T (dimensionless)", title="temperature")
    ax.legend()
    return ax


def temperature_error(ds, ax=None):
    """|T / T_exact - 1| on a log axis, for a run with an exact temperature law.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store whose kernel and restitution law have an exact
        temperature law (Maxwell molecules, constant e).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        When no exact law is known for the run.
    """
    run = _Run.of(ds)
    run.homogeneous("temperature_error")
    exact = run.exact_temperature()
    if exact is None:
        check.reject("temperature_error", "ds", run.title,
                     "must be a run with an exact temperature law (Maxwell molecules with "
                     "the review's constant and a constant restitution coefficient)")
    ax = _axes(ax, run)
    error = numpy.abs(run.moments["temperature"] / exact - 1)
    ax.semilogy(run.step_time, _positive(error), color="C1")
    ax.set(xlabel=_TIME, ylabel=r"$|T/T_{exact} - 1|$ (dimensionless)",
           title=f"relative error of T against the exact law, max {error.max():.2e} "
                 "(zeros left out)")
    return ax


def mass_drift(ds, ax=None):
    """|m(t) / m(0) - 1| on a log axis, with the health check's limit.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    ax = _axes(ax, run)
    mass = run.moments["mass"]
    drift = numpy.abs(mass / mass[0] - 1)
    ax.semilogy(run.step_time, _positive(drift), ".", ms=2, color="C2",
                label=f"granframe, max {drift.max():.1e}")
    ax.axhline(run.description.health.mass_tolerance, color="C3", ls="--", lw=1,
               label="health limit (mass_tolerance)")
    ax.set(xlabel=_TIME, ylabel=r"mass drift $|m(t)/m(0) - 1|$ (dimensionless)",
           title="mass drift (zeros left out)")
    ax.legend()
    return ax


def kurtosis(ds, ax=None):
    """The kurtosis kappa(t) against the Maxwellian value (d + 2)/d.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.homogeneous("kurtosis")
    ax = _axes(ax, run)
    d = run.grid.dimension
    ax.plot(run.step_time, run.moments["kurtosis"], color="C4", label="granframe")
    ax.axhline((d + 2) / d, color="k", ls="--", lw=1, label=f"Maxwellian, {(d + 2) / d:g}")
    ax.set(xlabel=_TIME, ylabel=r"kurtosis $\kappa$ (dimensionless)",
           title=r"kurtosis $\kappa = \rho\int|v-u|^4 f\,/\,(\int|v-u|^2 f)^2$")
    ax.legend()
    return ax


def positivity(ds, ax=None):
    """How much of f is negative, on a log axis, against the positivity health limit.

    Draws the negative mass share int max(-f, 0) / int |f| at every step and
    -min f / max f at the snapshots; zeros (f >= 0 everywhere) are left out.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    ax = _axes(ax, run)
    share = run.moments["negative_mass_fraction"]
    peaks, lows = run.extremes()
    ax.semilogy(run.step_time, _positive(share), color="C3",
                label=r"negative mass share $\int f^- / \int |f|$")
    ax.semilogy(run.times, _positive(-lows / peaks), "s", ms=3.5, color="C5",
                label=r"$-\min f / \max f$ (at the snapshots)")
    ax.axhline(run.description.health.positivity_tolerance, color="k", ls="--", lw=1,
               label="health limit (positivity_tolerance)")
    ax.set(xlabel=_TIME, ylabel="negative part of f, share (dimensionless)",
           title="positivity: the negative part of f (zeros left out)")
    ax.legend()
    return ax


def entropy(ds, ax=None):
    """Relative entropy H(f(t) | f_ref) on a log axis.

    f_ref is the exact equilibrium where one is known (elastic collisions without a heat
    bath: the Maxwellian with the mass, momentum and temperature of f(0)); otherwise the
    last snapshot f(t_end), and the title says that H is then zero at t_end by
    construction. An exponential rate is fitted against an exact equilibrium, or against
    f(t_end) once the run is stationary (:data:`STATIONARY`).

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store with at least two snapshots.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.homogeneous("entropy")
    if run.count < 2:
        check.reject("entropy", "ds", f"{run.count} snapshot",
                     "must hold at least two snapshots")
    ax = _axes(ax, run)
    h = run.grid.cell_volume
    reference = run.equilibrium()
    if reference is not None:
        indices = range(run.count)
        symbol = r"$H(f(t)\,|\,M)$, M the exact equilibrium"
        title = ["relative entropy to the exact equilibrium M",
                 "(elastic, no heat bath: the Maxwellian of the mass, momentum and "
                 "temperature of f(0))"]
        fitted = True
    else:
        reference = run.snapshot(run.count - 1)
        indices = range(run.count - 1)
        end = run.times[-1]
        symbol = r"$H(f(t)\,|\,f(t_{end}))$"
        title = [f"relative entropy to the last snapshot f(t_end), t_end = {end:g}",
                 "(no exact equilibrium known: H = 0 at t_end by construction, "
                 "not by convergence)"]
        ax.axvline(end, color="0.4", ls=":", lw=1, label="t_end (the reference)")
        change = float(numpy.abs(reference - run.snapshot(run.count - 2)).max()
                       / reference.max())
        fitted = change < STATIONARY
        if not fitted:
            title.append(f"not stationary: the last two snapshots differ by {change:.1e} of "
                         "max f; no rate fitted")
    times = run.times[list(indices)]
    values = numpy.array([relative_entropy(run.snapshot(i), reference, h) for i in indices])
    positive = values > 0
    ax.semilogy(times, _positive(values), "o-", ms=3.5, color="C0", label=symbol)
    fit = positive & (values > 1e-8 * values[positive].max(initial=0.0))
    if fitted and fit.sum() >= 3:
        slope, intercept = numpy.polyfit(times[fit], numpy.log(values[fit]), 1)
        ax.semilogy(times[fit], numpy.exp(intercept + slope * times[fit]), "--", color="C3",
                    label=f"fit exp({slope:.4g} t)")
    ax.set(xlabel=_TIME, ylabel="relative entropy H (dimensionless)", title="\n".join(title))
    ax.legend()
    return ax


def slices(ds, ax=None, scale="linear"):
    """f along v1 through v = 0 at five times, a marker at each grid point.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.
    scale : {"linear", "log"}
        The y axis. On the log axis f > 0 is drawn as filled markers and -f where f < 0
        as open ones.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if scale not in ("linear", "log"):
        check.reject("slices", "scale", scale, "must be 'linear' or 'log'")
    run = _Run.of(ds)
    run.homogeneous("slices")
    ax = _axes(ax, run)
    v = run.axes[0]
    f, v1 = run.f_name, f"{run.v_name}1"
    label = f"{f}({v1}, 0)" if run.grid.dimension == 2 else f"{f}({v1}, 0, 0)"
    indices = run.snapshot_indices()
    for colour, i in enumerate(indices):
        line = run.line(i)
        style = dict(color=f"C{colour}", marker="o", ms=2.5, lw=1, label=f"t = {run.times[i]:g}")
        if scale == "linear":
            ax.plot(v, line, **style)
        else:
            ax.semilogy(v, _positive(line), **style)
            ax.semilogy(v, _positive(-line), ls="none", marker="o", ms=3.5, mfc="none",
                        color=f"C{colour}")
    if scale == "log":
        peak = max(float(run.line(i).max()) for i in indices)
        ax.set_ylim(peak * 1e-16, peak * 3)
        ax.plot([], [], ls="none", marker="o", mfc="none", color="0.3",
                label=f"-{f} where {f} < 0")
        title = f"log scale: filled {f} > 0, open -{f} where {f} < 0"
    else:
        title = f"slices of {f} through {run.v_name} = 0, a marker at each grid point"
    ax.set(xlabel=f"velocity {v1} (dimensionless)", ylabel=f"{label} (dimensionless)",
           title=title)
    ax.legend()
    return ax


def contour(ds, ax=None, index=-1):
    """Filled contours of f in the (v1, v2) plane (through v3 = 0 in 3D) at one snapshot.

    The filled levels start at f = 0, so the lowest band reaches as far as f >= 0; f < 0
    is grey. Orange lines mark f = 1e-2 and 1e-4 of max f. The window holds the square where
    f exceeds 1e-4 of max f, with a margin of 15 %.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (its figure gets the colour bar); a new captioned figure when
        None.
    index : int
        The snapshot, counted as a Python sequence index (0 the first, -1 the last).

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.homogeneous("contour")
    if not check.is_integer(index) or not -run.count <= index < run.count:
        check.reject("contour", "index", index,
                     f"must be an integer from {-run.count} to {run.count - 1}")
    ax = _axes(ax, run)
    index = int(index) % run.count
    v1, v2 = run.axes[0], run.axes[1]
    plane = run.plane(index)
    peak = float(plane.max())
    inside = plane > 1e-4 * peak
    reach = min(1.15 * max(float(numpy.abs(v1[inside.any(axis=1)]).max()),
                           float(numpy.abs(v2[inside.any(axis=0)]).max())) + run.grid.spacing,
                run.grid.half_width)
    levels = ticker.MaxNLocator(nbins=12).tick_values(0.0, peak)
    cmap = colormaps["viridis"].with_extremes(under="0.8")
    filled = ax.contourf(v1, v2, plane.T, levels=levels, cmap=cmap, extend="min")
    ax.contour(v1, v2, plane.T, levels=peak * numpy.array([1e-4, 1e-2]), colors="C1",
               linewidths=0.8, linestyles=[":", "--"])
    ax.set(xlim=(-reach, reach), ylim=(-reach, reach))
    ax.set_aspect("equal")
    f, v = run.f_name, run.v_name
    where = "" if run.grid.dimension == 2 else f", {v}3 = 0"
    ax.set(xlabel=f"velocity {v}1 (dimensionless)", ylabel=f"velocity {v}2 (dimensionless)",
           title=f"{f}({v}1, {v}2{where}) at t = {run.times[index]:g}, max {f} = {peak:.3g}")
    ax.legend(handles=[Line2D([], [], color="C1", ls="--", lw=0.8,
                              label=f"{f} = 1e-2 max {f}"),
                       Line2D([], [], color="C1", ls=":", lw=0.8, label=f"{f} = 1e-4 max {f}"),
                       Patch(color="0.8", label=f"{f} < 0")],
              loc="upper center", bbox_to_anchor=(0.5, -0.13), ncols=3, fontsize=7)
    ax.figure.colorbar(filled, ax=ax, shrink=0.85, label=f"{f} (dimensionless)")
    return ax


def _space_field(run, owner, field):
    """The entry of :data:`SPACE_FIELDS` named ``field`` of the space run ``run``."""
    run.inhomogeneous(owner)
    if field not in SPACE_FIELDS:
        check.reject(owner, "field", field, f"must be one of {', '.join(SPACE_FIELDS)}")
    return SPACE_FIELDS[field]


def field_map(ds, field="density", ax=None):
    """An x-t map of one field of a space run: its value in every cell after every step.

    Drawn with ``pcolormesh``, one quad per cell and record (cell width dx, the record's
    step around its time), with a colour bar; a signed field (u_1, q_1) on a diverging
    scale centred at zero.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a space run's store.
    field : {"density", "velocity", "temperature", "pressure", "heat_flux"}
        rho, u_1, T, P_11 or q_1 (:data:`SPACE_FIELDS`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (its figure gets the colour bar); a new captioned figure when
        None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    _, _, symbol, words, signed = _space_field(run, "field_map", field)
    ax = _axes(ax, run)
    x, t = run.ds["x"].values, run.step_time
    values = run.field(field)
    style = {"cmap": "viridis"}
    if signed:
        reach = float(numpy.nanmax(numpy.abs(values))) or 1.0
        style = {"cmap": "RdBu_r", "vmin": -reach, "vmax": reach}
    mesh = ax.pcolormesh(x, t, values, shading="nearest", **style)
    ax.figure.colorbar(mesh, ax=ax, label=f"{symbol} (dimensionless)")
    ax.grid(False)
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=_TIME,
           xlim=(0.0, run.space.length),
           title=f"{words} {symbol}(t, x): range [{numpy.nanmin(values):.4g}, "
                 f"{numpy.nanmax(values):.4g}]")
    return ax


def profiles(ds, field="density", ax=None):
    """One field of a space run against x at five of its snapshot times.

    The field of the record taken with each snapshot (its step), a marker at each cell
    centre.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a space run's store.
    field : {"density", "velocity", "temperature", "pressure", "heat_flux"}
        rho, u_1, T, P_11 or q_1 (:data:`SPACE_FIELDS`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    _, _, symbol, words, _ = _space_field(run, "profiles", field)
    ax = _axes(ax, run)
    x = run.ds["x"].values
    values = run.field(field)
    steps = run.ds["snapshot_step"].values
    for colour, i in enumerate(run.snapshot_indices()):
        ax.plot(x, values[int(steps[i])], color=f"C{colour}", marker="o", ms=2.5, lw=1,
                label=f"t = {run.times[i]:g}")
    ax.set(xlabel="position x, cell centres (dimensionless)",
           ylabel=f"{symbol} (dimensionless)", xlim=(0.0, run.space.length),
           title=f"{words} {symbol}(x) at the snapshots, a marker at each cell")
    ax.legend()
    return ax


def _entered(run, name):
    """What entered through both walls from t = 0 to each record (a running sum)."""
    return numpy.cumsum(run.ds[name].values.sum(axis=1))


def total_mass(ds, ax=None):
    """The total mass m(t) = int int f dv dx of a space run, drift and balance, log axis.

    Draws |m(t)/m(0) - 1| and the balance |m(t) - m(0) - M_in(t)| / m(0), where M_in(t)
    is the mass that entered through the walls up to t (``wall_mass`` summed), against
    the health check's limit; zeros are left out.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a space run's store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.inhomogeneous("total_mass")
    ax = _axes(ax, run)
    mass = run.moments["mass"]
    drift = numpy.abs(mass / mass[0] - 1)
    balance = numpy.abs((mass - mass[0] - _entered(run, "wall_mass")) / mass[0])
    ax.semilogy(run.step_time, _positive(drift), ".", ms=2, color="C2",
                label=f"drift |m(t)/m(0) - 1|, max {drift.max():.1e}")
    ax.semilogy(run.step_time, _positive(balance), "x", ms=3, color="C0",
                label=f"balance with the walls, max {balance.max():.1e}")
    ax.axhline(run.description.health.mass_tolerance, color="C3", ls="--", lw=1,
               label="health limit (mass_tolerance)")
    ax.set(xlabel=_TIME, ylabel=r"relative mass change (dimensionless)",
           title=r"total mass $m = \int\int f\,dv\,dx$, m(0) = " + f"{mass[0]:.6g}"
                 "\nand its balance with the walls (zeros left out)")
    ax.legend()
    return ax


def total_energy(ds, ax=None):
    """The total energy E(t) = int int |v|^2/2 f dv dx of a space run, with E(0) plus
    the energy that entered through the walls up to t (``wall_energy`` summed).

    The two agree where the transport and the collisions conserve energy (elastic
    collisions); their gap is what the collision step changed.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a space run's store.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.inhomogeneous("total_energy")
    ax = _axes(ax, run)
    energy = run.moments["kinetic_energy"]
    walls = energy[0] + _entered(run, "wall_energy")
    ax.plot(run.step_time, energy, color="C1", label="E(t)")
    ax.plot(run.step_time, walls, "--", color="C0",
            label="E(0) + energy entered through the walls")
    gap = float(numpy.abs(energy - walls).max())
    ax.set(xlabel=_TIME, ylabel="total energy E (dimensionless)",
           title=r"total energy $E = \int\int |v|^2/2\, f\,dv\,dx$" + "\nmax |E(t) - E(0) - "
                 f"entered| = {gap:.2e} (the collision step's)")
    ax.legend()
    return ax


def _level_colours(count):
    """The colour map of ``count`` levels: one colour of viridis each, cheapest first."""
    return colormaps["viridis"].resampled(count)


def level_map(ds, ax=None):
    """An x-t map of the collision model of every cell of a space run with a hierarchy.

    One quad per cell and record (as :func:`field_map`), in one colour per level of
    ``space.hierarchy.levels``; the colour bar names them.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of the store of a space run with a hierarchy of collision models.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (its figure gets the colour bar); a new captioned figure when
        None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.hierarchical("level_map")
    ax = _axes(ax, run)
    count = len(run.levels)
    mesh = ax.pcolormesh(run.ds["x"].values, run.step_time, run.ds["level"].values,
                         shading="nearest", cmap=_level_colours(count),
                         norm=BoundaryNorm(numpy.arange(count + 1) - 0.5, count))
    bar = ax.figure.colorbar(mesh, ax=ax, ticks=numpy.arange(count),
                             label="collision model (level)")
    bar.set_ticklabels(run.levels)
    bar.minorticks_off()
    ax.grid(False)
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=_TIME,
           xlim=(0.0, run.space.length),
           title="collision model of each cell (t, x)")
    return ax


def level_shares(ds, ax=None):
    """The share of the cells of a space run at each level of its hierarchy, against t.

    Stacked, cheapest at the bottom, in the colours of :func:`level_map`; the level
    recorded at a step holds over that step (from the previous record to its own). The
    title gives each level's mean share over the steps.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of the store of a space run with a hierarchy of collision models.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.hierarchical("level_shares")
    ax = _axes(ax, run)
    count = len(run.levels)
    levels = run.ds["level"].values
    shares = numpy.stack([(levels == k).mean(axis=1) for k in range(count)])
    ax.stackplot(run.step_time, shares, labels=run.levels, step="pre",
                 colors=_level_colours(count)(numpy.arange(count)))
    title = "share of the cells at each level"
    if shares.shape[1] > 1:           # the record at t = 0 is no step
        title += "\nmean over the steps: " + ", ".join(
            f"{name} {share:.0%}" for name, share in zip(run.levels, shares[:, 1:].mean(axis=1)))
    ax.set(xlabel=_TIME, ylabel="share of the cells (dimensionless)", ylim=(0.0, 1.0),
           title=title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.17), ncols=count)
    return ax


def indicator_map(ds, indicator="realizability", ax=None):
    """An x-t map of one indicator of a space run's hierarchy, on a logarithmic scale.

    The indicator of every cell after every step (as :func:`field_map`), with its
    thresholds (``space.hierarchy``) marked in red on the colour bar. The scale runs from
    :data:`INDICATOR_FLOOR` times the lowest threshold, smaller values (zero among them)
    in its lowest colour, to the largest value or threshold, an infinite kappa (a cell
    without an equilibrium) in its highest; NaN (not measured: t = 0, and delta where
    there is no equilibrium) is left blank.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of the store of a space run with a hierarchy of collision models.
    indicator : {"realizability", "distance"}
        kappa or delta (:data:`LEVEL_INDICATORS`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (its figure gets the colour bar); a new captioned figure when
        None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = _Run.of(ds)
    run.hierarchical("indicator_map")
    if indicator not in LEVEL_INDICATORS:
        check.reject("indicator_map", "indicator", indicator,
                     f"must be one of {', '.join(LEVEL_INDICATORS)}")
    symbol, words = LEVEL_INDICATORS[indicator]
    ax = _axes(ax, run)
    thresholds = getattr(run.space.hierarchy, indicator)
    values = run.ds[indicator].values
    finite = values[numpy.isfinite(values)]
    low = INDICATOR_FLOOR * min(thresholds)
    high = max(float(finite.max(initial=0.0)), max(thresholds))
    mesh = ax.pcolormesh(run.ds["x"].values, run.step_time, numpy.clip(values, low, high),
                         shading="nearest", cmap="viridis", norm=LogNorm(low, high))
    bar = ax.figure.colorbar(mesh, ax=ax, extend="min",
                             label=f"{symbol} (dimensionless), thresholds in red")
    for threshold in thresholds:
        bar.ax.axhline(threshold, color="C3", lw=1.5)
    ax.grid(False)
    largest = f"max {finite.max():.3g}" if finite.size else "not measured yet"
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=_TIME,
           xlim=(0.0, run.space.length),
           title=f"{words} {symbol}(t, x): {largest}\n(log scale; blank: not measured)")
    return ax


def _space_panels(run) -> dict:
    """The figures of a space run: name -> the functions drawing their panels."""
    def drawn(function, field):
        return lambda r, ax: function(r, field, ax)

    panels = {"maps": tuple(drawn(field_map, name) for name in SPACE_FIELDS),
              "profiles": tuple(drawn(profiles, name) for name in SPACE_FIELDS),
              "totals": (total_mass, total_energy, positivity)}
    if run.levels is not None:
        panels["levels"] = (level_map, level_shares,
                            *(drawn(indicator_map, name) for name in LEVEL_INDICATORS))
    return panels


def figures(ds) -> dict:
    """The figures of a run, each captioned with its parameters.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``temperature``, ``slices``, ``contour``, ``moments`` and, with at least three
        snapshots, ``entropy``; for a space run ``maps``, ``profiles`` and ``totals``, and
        ``levels`` with a hierarchy of collision models. They are not attached to pyplot.
    """
    run = _Run.of(ds)
    if run.space is not None:
        panels = _space_panels(run)
    else:
        error = temperature_error if run.exact_temperature() is not None else mass_drift
        panels = {"temperature": (temperature, error),
                  "slices": (slices, lambda r, ax: slices(r, ax, scale="log")),
                  "contour": (lambda r, ax: contour(r, ax, index=0), contour),
                  "moments": (mass_drift, kurtosis, positivity)}
        if run.count >= 3:
            panels["entropy"] = (entropy,)
    text = _wrapped(caption(run))
    drawn = {}
    for name, draws in panels.items():
        layout, size = _LAYOUTS[name]
        fig = Figure(figsize=size, layout="constrained")
        axes = numpy.atleast_1d(fig.subplots(*layout)).ravel()
        for ax, draw in zip(axes, draws):
            draw(run, ax)
        for ax in axes[len(draws):]:
            fig.delaxes(ax)
        fig.suptitle(text, fontsize=8, color="C3" if run.status not in (None, "finished")
                     or run.warnings or run.accuracy_warnings else "black")
        drawn[name] = fig
    return drawn


def plot(store, out, *, format="png", dpi=DEFAULT_DPI) -> list[pathlib.Path]:
    """Write the figures of the run store ``store`` into the folder ``out``.

    Parameters
    ----------
    store : str or pathlib.Path
        A run store; every committed chunk must pass its checksum.
    out : str or pathlib.Path
        The folder for the figures (made when missing).
    format : {"png", "pdf", "svg"}
        The file format.
    dpi : float
        Resolution of the raster parts, in dots per inch, within :data:`DPI_RANGE`.

    Returns
    -------
    list of pathlib.Path
        The files written, ``<figure>.<format>``.
    """
    if format not in FORMATS:
        check.reject("plot", "format", format, f"must be one of {', '.join(FORMATS)}")
    low, high = DPI_RANGE
    if not check.is_real(dpi) or not (math.isfinite(dpi) and low <= dpi <= high):
        check.reject("plot", "dpi", dpi, f"must be a number from {low} to {high}")
    import matplotlib

    with matplotlib.rc_context(_STYLE):
        drawn = figures(_Run(store))
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in drawn.items():
        path = out / f"{name}.{format}"
        fig.savefig(path, format=format, dpi=dpi)
        written.append(path)
    return written
