"""What a run store holds, by name: its schema, array names, long names and CF attributes.

The names of the snapshot and record arrays (:data:`SNAPSHOT_ARRAYS`,
:data:`RECORD_ARRAYS`, and :data:`FIRST_RECORD_ARRAYS` of the stores written before the
pressure tensor and heat flux were recorded), the chunk sizes along ``time`` and
``step_time``, the cells axis, the CF ``long_name`` of every array
(:func:`array_attributes`) and the flat CF attributes of the root
(:func:`root_attributes`) that :func:`granframe.open_run` and ``xarray.open_zarr`` show.
Nothing here touches a store.
"""

from __future__ import annotations

import datetime
import json

from granframe.abc.space import AXIS_NAMES
from granframe.validators import is_real

SCHEMA = "granframe.run/2"
SWEEP_SCHEMA_KEY = "granframe_sweep"
SCALAR_MOMENTS = ("mass", "temperature", "kinetic_energy", "min_f", "negative_mass_fraction",
                  "kurtosis", "sonine_a2")
#: arrays along the snapshot dimension ``time`` and along ``step_time``
SNAPSHOT_ARRAYS = ("f", "time", "snapshot_step", "snapshot_dt_next")
#: moments with d or d x d components, recorded every step beside ``momentum``
TENSOR_MOMENTS = ("pressure_tensor", "heat_flux")
#: the moments recorded after every step, and the record arrays: the step and its moments
RECORDED_MOMENTS = ("momentum",) + SCALAR_MOMENTS + TENSOR_MOMENTS
RECORD_ARRAYS = ("step_time", "step", "dt") + RECORDED_MOMENTS
#: the records of a store whose metadata names none (``record_arrays``): written before
#: granframe recorded the pressure tensor and heat flux; it keeps that layout when resumed
FIRST_RECORD_ARRAYS = ("step_time", "step", "dt", "momentum") + SCALAR_MOMENTS
#: the CF long name of each array of a space-homogeneous run (and of a space run's arrays
#: where :data:`SPACE_LONG_NAMES` names none)
LONG_NAMES = {
    "f": "distribution function f(t, v)", "time": "time of the snapshot",
    "snapshot_step": "step index of the snapshot",
    "snapshot_dt_next": "step size proposed after the snapshot",
    "step_time": "time after the step", "step": "step index", "dt": "step size taken",
    "mass": "mass int f dv", "temperature": "temperature int |v-u|^2 f / (d rho)",
    "kinetic_energy": "kinetic energy int |v|^2/2 f dv", "min_f": "minimum of f on the grid",
    "negative_mass_fraction": "int max(-f, 0) dv / int |f| dv",
    "kurtosis": "kurtosis rho int |v-u|^4 f / (int |v-u|^2 f)^2",
    "sonine_a2": "second Sonine coefficient d/(d+2) kurtosis - 1",
    "momentum": "momentum int v f dv",
    "pressure_tensor": "pressure tensor int (v-u)_i (v-u)_j f dv",
    "heat_flux": "heat flux int (v-u)_i |v-u|^2 f dv / 2",
}
#: the long names of the records of a space run with a hierarchy of collision models
#: (``space.hierarchy``; :data:`granframe.run.problems.space.LEVEL_RECORDS`)
LEVEL_LONG_NAMES = {
    "level": "collision model of each cell over the step: its index in space.hierarchy.levels",
    "realizability": "Navier-Stokes realizability indicator kappa = max(|sigma|_F / p, "
                     "|q| / (p sqrt T)) of each cell after the collision step (NaN before "
                     "the first step, infinite where the cell has no equilibrium)",
    "distance": "relative L1 distance delta = sum |f - M[f]| h^d / rho of each cell from its "
                "local Maxwellian after the collision step (NaN before the first step and "
                "where the cell has no equilibrium)",
    "reach": "cells on each side that the level of each cell reaches in the next choice: "
             "max(buffer, free_paths x eps sqrt(2T) / nu_s / dx)",
}

#: the long names of a space run's arrays where they differ from :data:`LONG_NAMES`: the
#: fields are per cell (rho, u, T, P, q of the cell average of f), the totals are
#: integrals over x as well, and the wall records what entered [0, ell] through each
#: wall over one step (time-integrated fluxes, positive inwards)
SPACE_LONG_NAMES = {
    **LEVEL_LONG_NAMES,
    "f": "distribution function f(t, x, v), cell averages",
    "x": "cell centre",
    "y": "cell centre along y",
    "mass": "total mass int int f dv dx",
    "kinetic_energy": "total kinetic energy int int |v|^2/2 f dv dx",
    "min_f": "minimum of f over the cells and the grid",
    "negative_mass_fraction": "int int max(-f, 0) dv dx / int int |f| dv dx",
    "density": "density rho = int f dv of each cell",
    "velocity": "bulk velocity u = int v f dv / rho of each cell",
    "temperature": "temperature int |v-u|^2 f dv / (d rho) of each cell",
    "pressure_tensor": "pressure tensor int (v-u)_i (v-u)_j f dv of each cell",
    "heat_flux": "heat flux int (v-u)_i |v-u|^2 f dv / 2 of each cell",
    "wall_mass": "mass that entered the interval through the wall over the step (the "
                 "time integral of the upwind wall flux int v_1 f dv, positive inwards)",
    "wall_energy": "energy that entered the interval through the wall over the step (the "
                   "time integral of the upwind wall flux int v_1 |v|^2/2 f dv, positive "
                   "inwards)",
    "wall_momentum": "momentum (components v1 ... vd) that entered the interval through the "
                     "wall over the step (the time integral of the upwind wall flux "
                     "int v_1 v f dv, positive along +v_i); per unit time, the force of the "
                     "wall on the gas",
}
#: CF version whose attribute names the stores and :func:`granframe.open_run` use
CONVENTIONS = "CF-1.10"
#: what every quantity is measured in; all are dimensionless (CF's units "1")
NONDIMENSIONALISATION = (
    "All quantities are dimensionless (units 1): granframe solves "
    "d_t f = Q_I(f, f)/eps + tau Delta_v f in reduced variables. Velocities (v1 ... vd) "
    "are in units of a reference thermal speed v0 = sqrt(k_B T_ref / m), so that the "
    "temperature T = int |v-u|^2 f dv / (d rho) is in units of T_ref; f is in units of "
    "n0 / v0^d, so that its mass int f dv is the number density in units of a reference "
    "density n0 (the initial condition sets it, 1 by default); time (time, step_time, dt) "
    "is in units of the collision time in which the kernel reads "
    "B = C |g|^lambda b(cos theta) E^gamma with the constant C of the run's kernel, by "
    "default the review's convention C = 1/(2 pi) in 2D and 1/(4 pi) in 3D (Maxwell "
    "molecules B = 1/(2 pi) in 2D, hard spheres B = |g|/(4 pi) in 3D). The heat bath tau "
    "and the Knudsen number eps are in these units too.")
#: added to :data:`NONDIMENSIONALISATION` for a run in self-similar variables
RESCALED_NOTE = (
    " This run is rescaled (free cooling in self-similar variables, "
    "granframe.equations.rescaled): time and step_time are the rescaled time s, v1 ... vd "
    "the velocities xi and f the profile g(s, xi), with f(t, v) = omega^d g(s, u + omega "
    "(v - u)), omega = exp(rescaling_rate s) and dt/ds = omega^rescaling_degree.")
REFERENCES = (
    "J. A. Carrillo, J. Hu, Z. Ma, T. Rey, Recent development in kinetic theory of "
    "granular materials: analysis and numerical methods, arXiv:2001.11206 (the review); "
    "F. Filbet, L. Pareschi, G. Toscani, J. Comput. Phys. 202 (2005) 216-235; "
    "J. Hu, Z. Ma, J. Comput. Phys. 385 (2019) 119-134")

MOMENT_CHUNK = 4096
SNAPSHOT_CHUNK = 1024
#: the names a space run's cells axis takes in its store (that of the axis the cells lie
#: along, :data:`granframe.abc.space.AXIS_NAMES`): the first dimension after ``time`` of f
#: and after ``step_time`` of the fields; the arrays that have it are written block by block
CELL_AXES = AXIS_NAMES
#: statuses of a run that may be continued
RESUMABLE = ("running", "interrupted")


def now() -> str:
    """The time now, UTC, in ISO 8601: the time stamps of the metadata (``created``,
    ``updated``) and of a writer lock (``since``)."""
    return datetime.datetime.now(datetime.timezone.utc).isoformat()


def array_attributes(name: str, space: bool = False) -> dict:
    """The CF attributes of the array ``name`` of a run store: ``long_name`` and ``units``.

    ``space``: the store of a space run (its metadata has a ``space`` entry), whose
    fields are per cell and whose totals are integrals over x too.
    """
    names = {**LONG_NAMES, **SPACE_LONG_NAMES} if space else LONG_NAMES
    long_name = names.get(name, f"velocity component {name}")
    return {"long_name": long_name, "units": "1"}


def flat_attributes(prefix: str, value) -> dict:
    """``value`` as attributes netCDF accepts: nested dicts become ``prefix_key`` names.

    Strings and numbers are kept (a bool as 0 or 1), a list of numbers or of strings
    stays a list, any other list becomes its JSON text; None and empty lists are left
    out (no attribute).
    """
    if isinstance(value, dict):
        flat = {}
        for key, item in value.items():
            flat.update(flat_attributes(f"{prefix}_{key}", item))
        return flat
    if value is None or (isinstance(value, list) and not value):
        return {}
    if isinstance(value, bool):
        return {prefix: int(value)}
    if isinstance(value, list):
        alike = all(isinstance(v, str) for v in value) or all(map(is_real, value))
        return {prefix: value if alike else json.dumps(value)}
    return {prefix: value}


def root_attributes(meta: dict) -> dict:
    """The flat CF attributes of a run store's root, from its ``granframe`` metadata.

    ``title``, ``source``, ``history``, ``Conventions``, ``references``,
    ``nondimensionalisation``, ``granframe_schema``, ``description_toml``, and the
    provenance, the rescaling and the f0 projection as ``provenance_*``,
    ``rescaling_*`` and ``f0_projection_*`` scalars. The same for every store of one
    description; what changes with each commit (``progress``) is not among them.
    """
    description = meta["description"]
    note = NONDIMENSIONALISATION + (RESCALED_NOTE if "rescaling" in meta else "")
    return {
        "title": description.get("title") or "granframe run",
        "source": f"granframe {meta['version']}",
        "history": f"{meta['created']} created by granframe run (granframe "
                   f"{meta['version']}, store schema {meta['schema']})",
        "Conventions": CONVENTIONS, "references": REFERENCES,
        "nondimensionalisation": note, "granframe_schema": meta["schema"],
        "description_toml": meta["description_toml"],
        **flat_attributes("provenance", meta.get("provenance", {})),
        **flat_attributes("rescaling", meta.get("rescaling")),
        **flat_attributes("f0_projection", meta.get("f0_projection")),
    }
