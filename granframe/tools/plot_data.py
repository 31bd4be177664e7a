"""What the figures of a run read from the Dataset of its store (:class:`RunData`: the
committed records and snapshots, in physical time for a rescaled run), the caption
every figure carries (:func:`caption`), and the small helpers the figures share.
"""

from __future__ import annotations

import math
import pathlib
import re
import textwrap

import numpy
import xarray

from granframe import validators as check
from granframe.equations.rescaled import Rescaling
from granframe.model.exact import heated_maxwell_law
from granframe.run.dataset import committed
from granframe.run.description import RunDescription
from granframe.run.storage import RunStore, StoreDamagedError, summarise


#: The label of every time axis.
TIME_LABEL = "time t (dimensionless)"

#: The fields of a space run that :func:`~granframe.tools.plot_space.field_map` and
#: :func:`~granframe.tools.plot_space.profiles` draw: name -> (stored array, component
#: index, symbol, words, signed).
SPACE_FIELDS = {
    "density": ("density", (), r"$\rho$", "density", False),
    "velocity": ("velocity", (0,), r"$u_1$", "bulk velocity", True),
    "temperature": ("temperature", (), "$T$", "temperature", False),
    "pressure": ("pressure_tensor", (0, 0), r"$P_{11}$", "pressure", False),
    "heat_flux": ("heat_flux", (0,), r"$q_1$", "heat flux", True),
}

#: The totals a space run records after every step (integrals over x and v).
_SPACE_TOTALS = ("mass", "kinetic_energy", "min_f", "negative_mass_fraction")


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


class RunData:
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
            if self.space is None:
                self.moments["temperature"] = law.temperature(self.step_time,
                                                              self.moments["temperature"])
            else:
                self._physical_fields(law)
            self.step_time = law.physical_time(self.step_time)
            self.times = law.physical_time(self.times)
            self.title += " (rescaled; f shown as the profile g)"
        #: the names of f and of the velocity in the figures: g and xi for a rescaled run
        self.f_name, self.v_name = ("g", "ξ") if self.rescaled else ("f", "v")
        self._extremes = None

    def _physical_fields(self, law) -> None:
        """The fields and the total kinetic energy of a rescaled space run, those of f
        (:meth:`~granframe.equations.rescaled.Rescaling.physical_fields` of the recorded
        fields of g at the records' times s)."""
        fields = law.physical_fields(self.step_time, *(
            self.ds[name].values for name in ("density", "velocity", "temperature",
                                              "pressure_tensor", "heat_flux")))
        density = fields.pop("energy_density")
        cell = math.prod(self.space.lengths) / math.prod(self.space.counts)
        energy = density.reshape(len(density), -1).sum(axis=1) * cell
        self.ds = self.ds.assign({name: (self.ds[name].dims, values)
                                  for name, values in fields.items()})
        self.moments["kinetic_energy"] = energy

    @classmethod
    def of(cls, data) -> "RunData":
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


def wrapped(text: str, width: int = 110) -> str:
    """``text`` with every line longer than ``width`` characters broken at spaces, so that a
    figure's caption (a long warning above all) stays within the figure."""
    return "\n".join(textwrap.fill(line, width) if len(line) > width else line
                     for line in text.splitlines())


def _short(warning: str) -> str:
    """A warning in a few words for a figure: its topic, where (the cell) and what to
    raise, e.g. ``velocity resolution (in cell 47, x = 0.95): raise grid.n_modes``."""
    topic = warning.split(":")[0]
    cell = re.search(r"\(in cell [^)]*\)", warning)
    remedy = re.search(r"raise [a-z_.]+( first)?", warning)
    return (topic + (f" {cell.group(0)}" if cell else "")
            + (f": {remedy.group(0)}" if remedy else ""))


def caption(ds, short: bool = False) -> str:
    """The caption of every figure of a run, from its stored description.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of a run store.
    short : bool
        The warnings in one line, each as its topic, cell and what to raise (the
        figures' caption: ``granframe info`` and the run's output say them in full).

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
    run = RunData.of(ds)
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
        + _warning_lines(run, short))


def _warning_lines(run, short: bool) -> list[str]:
    """The caption's lines on the run's warnings: one each, or one in all (``short``)."""
    if not short:
        return ([f"UNDER-RESOLVED: {warning}" for warning in run.warnings]
                + [f"INACCURATE: {warning}" for warning in run.accuracy_warnings])
    parts = ([f"UNDER-RESOLVED {_short(w)}" for w in run.warnings]
             + [f"INACCURATE {_short(w)}" for w in run.accuracy_warnings])
    return ["; ".join(parts) + " (granframe info STORE: the warnings in full)"] if parts else []


def _space_line(space) -> str:
    """The caption line of a space run: its interval, cells, reconstruction and walls."""
    collisions = "" if space.collisions else "; collisionless (free transport)"
    if space.dimension == 2:
        (cx, cy), (lx, ly) = space.counts, space.lengths
        walls = ", ".join(f"{side} {_component(space.wall(side))}" for side in space.sides)
        return (f"space: {cx} x {cy} cells on [0, {lx:g}] x [0, {ly:g}], reconstruction "
                f"{_component(space.reconstruction)}, walls: {walls}{collisions}")
    return (f"space: {space.cells} cells on [0, {space.length:g}] "
            f"(dx = {space.length / space.cells:.4g}), reconstruction "
            f"{_component(space.reconstruction)}, walls: left {_component(space.left)}, "
            f"right {_component(space.right)}{collisions}")


def axes_for(ax, run):
    """``ax``, or the axes of a new figure captioned with the run's parameters."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.8), layout="constrained")
    fig.suptitle(wrapped(caption(run, short=True)), fontsize=8)
    return ax


def positive_values(values):
    """``values`` with its zeros and negative entries left out (for a logarithmic axis)."""
    values = numpy.asarray(values, dtype=float)
    return numpy.where(values > 0, values, numpy.nan)
