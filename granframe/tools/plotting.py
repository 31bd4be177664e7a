"""Figures of a run store (``granframe plot``): PNG files drawn with matplotlib.

- ``temperature.png``: T(t) with the exact law where one exists, and the
  relative error against it (otherwise the mass drift);
- ``entropy.png``: relative entropy H(f(t) | f(t_end)) on a log scale with the
  fitted exponential rate;
- ``slices.png``: f(v1, 0, ...) at several times, linear and logarithmic;
- ``contour.png``: f in the (v1, v2) plane (through v3 = 0 in 3D), first and last snapshot;
- ``moments.png``: mass drift, kurtosis against the Maxwellian value, min f.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402

from granframe.tools.analysis import relative_entropy  # noqa: E402
from granframe.run.description import RunDescription  # noqa: E402
from granframe.model.exact import heated_maxwell_law  # noqa: E402
from granframe.equations.rescaled import Rescaling  # noqa: E402
from granframe.run.storage import RunStore, StoreDamagedError, summarise  # noqa: E402

#: Largest max|f(t_end) - f(t_end - interval)| / max f for which f(t_end) is taken as f_infinity.
STATIONARY = 1e-6

_STYLE = {"figure.dpi": 110, "axes.grid": True, "grid.alpha": 0.3, "font.size": 10,
          "axes.titlesize": 10, "legend.fontsize": 9}


class _Run:
    """What the figures read from a store."""

    def __init__(self, path):
        store = RunStore.open(path, complete=False)
        problems = store.verify()     # every committed chunk present and passing its checksum
        if problems:
            raise StoreDamagedError(f"plot: store '{path}' is damaged: {summarise(problems)} "
                                    "(granframe check lists every problem)", problems)
        group, progress = store.group, store.progress
        n, k = int(progress["records"]), store.snapshot_count
        if k == 0:
            raise ValueError(f"plot: store '{path}' has no snapshot yet")
        self.description = RunDescription.from_dict(store.metadata["description"])
        self.title = self.description.title or pathlib.Path(path).name
        self.grid = self.description.grid
        self.step_time = group["step_time"][:n]
        self.moments = {name: group[name][:n] for name in
                        ("mass", "temperature", "kurtosis", "min_f", "negative_mass_fraction")}
        self.times = group["time"][:k]
        self.f = group["f"]
        self.count = k
        self.axes = [group[f"v{i + 1}"][:] for i in range(self.grid.dimension)]
        self.status = progress.get("status")
        if "rescaling" in store.metadata:
            # a rescaled run: times and temperatures in physical terms; f is the profile g
            law = Rescaling.from_store(store)
            self.moments["temperature"] = law.temperature(self.step_time,
                                                          self.moments["temperature"])
            self.step_time = law.physical_time(self.step_time)
            self.times = law.physical_time(self.times)
            self.title += " (rescaled; f shown as the profile g)"

    def snapshot(self, index):
        return self.f[index]

    def plane(self, index):
        """f in the (v1, v2) plane (through the middle of v3 in 3D)."""
        f = self.snapshot(index)
        return f if f.ndim == 2 else f[:, :, self.grid.n_modes // 2]

    def line(self, index):
        """f along v1 with the other components at the grid point v = 0."""
        f = self.snapshot(index)
        middle = self.grid.n_modes // 2
        return f[(slice(None),) + (middle,) * (f.ndim - 1)]

    def exact_temperature(self):
        d = self.description
        law = heated_maxwell_law(d.build("kernel"), d.build("restitution"), d.heat_bath,
                                 d.knudsen)
        if law is None:
            return None
        return law(self.step_time, self.moments["temperature"][0], self.moments["mass"][0])

    def snapshot_indices(self, count=5):
        return sorted(set(numpy.linspace(0, self.count - 1, min(count, self.count))
                          .round().astype(int)))


def _temperature(run, ax_t, ax_e):
    t, T = run.step_time, run.moments["temperature"]
    exact = run.exact_temperature()
    marks = max(1, len(t) // 40)
    if exact is not None:
        ax_t.plot(t, exact, color="C0", lw=1.5, label="exact law")
        ax_t.plot(t[::marks], T[::marks], "o", color="C1", ms=3.5, label="granframe")
        error = numpy.abs(T / exact - 1)
        ax_e.semilogy(t[1:], numpy.maximum(error[1:], 1e-17), color="C1")
        ax_e.set_title(f"|T / T_exact - 1|, max {error.max():.2e}")
    else:
        ax_t.plot(t, T, color="C1", label="granframe")
        drift = numpy.abs(run.moments["mass"] / run.moments["mass"][0] - 1)
        ax_e.semilogy(t[1:], numpy.maximum(drift[1:], 1e-17), color="C2")
        ax_e.set_title(f"no exact law for this kernel/law: |mass/mass(0) - 1|, max "
                       f"{drift.max():.1e}")
    ax_t.set(xlabel="t", ylabel="temperature T", title=f"temperature, {run.title}")
    ax_t.legend()
    ax_e.set(xlabel="t")


def _entropy(run, ax):
    reference = run.snapshot(run.count - 1)
    h = run.grid.cell_volume
    values = numpy.array([relative_entropy(run.snapshot(i), reference, h)
                          for i in range(run.count - 1)])
    times = run.times[:-1]
    positive = values > 0
    ax.semilogy(times[positive], values[positive], "o-", ms=3.5, color="C0",
                label=r"$H(f(t)\,|\,f(t_{end}))$")
    # f(t_end) stands for f_infinity only once the run is stationary; only then is a rate fitted
    change = float(numpy.abs(reference - run.snapshot(run.count - 2)).max() / reference.max())
    title = f"relative entropy to f(t = {run.times[-1]:g})"
    fit = positive & (values > 1e-8 * values[positive].max(initial=0.0))
    if change < STATIONARY and fit.sum() >= 3:
        slope, intercept = numpy.polyfit(times[fit], numpy.log(values[fit]), 1)
        ax.semilogy(times[fit], numpy.exp(intercept + slope * times[fit]), "--", color="C3",
                    label=f"fit exp({slope:.4g} t)")
    else:
        title += (f"\nnot stationary yet (last snapshots differ by {change:.1e} of max f): "
                  "no rate fitted")
    ax.set(xlabel="t", ylabel="relative entropy", title=title)
    ax.legend()


def _slices(run, ax_lin, ax_log):
    v = run.axes[0]
    label = "f(v1, 0)" if run.grid.dimension == 2 else "f(v1, 0, 0)"
    for i in run.snapshot_indices():
        line = run.line(i)
        ax_lin.plot(v, line, label=f"t = {run.times[i]:g}")
        ax_log.semilogy(v, numpy.where(line > 0, line, numpy.nan), label=f"t = {run.times[i]:g}")
    peak = max(float(run.line(i).max()) for i in run.snapshot_indices())
    ax_log.set_ylim(peak * 1e-16, peak * 3)
    ax_lin.set(xlabel="v1", ylabel=label, title=f"slices of f, {run.title}")
    ax_log.set(xlabel="v1", title="log scale (where f > 0; negative values left out)")
    ax_lin.legend()


def _contours(run, axes):
    v1, v2 = run.axes[0], run.axes[1]
    for ax, index in zip(axes, (0, run.count - 1)):
        plane = run.plane(index)
        # each panel shows the square where its f exceeds 1e-3 of its maximum (above the noise)
        inside = plane > 1e-3 * plane.max()
        reach = max(float(numpy.abs(v1[inside.any(axis=1)]).max()),
                    float(numpy.abs(v2[inside.any(axis=0)]).max())) + run.grid.spacing
        levels = numpy.linspace(0, plane.max(), 21)[1:]
        filled = ax.contourf(v1, v2, plane.T, levels=levels, cmap="viridis")
        ax.contour(v1, v2, plane.T, levels=plane.max() * numpy.array([1e-4, 1e-2]),
                   colors="0.35", linewidths=0.8, linestyles=[":", "--"])
        ax.set(xlim=(-reach, reach), ylim=(-reach, reach))
        ax.set_aspect("equal")
        where = "" if run.grid.dimension == 2 else ", v3 = 0"
        ax.set(xlabel="v1", ylabel="v2", title=f"f at t = {run.times[index]:g}{where}")
        plt.colorbar(filled, ax=ax, shrink=0.8, format="%.3g",
                     label="f (grey: 1e-2 dashed, 1e-4 dotted, of max f)")


def _moments(run, axes):
    t = run.step_time
    drift = numpy.abs(run.moments["mass"] / run.moments["mass"][0] - 1)
    axes[0].semilogy(t, numpy.where(drift > 0, drift, numpy.nan), ".", ms=2, color="C2")
    axes[0].set(xlabel="t", title="|mass / mass(0) - 1| (zeros left out)")
    d = run.grid.dimension
    axes[1].plot(t, run.moments["kurtosis"], color="C4", label="granframe")
    axes[1].axhline((d + 2) / d, color="k", ls="--", lw=1, label=f"Maxwellian {(d + 2) / d:g}")
    axes[1].set(xlabel="t", title="kurtosis")
    axes[1].legend()
    peaks = numpy.array([float(run.snapshot(i).max()) for i in range(run.count)])
    axes[2].plot(t, run.moments["min_f"] / numpy.interp(t, run.times, peaks), color="C5",
                 label="min f / max f")
    axes[2].plot(t, -run.moments["negative_mass_fraction"], color="C3", ls="--",
                 label="- negative mass share")
    axes[2].set(xlabel="t", title="positivity")
    axes[2].legend()


def plot(store, out) -> list[pathlib.Path]:
    """Write the figures of ``store`` into the folder ``out``; returns their paths."""
    run = _Run(store)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures = {"temperature.png": ((1, 2), (11, 4), _temperature),
               "slices.png": ((1, 2), (11, 4), _slices),
               "contour.png": ((1, 2), (10, 4.2), lambda r, a, b: _contours(r, (a, b))),
               "moments.png": ((1, 3), (13, 3.6), lambda r, *a: _moments(r, a))}
    if run.count >= 3:
        figures["entropy.png"] = ((1, 1), (6, 4), _entropy)
    written = []
    with plt.rc_context(_STYLE):
        for name, (layout, size, draw) in figures.items():
            fig, axes = plt.subplots(*layout, figsize=size, constrained_layout=True)
            draw(run, *numpy.atleast_1d(axes))
            if run.status != "finished":
                fig.suptitle(f"run status: {run.status}", color="C3")
            path = out / name
            fig.savefig(path)
            plt.close(fig)
            written.append(path)
    return written
