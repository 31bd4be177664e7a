"""The figures of a space run: x-t maps and profiles of its fields, and its total mass and
energy with what entered through the walls.
"""

from __future__ import annotations

import numpy

from granframe import validators as check
from granframe.tools.plot_data import (SPACE_FIELDS, RunData, TIME_LABEL, axes_for,
                                       positive_values)


def _space_field(run, owner, field):
    """The entry of :data:`~granframe.tools.plot_data.SPACE_FIELDS` named ``field`` of the space run ``run``."""
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
        rho, u_1, T, P_11 or q_1 (:data:`~granframe.tools.plot_data.SPACE_FIELDS`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (its figure gets the colour bar); a new captioned figure when
        None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = RunData.of(ds)
    _, _, symbol, words, signed = _space_field(run, "field_map", field)
    ax = axes_for(ax, run)
    x, t = run.ds["x"].values, run.step_time
    values = run.field(field)
    style = {"cmap": "viridis"}
    if signed:
        reach = float(numpy.nanmax(numpy.abs(values))) or 1.0
        style = {"cmap": "RdBu_r", "vmin": -reach, "vmax": reach}
    mesh = ax.pcolormesh(x, t, values, shading="nearest", **style)
    ax.figure.colorbar(mesh, ax=ax, label=f"{symbol} (dimensionless)")
    ax.grid(False)
    ax.set(xlabel="position x, cell centres (dimensionless)", ylabel=TIME_LABEL,
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
        rho, u_1, T, P_11 or q_1 (:data:`~granframe.tools.plot_data.SPACE_FIELDS`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new captioned figure when None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    run = RunData.of(ds)
    _, _, symbol, words, _ = _space_field(run, "profiles", field)
    ax = axes_for(ax, run)
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
    run = RunData.of(ds)
    run.inhomogeneous("total_mass")
    ax = axes_for(ax, run)
    mass = run.moments["mass"]
    drift = numpy.abs(mass / mass[0] - 1)
    balance = numpy.abs((mass - mass[0] - _entered(run, "wall_mass")) / mass[0])
    ax.semilogy(run.step_time, positive_values(drift), ".", ms=2, color="C2",
                label=f"drift |m(t)/m(0) - 1|, max {drift.max():.1e}")
    ax.semilogy(run.step_time, positive_values(balance), "x", ms=3, color="C0",
                label=f"balance with the walls, max {balance.max():.1e}")
    ax.axhline(run.description.health.mass_tolerance, color="C3", ls="--", lw=1,
               label="health limit (mass_tolerance)")
    ax.set(xlabel=TIME_LABEL, ylabel=r"relative mass change (dimensionless)",
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
    run = RunData.of(ds)
    run.inhomogeneous("total_energy")
    ax = axes_for(ax, run)
    energy = run.moments["kinetic_energy"]
    walls = energy[0] + _entered(run, "wall_energy")
    ax.plot(run.step_time, energy, color="C1", label="E(t)")
    ax.plot(run.step_time, walls, "--", color="C0",
            label="E(0) + energy entered through the walls")
    gap = float(numpy.abs(energy - walls).max())
    ax.set(xlabel=TIME_LABEL, ylabel="total energy E (dimensionless)",
           title=r"total energy $E = \int\int |v|^2/2\, f\,dv\,dx$" + "\nmax |E(t) - E(0) - "
                 f"entered| = {gap:.2e} (the collision step's)")
    ax.legend()
    return ax
