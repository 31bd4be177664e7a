"""Memory budgets: what a run and its collision operator may allocate, checked beforehand.

A 3D grid of N = 1024 holds 8 GiB per copy of f, and the operators' tables are tens
of such copies; allocating first would end in the out-of-memory killer. So the
operators estimate their bytes before allocating
(:meth:`granframe.CollisionOperator.estimate_memory`) and refuse past their
``memory_budget``, and :func:`check_run_memory` refuses a run whose estimate
(:func:`run_memory`) exceeds :func:`budget` before anything is built.

The budget is the environment variable ``GRANFRAME_MEMORY_BUDGET`` (bytes) when it is
set, else :data:`DEFAULT_BUDGET` for a run and each operator's own default for its
``memory_budget``. A fixed default, not a share of this machine's memory, keeps a
description valid or not alike on every machine (a run refused on a laptop is refused
on the cluster too, until the variable says otherwise).
"""

from __future__ import annotations

import inspect
import math
import os

from granframe import validators as check

#: Environment variable that overrides every default budget (a number of bytes).
ENVIRONMENT_VARIABLE = "GRANFRAME_MEMORY_BUDGET"

#: Bytes a run may use when GRANFRAME_MEMORY_BUDGET is not set: 4 GiB, what a laptop or a
#: CI runner can give one run; every study and test of granframe needs far less.
DEFAULT_BUDGET = 4 * 2 ** 30


def gib(nbytes: float) -> str:
    """``nbytes`` in GiB, three significant digits."""
    return f"{nbytes / 2 ** 30:.3g}"


def budget(default: int = DEFAULT_BUDGET) -> int:
    """GRANFRAME_MEMORY_BUDGET in bytes when set (a positive number, e.g. 8e9), else ``default``."""
    text = os.environ.get(ENVIRONMENT_VARIABLE)
    if text is None:
        return default
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 1):
        check.reject("environment", ENVIRONMENT_VARIABLE, text,
                     "must be a positive number of bytes, e.g. 8e9")
    return int(value)


def integrator_copies(integrator) -> int:
    """Copies of f a time integrator holds in one step: 2 per stage (the stage value and the
    combination in progress, or the explicit and implicit terms of an IMEX stage) and 4 more
    (f, the result, and what an embedded error estimate or an integrating factor keeps)."""
    tableau = getattr(integrator, "tableau", None) or getattr(integrator, "explicit", None)
    stages = len(tableau.b) if tableau is not None else 4
    return 2 * stages + 4


#: Copies of f a run holds besides the integrator's: the sampled and projected f0, the
#: equation's right-hand side (Q, the heat bath term and their sum), the host copy of a
#: snapshot, and the moment computations (|v|^2, |v - u|^2 and a product).
RUN_COPIES = 2 + 3 + 1 + 3


#: Copies of every cell's f a space run holds throughout its steps: f0 on the host, the
#: block array with its ghost cells, the host copy of a snapshot and a spare for the
#: record's moments.
SPACE_RESIDENT = 4

#: Copies of the cells' f at the peak of the transport sub-step, by reconstruction: the
#: start of the sub-step and its three stage rates, the face values and fluxes, and the
#: reconstruction's temporaries, measured (tracemalloc, NumPy backend, 24 x 24 cells of
#: 2D N = 24 with their ghost strips) 7.1 (upwind), 11.4 (MUSCL) and 17.1 (WENO5).
TRANSPORT_COPIES = {"upwind": 8, "muscl": 12, "weno5": 18}

#: Bytes of the velocity grids padded to 2N per axis in one batch of the resolution report
#: of a space run's cells (:meth:`granframe.velocity.moments.FieldMoments.resolution`).
RESOLUTION_BATCH_BYTES = 16 * 2 ** 20

def resolution_batch(n_modes: int, dimension: int) -> int:
    """Cells per batch of the resolution report: their grids padded to 2N hold at most
    :data:`RESOLUTION_BATCH_BYTES`, and a batch holds at least one cell."""
    return max(1, RESOLUTION_BATCH_BYTES // (8 * (2 * n_modes) ** dimension))


#: Bytes a space run holds besides its copies of f and its operator: the records and
#: reports of its cells, the store's write buffers, the threads' stacks (measured: 1D runs
#: of 2 MiB of f, 23 to 24 MiB above the estimate without it).
SPACE_OVERHEAD = 32 * 2 ** 20

#: Copies of the cells' f the resolution report of a space run holds at an output point
#: (the cells' spectra, their moduli, the outermost shell and f without it), besides its
#: batch of grids padded to 2N (three arrays of
#: :data:`RESOLUTION_BATCH_BYTES`).
REPORT_COPIES = 6


def run_memory(description, backend=None, cells: int | None = None) -> dict:
    """Estimated bytes of a run of ``description``, found without allocating anything large.

    ``backend`` is the run's array backend when it is built already (else the estimate
    builds the description's, for the operator's estimate only); ``cells``: the cells one
    process of a space run owns (all of them by default).

    Returns ``f`` (bytes of one float64 copy of f; of every cell's f in a space run),
    ``copies`` (:func:`integrator_copies` + :data:`RUN_COPIES`; in a space run, whose
    transport and collision sub-steps never hold their temporaries at once,
    :data:`SPACE_RESIDENT` + max(:func:`integrator_copies` + 3,
    :data:`TRANSPORT_COPIES` of its reconstruction), the 3 the equation's right-hand side,
    or the resolution report's :data:`REPORT_COPIES` and its padded batch, whichever is
    larger, and :data:`SPACE_OVERHEAD`; docs/space.md, "Memory on a rectangle"),
    ``other`` (in a space run the report's padded batch, :data:`SPACE_OVERHEAD` and f0 of
    the cells other processes own, which every process keeps; else 0), ``operator`` (the
    operator's
    :meth:`~granframe.CollisionOperator.estimate_memory`, 0 when it gives none) and
    ``total``. A space run evaluates Q on the stack of all its cells at once, so the
    operator's estimate is asked for ``distributions`` = cells where it takes that option:
    it then includes the per-cell working arrays of one call (the direct method gathers
    16 bytes per pair of modes and cell: 2D N = 16, 256 cells, measured peak 205 MiB
    against 219 MiB estimated). The operator's estimate raises the operator's own
    errors, among them a ``memory_budget`` too small for it.
    """
    from granframe.registry import default_registries

    d = description
    space = getattr(d, "space", None)
    cells = None if space is None else (math.prod(space.counts) if cells is None else cells)
    stepping = integrator_copies(d.build("integrator"))
    need = {"f": 8 * d.grid.n_modes ** d.grid.dimension * (1 if space is None else cells),
            "operator": 0}
    if space is None:
        need["copies"], report = stepping + RUN_COPIES, 0
    else:
        step = max(stepping + 3, TRANSPORT_COPIES.get(space.reconstruction.name,
                                                      max(TRANSPORT_COPIES.values())))
        n, dim = d.grid.n_modes, d.grid.dimension
        report = 3 * min(cells, resolution_batch(n, dim)) * 8 * (2 * n) ** dim
        # the step's copies, or the report's at an output point, whichever is larger
        if REPORT_COPIES * need["f"] + report > step * need["f"]:
            need["copies"] = SPACE_RESIDENT + REPORT_COPIES
        else:
            need["copies"], report = SPACE_RESIDENT + step, 0
    # every process keeps f0 of all cells (its copy among the resident ones is its own)
    others = 0 if space is None else math.prod(space.counts) - cells
    need["other"] = report + (0 if space is None else SPACE_OVERHEAD
                              + 8 * d.grid.n_modes ** d.grid.dimension * others)
    need["total"] = need["f"] * need["copies"] + need["other"]
    if need["total"] <= budget():   # else too much already, whatever the operator needs
        factory = default_registries().get("collision_operators", d.operator.name).factory
        estimate = getattr(factory, "estimate_memory", None)
        if estimate is not None:
            options = d.operator_options()
            if space is not None and "distributions" in inspect.signature(estimate).parameters:
                options["distributions"] = cells
            need["operator"] = _operator_need(estimate, d, backend, options)
            need["total"] += need["operator"]
    return need


def _operator_need(estimate, description, backend, options) -> int:
    """The operator's estimate of its bytes for the run (0 when it gives none). An
    operator whose own ``memory_budget`` (the run's budget, unless the description sets
    it) is too small for it refuses in its estimate; the run's need is then the
    operator's without that limit beside the copies of f, so that the run is refused
    with its whole need (:func:`check_run_memory`), not with the operator's share of it."""
    d = description
    arguments = (d.grid, d.build("kernel"), d.build("restitution"),
                 d.build("backend") if backend is None else backend)
    try:
        return estimate(*arguments, **options) or 0
    except ValueError:
        unset = ("memory_budget" in inspect.signature(estimate).parameters
                 and options.get("memory_budget") is None)
        if not unset:
            raise            # the operator's own refusal of an option the run set
        try:
            return estimate(*arguments, **{**options, "memory_budget": 2 ** 62}) or 0
        except ValueError:
            pass             # not a matter of memory: the operator's first error
        raise


def check_run_memory(description, backend=None, cells: int | None = None,
                     share: int = 1) -> None:
    """Refuse a run whose :func:`run_memory` exceeds :func:`budget`, with the estimate
    (``backend``, ``cells``: as in :func:`run_memory`); ``share``: the processes of the run
    on this host, which divide the budget among themselves."""
    need, limit = run_memory(description, backend, cells), budget() // share
    if need["total"] > limit:
        grid = description.grid
        operator = (f"operator {gib(need['operator'])} GiB + " if need["operator"] else "")
        space = getattr(description, "space", None)
        if space is not None:
            total = math.prod(space.counts)
            process = (f" (the {cells} cells of one of the {share} processes on this host, "
                       "which share the budget)" if share > 1 or cells not in (None, total)
                       else "")
            check.reject("Simulation", "space.cells",
                         list(space.counts) if space.dimension > 1 else space.cells,
                         f"with grid.n_modes = {grid.n_modes} (d = {grid.dimension}) needs "
                         f"about {gib(need['total'])} GiB for this run{process} ({operator}"
                         f"{need['copies']} copies of every cell's f at {gib(need['f'])} GiB), "
                         f"more than the memory budget of {gib(limit)} GiB; use fewer cells "
                         f"or a smaller n_modes, or set {ENVIRONMENT_VARIABLE} (bytes) to "
                         "allow more")
        check.reject("Simulation", "grid.n_modes", grid.n_modes,
                     f"needs about {gib(need['total'])} GiB for this run ({operator}"
                     f"{need['copies']} copies of f at {gib(need['f'])} GiB, "
                     f"d = {grid.dimension}), more than the memory budget of {gib(limit)} "
                     f"GiB; use a smaller n_modes, or set {ENVIRONMENT_VARIABLE} (bytes) to "
                     "allow more")
