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
from granframe.space.transport import box_step_limit, step_limit
from granframe.velocity.grid import SCALE_RANGE

#: Most cells of a space run: 1e9 cells of the smallest grid (2D N = 4) already hold 128 GB
#: per copy of f, so more is a mistake (and it keeps dx = length / cells a float).
MAX_CELLS = 10 ** 9


#: what the cells of a space section may be: a number (an interval along x) or a list of two
#: (a rectangle, cells along x and y)
CELLS_ALLOWED = (f"must be an integer >= 1 and <= {MAX_CELLS} (the cells of an interval), or "
                 "a list [Cx, Cy] of two such (the cells of a rectangle along x and y)")


def _counts(value):
    """The cells as an int, or a tuple of two ints from a list of two integers; anything
    else as it is, for the validator."""
    if isinstance(value, (list, tuple)) and len(value) == 2 and all(map(check.is_integer,
                                                                         value)):
        return tuple(int(v) for v in value)
    return check.to_int(value)


def _lengths(value):
    """A length as a float, two as a tuple of floats; anything else as it is."""
    if isinstance(value, (list, tuple)) and len(value) == 2 and all(map(check.is_real, value)):
        try:
            return tuple(check.to_float(v) for v in value)
        except (TypeError, OverflowError):
            return value
    return check.to_float(value)


def _check_cells(instance, attribute, value):
    """An interval's cells (1 to MAX_CELLS) or a rectangle's two counts (each >= 1, their
    product at most MAX_CELLS)."""
    if isinstance(value, tuple):
        if not all(1 <= v for v in value) or math.prod(value) > MAX_CELLS:
            check.reject("Space", "cells", list(value), CELLS_ALLOWED[:-1]
                         + f"; Cx Cy at most {MAX_CELLS})")
        return
    if not check.is_integer(value):
        check.reject("Space", "cells", value, CELLS_ALLOWED, error=TypeError)
    check.integer(1, MAX_CELLS)(instance, attribute, value)


def _optional_component(value):
    return None if value is None else coerce_component(value)


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
    r"""The space of d_t f + v . grad_x f = Q(f, f)/eps (+ tau Delta_v f): an interval
    along x, or a rectangle in x and y (docs/space.md, "Two dimensions").

    Parameters
    ----------
    cells : int or list of two int
        Finite-volume cells on [0, length] (an interval), or [Cx, Cy] on
        [0, Lx] x [0, Ly] (a rectangle); along every axis at least the reconstruction's
        stencil, 2 ghost + 1 (3 for ``upwind``, 5 for ``muscl``, 7 for ``weno5``), in all at
        most :data:`MAX_CELLS`.
    length : float or list of two float
        ell, or [Lx, Ly] (one number: a square), in the velocity grid's scale range
        (1e-50 to 1e50).
    block_cells : int, list of two int, or None
        The width of the store's chunks of f and of the fields along each axis (one number:
        the same along both); a divisor of the cells, at least the reconstruction's ghost
        width. A run on several processes gives each whole chunks, so it runs on at most
        cells / block_cells of them along each axis. None: :meth:`blocks` (about 16
        chunks or more along each axis, at most 64 cells wide).
    reconstruction : Component
        Registered reconstruction of the cell averages (``muscl``, ``weno5``, ``upwind``).
    left, right : Component
        Registered boundaries at x = 0 and x = Lx (``periodic``, ``specular``,
        ``diffuse`` with ``temperature``, ``velocity``, ``accommodation``, ``vibrating``,
        ``reservoir``); periodic at both ends or at neither.
    bottom, top : Component or None
        The boundaries at y = 0 and y = Ly of a rectangle, named as ``left`` and
        ``right`` (periodic by default; periodic at both or at neither); an interval has
        none. A wall sees its own frame: at the bottom and the top the normal velocity
        is v_2 and a diffuse wall's ``velocity`` is along v_1 (a lid moving along x).

    collisions : bool
        False: a collisionless gas (free-molecular flow, d_t f + v_1 d_x f = 0); the
        kernel, the restitution law and the operator are then not built.
    hierarchy : Hierarchy or None
        Collision models chosen cell by cell (a ``[space.hierarchy]`` table); None: the
        full operator in every cell.

    The Knudsen number eps is the description's ``knudsen``.
    """

    cells: int | tuple = attrs.field(converter=_counts, validator=_check_cells)
    length: float | tuple = attrs.field(default=1.0, converter=_lengths)
    block_cells: int | tuple | None = attrs.field(default=None, converter=_counts)
    reconstruction: Component = component_field(default=Component("muscl"))
    left: Component = component_field(default=Component("periodic"))
    right: Component = component_field(default=Component("periodic"))
    bottom: Component | None = attrs.field(default=None, converter=_optional_component)
    top: Component | None = attrs.field(default=None, converter=_optional_component)
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

    @length.validator
    def _check_length(self, attribute, value):
        if isinstance(value, (list, tuple)):
            if len(value) != self.dimension:
                check.reject("Space", "length", list(value), f"must be one number, or one "
                             f"for each of the {self.dimension} axes of cells = {self.cells}")
            for v in value:
                check.real(*SCALE_RANGE)(self, attribute, v)
            return
        check.real(*SCALE_RANGE)(self, attribute, value)

    @block_cells.validator
    def _check_block(self, attribute, value):
        if value is None:
            return
        counts = self.counts
        widths = value if isinstance(value, tuple) else (value,) * len(counts)
        if len(widths) != len(counts) or not all(
                check.is_integer(b) and 1 <= b <= n and n % b == 0
                for b, n in zip(widths, counts)):
            cells = self.cells if self.dimension == 1 else list(self.cells)
            check.reject("Space", "block_cells", list(value) if isinstance(value, tuple)
                         else value, f"must be a divisor of cells = {cells}"
                         + (" (one number, the same along both axes, or one for each)"
                            if self.dimension > 1 else "") + " (or None)")

    @bottom.validator
    def _check_bottom(self, attribute, value):
        for name in ("bottom", "top"):
            given = getattr(self, name) if name == "top" else value
            if given is not None and self.dimension == 1:
                check.reject("Space", name, given.name, "is a wall of y: an interval (one "
                             "number of cells) has none; give cells = [Cx, Cy] for a rectangle")
            if given is not None and not isinstance(given, Component):
                check.reject("Space", name, given, "must be a name or a table",
                             error=TypeError)

    @property
    def dimension(self) -> int:
        """The number of space axes: 1 (an interval) or 2 (a rectangle)."""
        return len(self.cells) if isinstance(self.cells, tuple) else 1

    @property
    def counts(self) -> tuple:
        """The cells along every axis."""
        return self.cells if isinstance(self.cells, tuple) else (self.cells,)

    @property
    def lengths(self) -> tuple:
        """The length of every axis (one number for a rectangle: a square)."""
        if isinstance(self.length, tuple):
            return self.length
        return (self.length,) * self.dimension

    @property
    def sides(self) -> tuple:
        """The names of the walls: left, right (and bottom, top for a rectangle)."""
        return ("left", "right") if self.dimension == 1 else ("left", "right", "bottom", "top")

    def wall(self, side: str) -> Component:
        """The component of ``side`` (a wall's name, or ``reconstruction``); bottom and
        top are periodic when not given."""
        component = getattr(self, side)
        return Component("periodic") if component is None else component

    @property
    def spacing(self) -> tuple:
        """The cell widths along every axis."""
        return tuple(ell / n for ell, n in zip(self.lengths, self.counts))

    def build(self, field: str):
        """The registered reconstruction (``reconstruction``) or boundary (``left``,
        ``right``, ``bottom``, ``top``)."""
        if field == "reconstruction":
            component, family = self.reconstruction, "reconstructions"
        else:
            component, family = self.wall(field), "boundaries"
        return default_registries().create(family, component.name, **component.params)

    def blocks(self, ghost: int):
        """The store's chunk width along x (:func:`granframe.parallel.store_chunk` of
        ``cells`` and ``block_cells``); of a rectangle, a tuple, one per axis."""
        if self.dimension == 1:
            return store_chunk(self.cells, ghost, self.block_cells)
        widths = (self.block_cells if isinstance(self.block_cells, tuple)
                  else (self.block_cells,) * self.dimension)
        return tuple(store_chunk(n, ghost, b) for n, b in zip(self.counts, widths))

    def check(self, grid, time_step, step_limit: bool) -> dict:
        """Build and check the reconstruction and the boundaries against the cells, the
        grid and the time step (the transport's CFL limit); returns them."""
        owner = "RunDescription"
        built = {field: self.build(field) for field in ("reconstruction",) + self.sides}
        ghost = built["reconstruction"].ghost
        rectangle = self.dimension > 1
        if min(self.counts) < 2 * ghost + 1:
            check.reject(owner, "space.cells", list(self.cells) if rectangle else self.cells,
                         f"must be >= {2 * ghost + 1}{' along every axis' if rectangle else ''}"
                         f", the stencil of the reconstruction "
                         f"'{self.reconstruction.name}' (2 x {ghost} ghost cells + 1)")
        if rectangle and grid.dimension < self.dimension:
            check.reject(owner, "space.cells", list(self.cells), f"has {self.dimension} space "
                         f"axes, more than the velocity dimension {grid.dimension}")
        block = self.blocks(ghost)
        if min(block if rectangle else (block,)) < ghost:
            check.reject(owner, "space.block_cells", list(block) if rectangle else block,
                         f"must be >= {ghost}, the ghost width of the reconstruction "
                         f"'{self.reconstruction.name}' (a block fills its neighbour's ghosts)")
        for lower, upper in zip(self.sides[::2], self.sides[1::2]):
            low, high = built[lower], built[upper]
            if low.periodic != high.periodic:
                check.reject(owner, f"space.{lower}" if not low.periodic else f"space.{upper}",
                             self.wall(lower if not low.periodic else upper).name,
                             f"must be periodic too: {'an interval' if not rectangle else 'an axis'}"
                             f" is periodic at both ends or at neither ({lower}, {upper})")
        for side in self.sides:
            built[side].check(grid)
            if time_step is not None:
                built[side].check_time_step(time_step)
        if step_limit and time_step is not None:
            limit = self.transport_limit(grid, built["reconstruction"])
            if time_step > limit * (1 + 1e-12):
                widths = " and ".join(f"d{a} = {h:.6g}" for a, h in zip("xy", self.spacing))
                moves = ("at most cfl = " if not rectangle else
                         "along x and along y at once, sum_a (L - h) dt / (2 dx_a) at most ")
                check.reject(owner, "time_step", time_step,
                             f"must be <= {limit:.6g}, the transport's CFL limit: each half "
                             f"step dt/2 moves the fastest node (max|v_{'a' if rectangle else 1}| = L - h = "
                             f"{grid.half_width - grid.spacing:.6g}) {moves}"
                             f"{built['reconstruction'].cfl:g} cells of "
                             f"{widths if rectangle else 'dx = ' + format(self.spacing[0], '.6g')}"
                             f" ('{self.reconstruction.name}' with SSP RK3); lower time_step, "
                             "or use fewer space.cells")
        return built

    def transport_limit(self, grid, reconstruction=None) -> float:
        """The largest time step of the transport: each half step dt/2 moves the fastest
        node (max|v_1| = L - h) at most the reconstruction's ``cfl`` cells,
        dt <= 2 cfl dx / (L - h) (:func:`granframe.space.transport.step_limit`)."""
        reconstruction = reconstruction or self.build("reconstruction")
        if self.dimension > 1:
            return box_step_limit(grid, self.spacing, reconstruction.cfl)
        return step_limit(grid, self.length / self.cells, reconstruction.cfl)

    def to_dict(self) -> dict:
        def listed(value):
            return list(value) if isinstance(value, tuple) else value

        return {"cells": listed(self.cells), "length": listed(self.length),
                "block_cells": listed(self.block_cells),
                **({} if self.collisions else {"collisions": False}),
                **({} if self.hierarchy is None else {"hierarchy": self.hierarchy.to_dict()}),
                **{field: self.wall(field).to_dict(f"space.{field}")
                   for field in ("reconstruction",) + self.sides}}
