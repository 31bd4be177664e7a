"""A run store as an :class:`xarray.Dataset`: checked first, cut to its last commit, labelled.

:func:`open_run` reads what a store has committed and nothing else: the store is refused
when it is damaged or was never completed, and every array is cut to the snapshots and
moment records that ``progress`` names, so a commit cut short by a kill never shows. The
attributes follow the CF conventions and hold only strings, numbers and lists of them,
so ``open_run(path).to_netcdf(out)`` writes a netCDF-4 file as it is.
"""

from __future__ import annotations

import os

import xarray

from granframe import validators as check
from granframe.run.storage import (RunStore, StoreDamagedError, array_attributes,
                                   flat_attributes, root_attributes, summarise)


def open_run(path) -> xarray.Dataset:
    """The committed contents of the run store ``path``, as a labelled dataset.

    The store is checked the way ``granframe info`` checks it: its metadata, every
    committed chunk present, and the small arrays (everything but ``f``) read against
    their checksums. Nothing of the run's description is built, so a store written on
    a GPU (``backend = {name = "cupy"}``) opens on a machine without CuPy.

    Parameters
    ----------
    path : str or os.PathLike
        A granframe run store (``granframe run ... --out PATH``).

    Returns
    -------
    xarray.Dataset
        The store's arrays under their own names, ``f`` read lazily (a snapshot is
        read when used):

        - dimensions ``time`` (committed snapshots), ``step_time`` (committed moment
          records, one per step, t = 0 first), ``v1`` ... ``vd`` and ``axis`` (d);
        - coordinates ``time``, ``step_time``, ``v1`` ... ``vd`` (the grid points) and
          ``axis`` (the names ``v1`` ... ``vd``, the components of ``momentum``);
        - per variable, ``long_name`` and ``units`` ("1": every quantity is
          dimensionless, the root attribute ``nondimensionalisation`` says in which
          units);
        - root attributes ``title``, ``source``, ``history``, ``Conventions``,
          ``references``, ``nondimensionalisation``, ``granframe_schema``,
          ``description_toml`` (the run's description as TOML text), the flattened
          ``provenance_*``, ``rescaling_*`` (rescaled runs) and ``f0_projection_*``,
          and ``progress_*``, the state of the last commit (``progress_status``:
          finished, running, interrupted or failed).

    Raises
    ------
    TypeError
        ``path`` is not a path.
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
    """
    if not isinstance(path, (str, os.PathLike)):
        check.reject("open_run", "path", path, "must be the path (str or os.PathLike) of a "
                     "granframe run store", error=TypeError)
    store = RunStore.open(path)
    problems = store.verify([name for name in sorted(store.group.array_keys()) if name != "f"])
    if problems:
        raise StoreDamagedError(f"open_run: store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    meta = store.metadata
    snapshots, records = store.snapshot_count, int(store.progress["records"])
    if snapshots == 0:
        raise StoreDamagedError(f"open_run: store '{path}' holds no commit: its creation was "
                                "cut short (a store is put in place with its first commit); "
                                "run it again")
    dataset = xarray.open_zarr(store.path, consolidated=False, chunks=None)
    dataset = dataset.isel(time=slice(0, snapshots), step_time=slice(0, records))
    dataset = dataset.drop_encoding()       # the zarr codecs and chunks: no netCDF encoding
    dimension = dataset.sizes["axis"]
    dataset = dataset.assign_coords(axis=[f"v{i + 1}" for i in range(dimension)])
    for name, variable in dataset.variables.items():
        variable.attrs = array_attributes(name)
    dataset["axis"].attrs = {"long_name": "velocity component of momentum"}
    dataset.attrs = {**root_attributes(meta), **flat_attributes("progress", meta["progress"])}
    return dataset
