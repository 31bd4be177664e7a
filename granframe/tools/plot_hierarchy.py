"""The figures of a space run with a hierarchy of collision models: the x-t map of each
cell's level, the shares of the levels against t, and x-t maps of the indicators that
chose them.
"""

from __future__ import annotations

import numpy
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, LogNorm

from granframe import validators as check
from granframe.tools.plot_data import TIME_LABEL, RunData, axes_for
from granframe.tools.plot_plane import check_snapshot, record_at, rectangle_run

#: The indicators of a hierarchy of collision models that :func:`indicator_map` draws:
#: stored array -> (symbol, words).
LEVEL_INDICATORS = {
    "realizability": (r"$\kappa$", "Navier-Stokes realizability"),
    "distance": (r"$\delta$", "distance from the local Maxwellian"),
}

#: The colour scale of :func:`indicator_map` starts at this share of the lowest threshold;
#: smaller values take its lowest colour.
INDICATOR_FLOOR = 1e-3


def _level_colours(count):
    """The colour map of ``count`` levels: one colour of viridis each, cheapest first."""
    return colormaps["viridis"].resampled(count)


def _level_mesh(ax, run, x, y, levels) -> None:
    """``levels`` on the quads of (x, y) in :func:`_level_colours`, with a colour bar that
    names the levels."""
    count = len(run.levels)
    mesh = ax.pcolormesh(x, y, levels, shading="nearest", cmap=_level_colours(count),
                         norm=BoundaryNorm(numpy.arange(count + 1) - 0.5, count))
    bar = ax.figure.colorbar(mesh, ax=ax, ticks=numpy.arange(count),
                             label="collision model (level)")
    bar.set_ticklabels(run.levels)
    bar.minorticks_off()
    ax.grid(False)


def level_map(ds, ax=None):
    """An x-t map of the collision model of every cell of a space run with a hierarchy.

    One quad per cell and record (as :func:`~granframe.tools.plot_space.field_map`), in one colour per level of
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
    run = RunData.of(ds)
    run.hierarchical("level_map")
    ax = axes_for(ax, run)
    _level_mesh(ax, run, run.ds["x"].values, run.step_time, run.ds["level"].values)
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=TIME_LABEL,
           xlim=(0.0, run.space.length),
           title="collision model of each cell (t, x)")
    return ax


def level_plane(ds, index=-1, ax=None):
    """A map on (x, y) of the collision model of every cell of a run on a rectangle with a
    hierarchy, in the step that ends at snapshot ``index``, in the colours of
    :func:`level_map`.

    Parameters
    ----------
    ds : xarray.Dataset
        The Dataset of the store of a run on a rectangle with a hierarchy.
    index : int
        The snapshot (negative: from the last).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = RunData.of(ds)
    run.hierarchical("level_plane")
    rectangle_run(run, "level_plane", "; level_map draws an interval's")
    check_snapshot(run, "level_plane", index)
    ax = axes_for(ax, run)
    levels = run.ds["level"].values[record_at(run, float(run.times[index]))]
    _level_mesh(ax, run, run.ds["x"].values, run.ds["y"].values, levels.T)
    lx, ly = run.space.lengths
    ax.set(xlabel="x", ylabel="y", xlim=(0.0, lx), ylim=(0.0, ly), aspect="equal",
           title=f"collision model of each cell at t = {float(run.times[index]):.4g}")
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
    run = RunData.of(ds)
    run.hierarchical("level_shares")
    ax = axes_for(ax, run)
    count = len(run.levels)
    levels = run.ds["level"].values
    levels = levels.reshape(len(levels), -1)              # (records, cells), x and y alike
    shares = numpy.stack([(levels == k).mean(axis=1) for k in range(count)])
    ax.stackplot(run.step_time, shares, labels=run.levels, step="pre",
                 colors=_level_colours(count)(numpy.arange(count)))
    title = "share of the cells at each level"
    if shares.shape[1] > 1:           # the record at t = 0 is no step
        title += "\nmean over the steps: " + ", ".join(
            f"{name} {share:.0%}" for name, share in zip(run.levels, shares[:, 1:].mean(axis=1)))
    ax.set(xlabel=TIME_LABEL, ylabel="share of the cells (dimensionless)", ylim=(0.0, 1.0),
           title=title)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.17), ncols=count)
    return ax


def indicator_map(ds, indicator="realizability", ax=None):
    """An x-t map of one indicator of a space run's hierarchy, on a logarithmic scale.

    The indicator of every cell after every step (as :func:`~granframe.tools.plot_space.field_map`), with its
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
    run = RunData.of(ds)
    run.hierarchical("indicator_map")
    if indicator not in LEVEL_INDICATORS:
        check.reject("indicator_map", "indicator", indicator,
                     f"must be one of {', '.join(LEVEL_INDICATORS)}")
    symbol, words = LEVEL_INDICATORS[indicator]
    ax = axes_for(ax, run)
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
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=TIME_LABEL,
           xlim=(0.0, run.space.length),
           title=f"{words} {symbol}(t, x): {largest}\n(log scale; blank: not measured)")
    return ax
