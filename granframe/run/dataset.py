"""A run store as an :class:`xarray.Dataset`: checked first, cut to its last commit, labelled.

:func:`open_run` reads what a store has committed and nothing else: the store is refused
when it is damaged or was never completed, and every array is cut to the snapshots and
moment records that ``progress`` names, so a commit cut short by a kill never shows. The
attributes follow the CF conventions and hold only strings, numbers and lists of them
(``flag_values`` an int64 array, the type of its variable), so
``open_run(path).to_netcdf(out)`` writes a netCDF-4 file as it is.
"""

from __future__ import annotations

import os

import numpy
import xarray

from granframe import validators as check
from granframe.run.storage import (LEVEL_LONG_NAMES, SNAPSHOT_ARRAYS, RunStore,
                                   StoreDamagedError, array_attributes, flat_attributes,
                                   root_attributes, summarise)

#: the coordinate of a space run's wall records: the wall at x = 0, then at x = ell
WALLS = ("left", "right")
#: the sides of a rectangle, in the order of its wall records
SIDES = WALLS + ("bottom", "top")
#: the time axes :func:`open_run` can name ``time``: the snapshots' (the default) or the
#: steps'
TIME_AXES = ("snapshots", "steps")


def open_run(path, *, time_axis: str = "snapshots") -> xarray.Dataset:
    """The committed contents of the run store ``path``, as a labelled dataset.

    The store is checked the way ``granframe info`` checks it: its metadata, every
    committed chunk present, and the small arrays (everything but ``f``) read against
    their checksums. Nothing of the run's description is built, so a store written on
    a GPU (``backend = {name = "cupy"}``) opens on a machine without CuPy.

    Parameters
    ----------
    path : str or os.PathLike
        A granframe run store (``granframe run ... --out PATH``).
    time_axis : {"snapshots", "steps"}
        Which time axis is called ``time``. ``"snapshots"`` (the default): the snapshots
        of f are along ``time`` and the records of every step along ``step_time``, as
        :func:`run_dataset` describes. ``"steps"``: the records of every step (the
        moments, a space run's fields and wall records) are along ``time`` and the
        snapshots along ``snapshot_time`` (:func:`steps_on_time`), so that
        ``ds.temperature.sel(time=t)`` selects the step at time t; every output time is a
        step, so ``ds.f.sel(snapshot_time=t)`` is f there.

    Returns
    -------
    xarray.Dataset
        The store's arrays under their own names, ``f`` read lazily (a snapshot when
        used), labelled as :func:`run_dataset` and, for a space run, :func:`label_space` list.

    Raises
    ------
    TypeError
        ``path`` is not a path.
    ValueError
        ``time_axis`` is not one of :data:`TIME_AXES`.
    granframe.run.storage.StoreError
        ``path`` is not a granframe run store, or its replacement was cut short
        (``--resume`` completes it).
    granframe.run.storage.StoreDamagedError
        A committed chunk is missing or fails its checksum, or the store holds no
        commit (its creation was cut short). A damaged chunk of ``f`` raises when it
        is read (``granframe check`` reads them all).

    Examples
    --------
    >>> import granframe
    >>> ds = granframe.open_run("runs/h.zarr")                  # doctest: +SKIP
    >>> ds.temperature.sel(step_time=1.0).item()                # doctest: +SKIP
    >>> ds.f.isel(time=-1).plot()                               # doctest: +SKIP
    >>> ds.to_netcdf("h.nc")                                    # doctest: +SKIP
    >>> steps = granframe.open_run("runs/sod.zarr", time_axis="steps")  # doctest: +SKIP
    >>> steps.temperature.sel(time=0.1, method="nearest")      # doctest: +SKIP
    """
    if not isinstance(path, (str, os.PathLike)):
        check.reject("open_run", "path", path, "must be the path (str or os.PathLike) of a "
                     "granframe run store", error=TypeError)
    if time_axis not in TIME_AXES:
        check.reject("open_run", "time_axis", time_axis,
                     f"must be one of {', '.join(repr(a) for a in TIME_AXES)}")
    dataset = run_dataset(_checked_store(path))
    return steps_on_time(dataset) if time_axis == "steps" else dataset


def _checked_store(path) -> RunStore:
    """The run store ``path`` opened, its small arrays verified and its first commit made:
    :class:`~granframe.run.storage.StoreDamagedError` otherwise (:func:`open_run`)."""
    store = RunStore.open(path)
    problems = store.verify([name for name in sorted(store.group.array_keys()) if name != "f"])
    if problems:
        raise StoreDamagedError(f"open_run: store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    if store.snapshot_count == 0:
        raise StoreDamagedError(f"open_run: store '{path}' holds no commit: its creation was "
                                "cut short (a store is put in place with its first commit); "
                                "run it again")
    return store


def steps_on_time(dataset: xarray.Dataset) -> xarray.Dataset:
    """``dataset`` (as :func:`open_run` gives it) with the steps' time axis named ``time``.

    The records of every step (``step_time``: the moments, a space run's fields and wall
    records, ``step`` and ``dt``) move to ``time``, and the snapshots of f (``time``) to
    ``snapshot_time``; nothing is read or copied. ``open_run(path, time_axis="steps")``
    opens a store this way; this function does it to a dataset already open, or to one
    from :func:`granframe.run_in_memory`.

    Examples
    --------
    >>> import granframe
    >>> from granframe.run.dataset import steps_on_time
    >>> ds = steps_on_time(granframe.run_in_memory(description))   # doctest: +SKIP
    >>> ds.temperature.sel(time=0.1, method="nearest").plot()     # doctest: +SKIP
    """
    return dataset.rename({"time": "snapshot_time"}).rename({"step_time": "time"})


def run_dataset(store: RunStore) -> xarray.Dataset:
    """The committed contents of an open :class:`RunStore` (on disk or in memory), labelled;
    ``f`` is read lazily from the store.

    The dataset (:func:`open_run` gives it) has:

    - dimensions ``time`` (committed snapshots), ``step_time`` (committed moment
      records, one per step, t = 0 first), ``v1`` ... ``vd``, ``axis`` (d) and
      ``axis2`` (d, the second index of ``pressure_tensor``);
    - coordinates ``time``, ``step_time``, ``v1`` ... ``vd`` (the grid points),
      ``axis`` (the names ``v1`` ... ``vd``, the components of ``momentum``,
      ``heat_flux`` and the rows of ``pressure_tensor``) and ``axis2`` (the same names,
      the columns of ``pressure_tensor``);
    - the moment records along ``step_time``: the scalars (``mass``, ``temperature``,
      ...), ``momentum`` and ``heat_flux`` q_i = int (v-u)_i |v-u|^2 f dv / 2
      (``step_time``, ``axis``) and ``pressure_tensor``
      P_ij = int (v-u)_i (v-u)_j f dv (``step_time``, ``axis``, ``axis2``); a store
      written before granframe recorded the last two has neither (nor ``axis2``);
    - per variable, ``long_name`` and ``units`` ("1": every quantity is
      dimensionless, the root attribute ``nondimensionalisation`` says in which
      units);
    - root attributes ``title``, ``source``, ``history``, ``Conventions``,
      ``references``, ``nondimensionalisation``, ``granframe_schema``,
      ``description_toml`` (the run's description as TOML text), the flattened
      ``provenance_*``, ``rescaling_*`` (rescaled runs) and ``f0_projection_*``,
      and ``progress_*``, the state of the last commit (``progress_status``:
      finished, running, interrupted or failed; ``progress_resolution_*`` and
      ``progress_accuracy_*``, the resolution indicators and the accuracy monitors
      of :mod:`granframe.run.monitors`: ``progress_accuracy_values_temperature``,
      ``progress_accuracy_flagged_step``, ``progress_accuracy_warnings``, ...).

    A space run's dataset has, besides, what :func:`label_space` describes.
    """
    meta = store.metadata
    dataset = committed(store).drop_encoding()   # the zarr codecs and chunks: no netCDF encoding
    names = [f"v{i + 1}" for i in range(dataset.sizes["axis"])]
    dataset = dataset.assign_coords(axis=names)
    if "axis2" in dataset.dims:
        dataset = dataset.assign_coords(axis2=names)
    space = "space" in meta
    if "wall" in dataset.dims:
        dataset = dataset.assign_coords(wall=list(SIDES[:dataset.sizes["wall"]]))
    for name, variable in dataset.variables.items():
        variable.attrs = array_attributes(name, space)
    vector = "the bulk velocity" if space else "momentum"
    dataset["axis"].attrs = {"long_name": f"velocity component of {vector}, heat flux and "
                                          "the first index of the pressure tensor"}
    if "axis2" in dataset.dims:
        dataset["axis2"].attrs = {"long_name": "velocity component of the second index of "
                                               "the pressure tensor"}
    label_space(dataset, meta)
    dataset.attrs = {**root_attributes(meta), **flat_attributes("progress", meta["progress"])}
    return dataset


def label_space(dataset: xarray.Dataset, meta: dict) -> None:
    """Give the wall coordinate and the hierarchy records of a space run their attributes,
    in place (nothing for a space-homogeneous run: no ``wall`` and no ``level``).

    A space run's store (its metadata has a ``space`` entry) has, besides what
    :func:`run_dataset` lists:

    - dimensions ``x`` (the cells) and ``wall`` (2), with coordinates ``x`` (the cell
      centres (j + 1/2) ell / cells, long name "cell centre") and ``wall``
      (``"left"``, ``"right"``: the walls at x = 0 and x = ell); ``f`` is
      (``time``, ``x``, ``v1`` ... ``vd``), the cell averages; on a rectangle the
      dimensions ``x`` and ``y`` (coordinates the cell centres along each) and ``wall``
      (4: ``"left"``, ``"right"``, ``"bottom"``, ``"top"``, at x = 0, x = L_x, y = 0,
      y = L_y), ``f`` (``time``, ``x``, ``y``, ``v1`` ... ``vd``) and the fields
      (``step_time``, ``x``, ``y``, ...); a wall's totals are then per unit length
      along z, the face fluxes summed along its side;
    - the fields of every cell along (``step_time``, ``x``, ...): ``density``,
      ``velocity``, ``temperature``, ``pressure_tensor`` and ``heat_flux``;
    - the totals over the interval: ``mass`` int int f dv dx, ``kinetic_energy``,
      ``min_f`` and ``negative_mass_fraction``;
    - ``wall_mass`` and ``wall_energy`` (``step_time``, ``wall``): the mass and the
      energy that entered the interval through each wall over the step (a
      time-integrated flux, positive inwards; 0 at t = 0), so that
      m(t) - m(0) = the sum of ``wall_mass`` up to t;
    - ``wall_momentum`` (``step_time``, ``wall``, ``axis``): the momentum, components
      ``v1`` (normal) ... ``vd`` (tangential), that entered through each wall over the
      step (positive along +v_i; 0 at t = 0). Divided by ``dt`` it is the force per
      unit area of the wall on the gas; the gas acts on the wall with minus it: the
      ``v1`` component is the pressure on the left wall and minus the pressure on the
      right one, the tangential components are minus the shear stress on the wall
      (docs/space.md, "Wall pressure and shear stress");
    - with a hierarchy of collision models (``space.hierarchy``), ``level``
      (``step_time``, ``x``), int64: the collision model of each cell over the step,
      its index in the hierarchy's levels, whose names are the attribute ``levels``
      (and, in the CF style, ``flag_values`` 0 ... n-1 and ``flag_meanings``, the
      names separated by spaces; :func:`label_levels`); ``realizability`` and
      ``distance`` (``step_time``, ``x``): the indicators kappa and delta that chose
      it, measured after the collision step (NaN at t = 0).
    """
    if "wall" in dataset.dims and dataset.sizes["wall"] == 2:
        dataset["wall"].attrs = {"long_name": "wall of the interval [0, ell]: left at x = 0, "
                                              "right at x = ell"}
    elif "wall" in dataset.dims:
        dataset["wall"].attrs = {"long_name": "side of the rectangle [0, Lx] x [0, Ly]: left "
                                              "at x = 0, right at x = Lx, bottom at y = 0, "
                                              "top at y = Ly"}
    if "level" in dataset:
        label_levels(dataset, meta["description"]["space"]["hierarchy"]["levels"])


def label_levels(dataset: xarray.Dataset, levels: list) -> None:
    """Give the records of a hierarchy of collision models in ``dataset`` their attributes.

    Parameters
    ----------
    dataset : xarray.Dataset
        A space run's dataset with the arrays ``level``, ``realizability``, ``distance``
        and ``reach``; their attributes are set in place.
    levels : list of dict
        The hierarchy's levels as the stored description has them
        (``description["space"]["hierarchy"]["levels"]``), each a table with a ``name``,
        cheapest first.
    """
    names = [level["name"] for level in levels]
    for name, long_name in LEVEL_LONG_NAMES.items():
        dataset[name].attrs = {"long_name": long_name, "units": "1"}
    dataset["level"].attrs.update(levels=names,
                                  flag_values=numpy.arange(len(names), dtype=numpy.int64),
                                  flag_meanings=" ".join(names))


def committed(store: RunStore) -> xarray.Dataset:
    """The arrays of ``store`` as ``xarray.open_zarr`` shows them (its own attributes),
    cut to the snapshots and records of the last commit; ``f`` is read lazily.

    A commit cut short (a kill) may leave the arrays along ``time`` or ``step_time``
    resized to different lengths, which one ``open_zarr`` of the whole store refuses;
    each array is then opened alone, cut, and the cut arrays merged.
    """
    cut = {"time": slice(0, store.snapshot_count),
           "step_time": slice(0, int(store.progress["records"]))}
    location, group = store.location, store.group
    lengths = [{group[name].shape[0] for name in names}
               for names in (SNAPSHOT_ARRAYS, store.record_arrays)]
    if all(len(found) == 1 for found in lengths):
        dataset = xarray.open_zarr(location, consolidated=False, chunks=None)
        return dataset.isel(cut)
    names = sorted(group.array_keys())
    parts = [xarray.open_zarr(location, consolidated=False, chunks=None,
                              drop_variables=[other for other in names if other != name])
             .isel(cut, missing_dims="ignore") for name in names]
    return xarray.merge(parts, combine_attrs="override")
