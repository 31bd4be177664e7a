"""The figures of a run on a rectangle: maps of its fields on (x, y) at a snapshot time, the
speed with the streamlines of the bulk velocity, the vorticity, and an animation of one
field over the snapshots.

The fields are those recorded after the step that ends at the snapshot's time (the
records of every step, :func:`~granframe.run.problems.spaces.space_layout`). The vorticity
omega = d_x u_2 - d_y u_1 is taken by second-order centred differences of the cell
velocities (one-sided at a wall, periodic across a periodic side): a picture of the flow,
not a result of the scheme.
"""

from __future__ import annotations

import numpy

from granframe import validators as check
from granframe.tools.plot_data import RunData, axes_for

#: The maps of a run on a rectangle: name -> (symbol, words, diverging colour map).
PLANE_FIELDS = {
    "density": (r"$\rho$", "density", False),
    "temperature": ("$T$", "temperature", False),
    "speed": (r"$|u|$", "speed, with the streamlines of u", False),
    "vorticity": (r"$\omega = \partial_x u_2 - \partial_y u_1$", "vorticity", True),
}


def rectangle_run(ds, owner: str, hint: str = ""):
    """The :class:`RunData` of ``ds``, refused in ``owner`` unless a run on a rectangle
    (``hint`` added to the message)."""
    run = RunData.of(ds)
    if run.space is None or run.space.dimension != 2:
        check.reject(owner, "ds", run.title, "must be the store of a run on a rectangle "
                     f"(space.cells = [Cx, Cy]){hint}")
    return run


def check_snapshot(run, owner: str, index) -> None:
    """Refuse in ``owner`` an ``index`` that is not a snapshot of ``run``."""
    if not check.is_integer(index) or not -run.count <= index < run.count:
        check.reject(owner, "index", index, f"must be a snapshot index from {-run.count} to "
                     f"{run.count - 1}")


def record_at(run, time: float) -> int:
    """The index of the record at ``time`` (a snapshot's): the last one at or before it."""
    return int(numpy.searchsorted(run.step_time, time * (1 + 1e-12), side="right") - 1)


def _periodic(run) -> tuple:
    """Whether the sides of x and of y are periodic."""
    space = run.space
    return (space.wall("left").name == "periodic", space.wall("bottom").name == "periodic")


def _derivative(values, spacing: float, axis: int, periodic: bool):
    """d values / d axis by centred differences: periodic across a periodic side, one-sided
    (second order) at a wall."""
    if periodic:
        return (numpy.roll(values, -1, axis) - numpy.roll(values, 1, axis)) / (2 * spacing)
    return numpy.gradient(values, spacing, axis=axis, edge_order=2)


def plane_field(run, field: str, index: int):
    """The values (C_x, C_y) of ``field`` (:data:`PLANE_FIELDS`) at snapshot ``index``, and
    the velocity (C_x, C_y, 2) there."""
    row = record_at(run, float(run.times[index]))
    velocity = numpy.asarray(run.ds["velocity"].values[row])[..., :2]
    if field in ("density", "temperature"):
        return numpy.asarray(run.ds[field].values[row]), velocity
    if field == "speed":
        return numpy.hypot(velocity[..., 0], velocity[..., 1]), velocity
    dx, dy = run.space.spacing
    across_x, across_y = _periodic(run)
    vorticity = (_derivative(velocity[..., 1], dx, 0, across_x)
                 - _derivative(velocity[..., 0], dy, 1, across_y))
    return vorticity, velocity


def plane_map(ds, field="density", index=-1, ax=None):
    """A map of one field of a run on a rectangle at one snapshot time.

    Parameters
    ----------
    ds : xarray.Dataset or RunData
        The Dataset of the store of a run on a rectangle.
    field : str
        One of :data:`PLANE_FIELDS`: ``density``, ``temperature``, ``speed`` (drawn with the
        streamlines of the bulk velocity) or ``vorticity``.
    index : int
        The snapshot (negative: from the last).
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = rectangle_run(ds, "plane_map")
    if field not in PLANE_FIELDS:
        check.reject("plane_map", "field", field,
                     f"must be one of {', '.join(PLANE_FIELDS)}{check.did_you_mean(field, PLANE_FIELDS)}")
    check_snapshot(run, "plane_map", index)
    symbol, words, signed = PLANE_FIELDS[field]
    values, velocity = plane_field(run, field, index)
    x, y = run.ds["x"].values, run.ds["y"].values
    ax = axes_for(ax, run)
    options = {"cmap": "viridis", "shading": "nearest"}
    if signed:
        top = float(numpy.nanmax(numpy.abs(values))) or 1.0
        options.update(cmap="RdBu_r", vmin=-top, vmax=top)
    mesh = ax.pcolormesh(x, y, values.T, **options)
    ax.figure.colorbar(mesh, ax=ax, label=symbol)
    if field == "speed" and numpy.nanmax(values) > 0:
        ax.streamplot(x, y, velocity[..., 0].T, velocity[..., 1].T, color="white",
                      linewidth=0.6, density=1.0, arrowsize=0.6)
    (lx, ly) = run.space.lengths
    ax.set(xlabel="x", ylabel="y", xlim=(0.0, lx), ylim=(0.0, ly), aspect="equal",
           title=f"{words} at t = {float(run.times[index]):.4g}")
    return ax


def animate(ds, out, field="density", *, fps: float = 4.0, dpi: float = 110):
    """An animation of one field of a run on a rectangle over its snapshots, written as a
    GIF (matplotlib's Pillow writer): one frame per snapshot, one colour scale for all.

    Parameters
    ----------
    ds : xarray.Dataset, RunData or path
        A run on a rectangle.
    out : str or pathlib.Path
        The GIF file to write.
    field : str
        One of :data:`PLANE_FIELDS`.
    fps : float
        Frames per second.

    Returns
    -------
    pathlib.Path
        ``out``.
    """
    import pathlib

    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    run = rectangle_run(ds, "animate")
    if field not in PLANE_FIELDS:
        check.reject("animate", "field", field, f"must be one of {', '.join(PLANE_FIELDS)}")
    if not check.is_real(fps) or not 0.1 <= fps <= 60:
        check.reject("animate", "fps", fps, "must be a number from 0.1 to 60")
    frames = [plane_field(run, field, k)[0] for k in range(run.count)]
    low = min(float(numpy.nanmin(f)) for f in frames)
    high = max(float(numpy.nanmax(f)) for f in frames)
    symbol, words, signed = PLANE_FIELDS[field]
    if signed:
        high = max(abs(low), abs(high)) or 1.0
        low = -high
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    ax = fig.add_subplot()
    x, y = run.ds["x"].values, run.ds["y"].values
    mesh = ax.pcolormesh(x, y, frames[0].T, shading="nearest", vmin=low, vmax=high,
                         cmap="RdBu_r" if signed else "viridis")
    fig.colorbar(mesh, ax=ax, label=symbol)
    ax.set(xlabel="x", ylabel="y", aspect="equal")

    def frame(k):
        mesh.set_array(frames[k].T.ravel())
        ax.set_title(f"{run.title}: {words} at t = {float(run.times[k]):.4g}")
        return (mesh,)

    out = pathlib.Path(out)
    FuncAnimation(fig, frame, frames=run.count).save(out, writer=PillowWriter(fps=fps),
                                                      dpi=dpi)
    return out
