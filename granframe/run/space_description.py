"""The space section of a run description: the interval in x, its cells, reconstruction
and walls (:class:`Space`), and the hierarchy of collision models chosen cell by cell
(:class:`Hierarchy`).

Both are checked when the description is made: the names against the registries, the
cells against the reconstruction's stencil and the store's chunks, the walls against the
velocity grid and the time step against the transport's CFL limit (:meth:`Space.check`).
:class:`~granframe.run.description.RunDescription` holds a :class:`Space` as its ``space``
(docs/space.md).
"""

from __future__ import annotations

import math

import attrs
import numpy

from granframe import validators as check
from granframe.parallel import store_chunk
from granframe.registry import default_registries
from granframe.run.components import Component, coerce_component, component_field, table_of
from granframe.space.transport import step_limit
from granframe.velocity.grid import SCALE_RANGE

#: Most cells of a space run: 1e9 cells of the smallest grid (2D N = 4) already hold 128 GB
#: per copy of f, so more is a mistake (and it keeps dx = length / cells a float).
MAX_CELLS = 10 ** 9


def _levels(value):
    """The hierarchy's levels as a tuple of :class:`Component` (names or tables)."""
    if isinstance(value, (str, dict, Component)):
        value = [value]
    try:
        return tuple(coerce_component(v) for v in value)
    except TypeError:
        return value


def _floats(value):
    """A tuple of floats from a list (a number alone as one), unchanged when not numbers
    (a string too, which is not a list of its characters)."""
    if check.is_real(value):
        value = [value]
    if not isinstance(value, (list, tuple, numpy.ndarray)):
        return value
    try:
        return tuple(check.to_float(v) for v in value)
    except TypeError:
        return value


@attrs.frozen(kw_only=True)
class Hierarchy:
    r"""Collision models chosen cell by cell (docs/space.md, "The hierarchy";
    :mod:`granframe.space.hierarchy`).

    Parameters
    ----------
    levels : list of Component
        Registered ``collision_models``, from the cheapest to the full operator (the last
        must be one, ``boltzmann``; the others must not): by default
        ``["euler", "esbgk", "boltzmann"]``.
    realizability : list of float
        For each level after the first, the Navier-Stokes realizability indicator kappa
        (the stress and heat flux of the Navier-Stokes closure relative to the pressure)
        above which a cell needs at least that level; positive, non-decreasing, at most 1.
    distance : list of float
        For each level after the first, the relative L1 distance delta of f from its local
        Maxwellian above which a cell (not at the first level) needs at least that level;
        positive, non-decreasing, at most 2 (the largest distance of two densities).
    hysteresis : float
        In (0, 1]: a cell leaves a level downwards only when its indicators are below this
        share of the thresholds.
    buffer : int
        Cells (0 to 64) each level is widened by on each side, at least.
    free_paths : float
        Mean free paths eps sqrt(2T)/nu_s (0 to 100) each level is widened by on each side
        when that is more than ``buffer`` cells: the particles a kinetic cell sends out fly
        about that far before they collide.
    interval : int
        Steps between choices of the levels (1 to 1000).
    """

    levels: tuple = attrs.field(default=(Component("euler"), Component("esbgk"),
                                         Component("boltzmann")), converter=_levels)
    realizability: tuple = attrs.field(default=(0.002, 0.02), converter=_floats)
    distance: tuple = attrs.field(default=(0.002, 0.05), converter=_floats)
    hysteresis: float = attrs.field(default=0.5, converter=check.to_float,
                                    validator=check.real(0.0, 1.0, lower_open=True))
    buffer: int = attrs.field(default=2, converter=check.to_int,
                              validator=check.integer(0, 64))
    free_paths: float = attrs.field(default=2.0, converter=check.to_float,
                                    validator=check.real(0.0, 100.0))
    interval: int = attrs.field(default=1, converter=check.to_int,
                                validator=check.integer(1, 1000))

    def __attrs_post_init__(self):
        owner = "Space"
        levels = self.levels
        if (not isinstance(levels, tuple) or not levels
                or not all(isinstance(c, Component) for c in levels)):
            check.reject(owner, "hierarchy.levels", levels, "must be a list of registered "
                         "collision model names (or tables with a name)", error=TypeError)
        registries = default_registries()
        names = registries.names("collision_models")
        for level in levels:
            if level.name not in names:
                check.reject(owner, "hierarchy.levels", level.name,
                             f"must be one of {names}{check.did_you_mean(level.name, names)}")
        chosen = [c.name for c in levels]
        if len(set(chosen)) != len(chosen):
            check.reject(owner, "hierarchy.levels", chosen, "must not name a level twice")
        full = [registries.get("collision_models", c.name).factory.full for c in levels]
        if len(levels) < 2 or not full[-1] or any(full[:-1]):
            check.reject(owner, "hierarchy.levels", chosen,
                         "must be at least two levels from the cheapest to the full collision "
                         f"operator, which comes last and only last (full: "
                         f"{[c for c, f in zip(chosen, full) if f] or 'none'}); e.g. "
                         "['euler', 'bgk', 'boltzmann']")
        for field, top in (("realizability", 1.0), ("distance", 2.0)):
            values = getattr(self, field)
            if (not isinstance(values, tuple) or len(values) != len(levels) - 1
                    or not all(check.is_real(v) for v in values)):
                check.reject(owner, f"hierarchy.{field}", values,
                             f"must be a list of {len(levels) - 1} numbers, one for each "
                             f"level after the first of {chosen}", error=TypeError)
            if not all(0.0 < v <= top and math.isfinite(v) for v in values) or any(
                    b < a for a, b in zip(values, values[1:])):
                check.reject(owner, f"hierarchy.{field}", list(values),
                             f"must be non-decreasing numbers in (0, {top:g}]")

    def to_dict(self) -> dict:
        return {"levels": [c.to_dict("space.hierarchy.levels") for c in self.levels],
                "realizability": list(self.realizability), "distance": list(self.distance),
                "hysteresis": self.hysteresis, "buffer": self.buffer,
                "free_paths": self.free_paths, "interval": self.interval}


@attrs.frozen(kw_only=True)
class Space:
    r"""The space interval of d_t f + v_1 d_x f = Q(f, f)/eps (+ tau Delta_v f) (docs/space.md).

    Parameters
    ----------
    cells : int
        Finite-volume cells on [0, length]; at least the reconstruction's stencil,
        2 ghost + 1 (3 for ``upwind``, 5 for ``muscl``, 7 for ``weno5``), at most
        :data:`MAX_CELLS`.
    length : float
        ell, in the velocity grid's scale range (1e-50 to 1e50).
    block_cells : int or None
        The width along x of the store's chunks of f and of the fields; a divisor of
        ``cells``, at least the reconstruction's ghost width. A run on several processes
        gives each whole chunks, so it runs on at most cells / block_cells of them. None:
        :meth:`blocks` (about 16 chunks or more, at most 64 cells each).
    reconstruction : Component
        Registered reconstruction of the cell averages (``muscl``, ``weno5``, ``upwind``).
    left, right : Component
        Registered boundaries (``periodic``, ``specular``, ``diffuse`` with
        ``temperature``, ``velocity``, ``accommodation``); periodic at both ends or at
        neither.

    collisions : bool
        False: a collisionless gas (free-molecular flow, d_t f + v_1 d_x f = 0); the
        kernel, the restitution law and the operator are then not built.
    hierarchy : Hierarchy or None
        Collision models chosen cell by cell (a ``[space.hierarchy]`` table); None: the
        full operator in every cell.

    The Knudsen number eps is the description's ``knudsen``.
    """

    cells: int = attrs.field(converter=check.to_int, validator=check.integer(1, MAX_CELLS))
    length: float = attrs.field(default=1.0, converter=check.to_float,
                                validator=check.real(*SCALE_RANGE))
    block_cells: int | None = attrs.field(default=None, converter=check.to_int)
    reconstruction: Component = component_field(default=Component("muscl"))
    left: Component = component_field(default=Component("periodic"))
    right: Component = component_field(default=Component("periodic"))
    collisions: bool = attrs.field(default=True, validator=check.boolean)
    hierarchy: Hierarchy | None = attrs.field(default=None, converter=table_of(Hierarchy))

    @hierarchy.validator
    def _check_hierarchy(self, attribute, value):
        if value is None:
            return
        if not isinstance(value, Hierarchy):
            check.reject("Space", "hierarchy", value, "must be a table (levels, thresholds) "
                         "or absent", error=TypeError)
        if not self.collisions:
            check.reject("Space", "hierarchy", "a table", "needs collisions: a collisionless "
                         "run (collisions = false) has no collision models to choose")

    @block_cells.validator
    def _check_block(self, attribute, value):
        if value is not None and not (check.is_integer(value) and 1 <= value <= self.cells
                                      and self.cells % value == 0):
            check.reject("Space", "block_cells", value, f"must be a divisor of cells = "
                         f"{self.cells} (or None)")

    def build(self, field: str):
        """The registered reconstruction (``reconstruction``) or boundary (``left``,
        ``right``)."""
        component = getattr(self, field)
        family = "reconstructions" if field == "reconstruction" else "boundaries"
        return default_registries().create(family, component.name, **component.params)

    def blocks(self, ghost: int) -> int:
        """The store's chunk width along x (:func:`granframe.parallel.store_chunk` of
        ``cells`` and ``block_cells``)."""
        return store_chunk(self.cells, ghost, self.block_cells)

    def check(self, grid, time_step, step_limit: bool) -> dict:
        """Build and check the reconstruction and the boundaries against the cells, the
        grid and the time step (the transport's CFL limit); returns them."""
        owner = "RunDescription"
        built = {field: self.build(field) for field in ("reconstruction", "left", "right")}
        ghost = built["reconstruction"].ghost
        if self.cells < 2 * ghost + 1:
            check.reject(owner, "space.cells", self.cells,
                         f"must be >= {2 * ghost + 1}, the stencil of the reconstruction "
                         f"'{self.reconstruction.name}' (2 x {ghost} ghost cells + 1)")
        block = self.blocks(ghost)
        if block < ghost:
            check.reject(owner, "space.block_cells", block,
                         f"must be >= {ghost}, the ghost width of the reconstruction "
                         f"'{self.reconstruction.name}' (a block fills its neighbour's ghosts)")
        left, right = built["left"], built["right"]
        if left.periodic != right.periodic:
            check.reject(owner, "space.left" if not left.periodic else "space.right",
                         (self.left if not left.periodic else self.right).name,
                         "must be periodic too: an interval is periodic at both ends or at "
                         "neither")
        for side in ("left", "right"):
            built[side].check(grid)
            if time_step is not None:
                built[side].check_time_step(time_step)
        if step_limit and time_step is not None:
            limit = self.transport_limit(grid, built["reconstruction"])
            if time_step > limit * (1 + 1e-12):
                check.reject(owner, "time_step", time_step,
                             f"must be <= {limit:.6g}, the transport's CFL limit: each half "
                             f"step dt/2 moves the fastest node (max|v_1| = L - h = "
                             f"{grid.half_width - grid.spacing:.6g}) at most cfl = "
                             f"{built['reconstruction'].cfl:g} cells of dx = "
                             f"{self.length / self.cells:.6g} ('{self.reconstruction.name}' "
                             "with SSP RK3); lower time_step, or use fewer space.cells")
        return built

    def transport_limit(self, grid, reconstruction=None) -> float:
        """The largest time step of the transport: each half step dt/2 moves the fastest
        node (max|v_1| = L - h) at most the reconstruction's ``cfl`` cells,
        dt <= 2 cfl dx / (L - h) (:func:`granframe.space.transport.step_limit`)."""
        reconstruction = reconstruction or self.build("reconstruction")
        return step_limit(grid, self.length / self.cells, reconstruction.cfl)

    def to_dict(self) -> dict:
        return {"cells": self.cells, "length": self.length, "block_cells": self.block_cells,
                **({} if self.collisions else {"collisions": False}),
                **({} if self.hierarchy is None else {"hierarchy": self.hierarchy.to_dict()}),
                **{field: getattr(self, field).to_dict(f"space.{field}")
                   for field in ("reconstruction", "left", "right")}}
