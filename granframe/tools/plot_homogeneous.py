"""The figures of a space-homogeneous run, drawn from f(v) and its moments: the
temperature and its error, the mass drift, the kurtosis, the relative entropy, slices
and contours of f; and the negative part of f, which a space run's figures draw too.
"""

from __future__ import annotations

import numpy
from matplotlib import colormaps, ticker
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from granframe import validators as check
from granframe.tools.analysis import relative_entropy
from granframe.tools.plot_data import RunData, TIME_LABEL, axes_for, positive_values


#: Largest max|f(t_end) - f(t_end - interval)| / max f for which f(t_end) is taken as f_infinity.
STATIONARY = 1e-6


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
    run = RunData.of(ds)
    run.homogeneous("temperature")
    ax = axes_for(ax, run)
    t, T = run.step_time, run.moments["temperature"]
    exact = run.exact_temperature()
    if exact is not None:
        marks = max(1, len(t) // 40)
        ax.plot(t, exact, color="C0", lw=1.5, label="exact law")
        ax.plot(t[::marks], T[::marks], "o", color="C1", ms=3.5,
                label=f"granframe, every {marks} steps" if marks > 1 else "granframe")
    else:
        ax.plot(t, T, color="C1", label="granframe (no exact law for this kernel and law)")
    ax.set(xlabel=TIME_LABEL, ylabel="temperature T (dimensionless)", title="temperature")
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
    run = RunData.of(ds)
    run.homogeneous("temperature_error")
    exact = run.exact_temperature()
    if exact is None:
        check.reject("temperature_error", "ds", run.title,
                     "must be a run with an exact temperature law (Maxwell molecules with "
                     "the review's constant and a constant restitution coefficient)")
    ax = axes_for(ax, run)
    error = numpy.abs(run.moments["temperature"] / exact - 1)
    ax.semilogy(run.step_time, positive_values(error), color="C1")
    ax.set(xlabel=TIME_LABEL, ylabel=r"$|T/T_{exact} - 1|$ (dimensionless)",
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
    run = RunData.of(ds)
    ax = axes_for(ax, run)
    mass = run.moments["mass"]
    drift = numpy.abs(mass / mass[0] - 1)
    ax.semilogy(run.step_time, positive_values(drift), ".", ms=2, color="C2",
                label=f"granframe, max {drift.max():.1e}")
    ax.axhline(run.description.health.mass_tolerance, color="C3", ls="--", lw=1,
               label="health limit (mass_tolerance)")
    ax.set(xlabel=TIME_LABEL, ylabel=r"mass drift $|m(t)/m(0) - 1|$ (dimensionless)",
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
    run = RunData.of(ds)
    run.homogeneous("kurtosis")
    ax = axes_for(ax, run)
    d = run.grid.dimension
    ax.plot(run.step_time, run.moments["kurtosis"], color="C4", label="granframe")
    ax.axhline((d + 2) / d, color="k", ls="--", lw=1, label=f"Maxwellian, {(d + 2) / d:g}")
    ax.set(xlabel=TIME_LABEL, ylabel=r"kurtosis $\kappa$ (dimensionless)",
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
    run = RunData.of(ds)
    ax = axes_for(ax, run)
    share = run.moments["negative_mass_fraction"]
    peaks, lows = run.extremes()
    ax.semilogy(run.step_time, positive_values(share), color="C3",
                label=r"negative mass share $\int f^- / \int |f|$")
    ax.semilogy(run.times, positive_values(-lows / peaks), "s", ms=3.5, color="C5",
                label=r"$-\min f / \max f$ (at the snapshots)")
    ax.axhline(run.description.health.positivity_tolerance, color="k", ls="--", lw=1,
               label="health limit (positivity_tolerance)")
    ax.set(xlabel=TIME_LABEL, ylabel="negative part of f, share (dimensionless)",
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
    run = RunData.of(ds)
    run.homogeneous("entropy")
    if run.count < 2:
        check.reject("entropy", "ds", f"{run.count} snapshot",
                     "must hold at least two snapshots")
    ax = axes_for(ax, run)
    h = run.grid.cell_volume
    reference, indices, symbol, title, fitted = _entropy_reference(run, ax)
    times = run.times[list(indices)]
    values = numpy.array([relative_entropy(run.snapshot(i), reference, h) for i in indices])
    positive = values > 0
    ax.semilogy(times, positive_values(values), "o-", ms=3.5, color="C0", label=symbol)
    fit = positive & (values > 1e-8 * values[positive].max(initial=0.0))
    if fitted and fit.sum() >= 3:
        slope, intercept = numpy.polyfit(times[fit], numpy.log(values[fit]), 1)
        ax.semilogy(times[fit], numpy.exp(intercept + slope * times[fit]), "--", color="C3",
                    label=f"fit exp({slope:.4g} t)")
    ax.set(xlabel=TIME_LABEL, ylabel="relative entropy H (dimensionless)",
           title="\n".join(title))
    ax.legend()
    return ax


def _entropy_reference(run, ax):
    """(f_ref, the snapshots compared with it, the curve's label, the lines of the title,
    whether a rate is fitted) of :func:`entropy`; f(t_end), when no exact equilibrium is
    known, marked on ``ax``."""
    reference = run.equilibrium()
    if reference is not None:
        return (reference, range(run.count), r"$H(f(t)\,|\,M)$, M the exact equilibrium",
                ["relative entropy to the exact equilibrium M",
                 "(elastic, no heat bath: the Maxwellian of the mass, momentum and "
                 "temperature of f(0))"], True)
    reference = run.snapshot(run.count - 1)
    end = run.times[-1]
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
    return reference, range(run.count - 1), r"$H(f(t)\,|\,f(t_{end}))$", title, fitted


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
    run = RunData.of(ds)
    run.homogeneous("slices")
    ax = axes_for(ax, run)
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
            ax.semilogy(v, positive_values(line), **style)
            ax.semilogy(v, positive_values(-line), ls="none", marker="o", ms=3.5, mfc="none",
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
    run = RunData.of(ds)
    run.homogeneous("contour")
    if not check.is_integer(index) or not -run.count <= index < run.count:
        check.reject("contour", "index", index,
                     f"must be an integer from {-run.count} to {run.count - 1}")
    ax = axes_for(ax, run)
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
