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

A run on a rectangle has one figure of maps per snapshot instead, ``plane_<k>``: the
density, the temperature, the speed with streamlines and the vorticity
(:func:`plane_map`), and with a hierarchy the map of each cell's collision model at that
snapshot (:func:`level_plane`) and the shares of the levels against t.

This module composes the figures and writes them; the drawing functions, importable from
here, are defined by concern in :mod:`granframe.tools.plot_homogeneous`,
:mod:`granframe.tools.plot_space` and :mod:`granframe.tools.plot_hierarchy`, over what
:mod:`granframe.tools.plot_data` reads from the Dataset.
"""

from __future__ import annotations

import math
import pathlib

import numpy
from matplotlib.figure import Figure

from granframe import validators as check
from granframe.tools.plot_data import SPACE_FIELDS, RunData, caption, wrapped
from granframe.tools.plot_hierarchy import (LEVEL_INDICATORS, indicator_map, level_map,
                                            level_plane, level_shares)
from granframe.tools.plot_homogeneous import (contour, entropy, kurtosis, mass_drift, positivity,
                                              slices, temperature, temperature_error)
from granframe.tools.plot_plane import PLANE_FIELDS, animate, plane_map
from granframe.tools.plot_space import field_map, profiles, total_energy, total_mass

#: File formats ``granframe plot --format`` writes.
FORMATS = ("png", "pdf", "svg")

#: Smallest and largest resolution, in dots per inch, of the raster parts of a figure.
DPI_RANGE = (10, 600)

#: Resolution of ``granframe plot`` unless ``--dpi`` says otherwise.
DEFAULT_DPI = 110

_STYLE = {"axes.grid": True, "grid.alpha": 0.3, "font.size": 10, "axes.titlesize": 10,
          "legend.fontsize": 8}

#: Figure name -> (rows, columns), size in inches.
_LAYOUTS = {"temperature": ((1, 2), (11, 4.4)), "entropy": ((1, 1), (8, 5.2)),
            "slices": ((1, 2), (11, 4.4)), "contour": ((1, 2), (11, 5.8)),
            "moments": ((1, 3), (14, 4.2)), "maps": ((2, 3), (15, 8.6)),
            "profiles": ((2, 3), (15, 8.2)), "totals": ((1, 3), (14, 4.2)),
            "levels": ((2, 2), (11, 8.6)), "plane": ((2, 2), (11, 9.0)),
            "plane_levels": ((2, 3), (16, 9.0))}


def _space_panels(run) -> dict:
    """The figures of a space run: name -> the functions drawing their panels; on a
    rectangle one figure of maps (:data:`PLANE_FIELDS`) per snapshot, ``plane_<k>``, and
    the totals."""
    def drawn(function, field):
        return lambda r, ax: function(r, field, ax)

    if run.space.dimension == 2:
        def mapped(field, index):
            return lambda r, ax: plane_map(r, field, index, ax)

        def levels(index):
            return lambda r, ax: level_plane(r, index, ax)

        panels = {f"plane_{k}": tuple(mapped(name, k) for name in PLANE_FIELDS)
                  + ((levels(k), level_shares) if run.levels is not None else ())
                  for k in range(run.count)}
        panels["totals"] = (total_mass, total_energy, positivity)
        return panels

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
    run = RunData.of(ds)
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
    text = wrapped(caption(run, short=True))
    drawn = {}
    for name, draws in panels.items():
        plane = "plane_levels" if len(draws) > 4 else "plane"
        layout, size = _LAYOUTS[plane if name.startswith("plane_") else name]
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


def plot(store, out, *, format="png", dpi=DEFAULT_DPI,
         animation: str | None = None) -> list[pathlib.Path]:
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
    animation : str, optional
        A field of :data:`~granframe.tools.plot_plane.PLANE_FIELDS` of a run on a
        rectangle: also its animation over the snapshots, ``<field>.gif``.

    Returns
    -------
    list of pathlib.Path
        The files written, ``<figure>.<format>`` (on a rectangle ``plane_<k>`` for snapshot
        k, and ``totals``).
    """
    if format not in FORMATS:
        check.reject("plot", "format", format, f"must be one of {', '.join(FORMATS)}")
    low, high = DPI_RANGE
    if not check.is_real(dpi) or not (math.isfinite(dpi) and low <= dpi <= high):
        check.reject("plot", "dpi", dpi, f"must be a number from {low} to {high}")
    import matplotlib

    run = RunData(store)
    if animation is not None and (run.space is None or run.space.dimension != 2
                                  or animation not in PLANE_FIELDS):
        check.reject("plot", "animate", animation, "must name a field of a run on a "
                     f"rectangle: one of {', '.join(PLANE_FIELDS)}")
    with matplotlib.rc_context(_STYLE):
        drawn = figures(run)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in drawn.items():
        path = out / f"{name}.{format}"
        fig.savefig(path, format=format, dpi=dpi)
        written.append(path)
    if animation is not None:
        with matplotlib.rc_context(_STYLE):
            written.append(animate(run, out / f"{animation}.gif", animation, dpi=dpi))
    return written
