"""The conformance checks of boundaries (the ends of a space run's interval): the class
attributes, the grids a wall accepts, its ghost cells and emission, and for a wall zero
net mass flux, positivity, its declared period and linearity, on both sides and at
times spread over its period.
"""

from __future__ import annotations

import math

import numpy

from granframe.abc import Side
from granframe.testing.conformance.common import require, require_contract


#: Velocity grids of the boundary checks, (dimension, N, support radius): narrow and wide
#: boxes (a wall may refuse a box that its wall Maxwellian does not fit).
WALL_GRIDS = ((2, 16, 1.5), (2, 32, 5.0), (3, 8, 1.5), (3, 16, 5.0))


#: The walls a boundary is checked as: the left one (x = 0) and the right one (x = ell),
#: given as the core gives them (:class:`granframe.abc.Side`).
WALL_SIDES = (Side(0, 0), Side(0, 1))


#: The times at which a wall that declares no ``period`` is checked.
WALL_TIMES = (0.0, 0.37, 1.9, 11.3, 97.0)


#: The times per period at which a wall with a ``period`` is checked, k P / WALL_PHASES.
WALL_PHASES = 8


def _wall_grids(boundary):
    """The grids of :data:`WALL_GRIDS` that ``boundary.check`` accepts; a refusal must be a
    ValueError naming a parameter, and at least one grid must be accepted."""
    from granframe.velocity.grid import VelocityGrid

    name, accepted = type(boundary).__name__, []
    for d, n, support in WALL_GRIDS:
        grid = VelocityGrid(d, n, support)
        try:
            boundary.check(grid)
        except ValueError as exc:
            require("parameter '" in str(exc),
                    f"{name}: check() refused the {d}D grid (N = {n}, L = "
                    f"{grid.half_width:g}) with a message naming no parameter: {exc}")
            continue
        except Exception as exc:   # any other error of check() is the finding
            raise AssertionError(f"{name}: check() on the {d}D grid (N = {n}, L = "
                                 f"{grid.half_width:g}) raised {exc!r}, not a ValueError "
                                 "naming a parameter") from exc
        accepted.append(grid)
    require(accepted, f"{name}: check() refused every grid of the kit {WALL_GRIDS}")
    return accepted


def _wall_times(boundary):
    """k P / :data:`WALL_PHASES`, k = 0 .. WALL_PHASES - 1, for a wall with a period P;
    :data:`WALL_TIMES` for one without."""
    period = boundary.period
    if period is None:
        return WALL_TIMES
    return tuple(k * period / WALL_PHASES for k in range(WALL_PHASES))


def _instants(boundary):
    """Every (t, side) a wall is checked at: its times (:func:`_wall_times`) on both sides."""
    return [(t, side) for t in _wall_times(boundary) for side in WALL_SIDES]


def _at(t, side, grid) -> str:
    return f"({grid.dimension}D, t = {t:.6g}, {side} wall)"


def _incoming(grid, seed: int):
    """Random positive face values at the wall, shape grid.shape."""
    return numpy.random.default_rng(seed).uniform(0.1, 1.0, grid.shape)


def _emit(boundary, incoming, grid, t=0.0, side="left"):
    name = type(boundary).__name__
    out = numpy.asarray(boundary.emit(incoming, grid, numpy, t=t, side=side))
    require(out.shape == grid.shape,
            f"{name}: emit() returned shape {out.shape}, the grid's is {grid.shape} "
            f"{_at(t, side, grid)}")
    require(numpy.all(numpy.isfinite(out)),
            f"{name}: emit() returned non-finite values {_at(t, side, grid)}")
    return out


def check_boundary(boundary, linear: bool = True) -> None:
    """:func:`check_boundary_basics`, then for a wall :func:`check_wall_mass_flux`,
    :func:`check_wall_positivity`, :func:`check_wall_period` and, if ``linear``,
    :func:`check_wall_linearity`; for an open end (``open``: mass crosses it) the
    positivity of its ghost cells and the period only."""
    check_boundary_basics(boundary)
    if type(boundary).periodic:
        return
    closed = not getattr(type(boundary), "open", False)
    if closed:
        check_wall_mass_flux(boundary)
    check_wall_positivity(boundary)
    check_wall_period(boundary)
    if linear and closed:
        check_wall_linearity(boundary)


def check_boundary_basics(boundary) -> None:
    """``periodic`` a bool class attribute; ``period`` None or a finite float > 0;
    ``check(grid)`` passes or raises a ValueError naming a parameter on 2D and 3D grids
    (:data:`WALL_GRIDS`), and accepts one; for a wall on each accepted grid, on both sides
    and at its times (k P / 8 over its period P, or :data:`WALL_TIMES`): ``ghosts`` of
    g = 1, 2, 3 cells of shape (g, *grid.shape), finite; ``emit`` of the grid's shape,
    finite, leaving its input unchanged, its values at c^+ > 0 (what the wall sends) read
    only the arriving values (c^- < 0): changing the incoming values where c^- = 0 leaves
    them unchanged to 1e-14 (c^± the upwind speeds,
    :func:`granframe.space.transport.upwind_speeds`; the node -L is both)."""
    from granframe.abc import Boundary

    require(isinstance(boundary, Boundary), f"{boundary!r} is not a granframe.abc.Boundary")
    require_contract("boundaries", boundary)
    kind, name = type(boundary), type(boundary).__name__
    flag = getattr(kind, "periodic", None)
    require(isinstance(flag, bool) and boundary.periodic is flag,
            f"{name}: 'periodic' must be a bool class attribute, got {flag!r}")
    period = boundary.period
    require(period is None or (isinstance(period, float) and math.isfinite(period)
                               and period > 0.0),
            f"{name}: 'period' must be None or a finite float > 0, got {period!r}")
    grids = _wall_grids(boundary)
    if flag:
        return
    for grid in grids:
        positive, negative = _speeds(grid)
        for t, side in _instants(boundary):
            for g in (1, 2, 3):
                inside = numpy.random.default_rng(g).uniform(0.1, 1.0, (g,) + grid.shape)
                ghosts = numpy.asarray(boundary.ghosts(inside, grid, numpy, t=t, side=side))
                require(ghosts.shape == inside.shape and numpy.all(numpy.isfinite(ghosts)),
                        f"{name}: ghosts() of {g} cells must be finite of shape "
                        f"{inside.shape}, got shape {ghosts.shape} {_at(t, side, grid)}")
            incoming = _incoming(grid, 4)
            copy = incoming.copy()
            out = _emit(boundary, incoming, grid, t, side)
            require(numpy.array_equal(incoming, copy),
                    f"{name}: emit() modified its input {_at(t, side, grid)}")
            changed = numpy.where(negative == 0, _incoming(grid, 5), incoming)
            error = float(numpy.max(numpy.abs(_emit(boundary, changed, grid, t, side)
                                              - out)[positive > 0]))
            require(error <= 1e-14 * numpy.max(numpy.abs(out)),
                    f"{name}: the emission (c^+ > 0) changed by {error:.3g} when only the "
                    f"incoming values at c^- = 0 changed {_at(t, side, grid)}: a wall sends "
                    "back what arrives (c^- < 0)")


def _speeds(grid):
    """The upwind speeds (c^+, c^-) broadcast to the grid's shape."""
    from granframe.space.transport import upwind_speeds

    return tuple(numpy.broadcast_to(c, grid.shape) for c in upwind_speeds(grid))


def _wall_flux(boundary, incoming, grid, t=0.0, side="left"):
    """F = c^+ out + c^- in at the wall at time t on ``side``, and c^-."""
    positive, negative = _speeds(grid)
    out = _emit(boundary, incoming, grid, t, side)
    return positive * out + negative * incoming, negative


def check_wall_mass_flux(boundary) -> None:
    """Zero net mass flux through the wall: sum_v F dv, F = c^+ out + c^- in with c^± the
    upwind speeds (:func:`granframe.space.transport.upwind_speeds`), is below 1e-13
    of the arriving flux sum_v |c^-| in dv, for three random positive ``in`` and a
    Maxwellian drifting into the wall, on every grid the wall accepts, on both sides and
    at the wall's times (k P / 8 over its period P, or :data:`WALL_TIMES`)."""
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        drifting = grid.maxwellian(1.0, [-0.5] + [0.2] * (grid.dimension - 1), 0.3)
        for incoming in (_incoming(grid, 6), _incoming(grid, 7), _incoming(grid, 8), drifting):
            for t, side in _instants(boundary):
                flux, negative = _wall_flux(boundary, incoming, grid, t, side)
                arriving = float(numpy.sum(-negative * incoming))
                net = float(numpy.sum(flux))
                require(abs(net) <= 1e-13 * arriving,
                        f"{name}: net mass flux through the wall {net * grid.cell_volume:.3g} "
                        f"at t = {t:.6g} on the {side}, {abs(net) / arriving:.3g} of the "
                        f"arriving flux ({grid.dimension}D): the wall must send back what "
                        "arrives")


def check_wall_positivity(boundary) -> None:
    """Non-negative incoming values (random, with zeros, and values down to 1e-300) give a
    non-negative emission (c^+ > 0) and non-negative ghost cells, on both sides and at the
    wall's times. An open end (``open``) sends in what it holds whatever arrives (a
    reservoir: the grid's Maxwellian, which rings below zero where the grid does not
    resolve it, as an initial Maxwellian does): its ghost cells only."""
    name = type(boundary).__name__
    closed = not getattr(type(boundary), "open", False)
    for grid in _wall_grids(boundary):
        rng = numpy.random.default_rng(9)
        c = _speeds(grid)[0]
        for incoming in (rng.uniform(0.0, 1.0, grid.shape) * (rng.uniform(size=grid.shape) > 0.5),
                         10.0 ** -rng.uniform(0.0, 300.0, grid.shape)):
            for t, side in _instants(boundary):
                out = _emit(boundary, incoming, grid, t, side)
                require(out[c > 0].min() >= 0.0 or not closed,
                        f"{name}: emission {out[c > 0].min():.3g} < 0 from non-negative "
                        f"incoming values {_at(t, side, grid)}")
                ghosts = numpy.asarray(boundary.ghosts(incoming[None], grid, numpy, t=t,
                                                       side=side))
                require(ghosts.min() >= 0.0,
                        f"{name}: ghost value {ghosts.min():.3g} < 0 from non-negative cells "
                        f"{_at(t, side, grid)}")


def check_wall_period(boundary) -> None:
    """A wall that declares a period P acts periodically: its emission at t + P equals that
    at t to 1e-12 of the largest emission, at its times k P / 8 on both sides (a wall
    without a period passes)."""
    period = boundary.period
    if period is None:
        return
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        c = _speeds(grid)[0]
        incoming = _incoming(grid, 12)
        for t, side in _instants(boundary):
            now = _emit(boundary, incoming, grid, t, side)
            later = _emit(boundary, incoming, grid, t + period, side)
            error = float(numpy.max(numpy.abs(later - now)[c > 0]))
            require(error <= 1e-12 * numpy.max(numpy.abs(now[c > 0])),
                    f"{name}: the emission at t + period (period = {period:.6g}) differs "
                    f"from that at t by {error:.3g} {_at(t, side, grid)}: 'period' must be "
                    "the period of what the wall does, or None")


def check_wall_linearity(boundary) -> None:
    """The emission (c^+ > 0) is linear in the incoming values: emit(a x + b y) = a emit(x)
    + b emit(y) to 1e-13 of the largest emission, a = 0.3, b = 2.5 (every wall whose
    accommodation does not depend on what arrives), on both sides and at the wall's
    times."""
    name = type(boundary).__name__
    for grid in _wall_grids(boundary):
        c = _speeds(grid)[0]
        x, y = _incoming(grid, 10), _incoming(grid, 11)
        for t, side in _instants(boundary):
            combined = _emit(boundary, 0.3 * x + 2.5 * y, grid, t, side)
            expected = (0.3 * _emit(boundary, x, grid, t, side)
                        + 2.5 * _emit(boundary, y, grid, t, side))
            error = float(numpy.max(numpy.abs(combined - expected)[c > 0]))
            require(error <= 1e-13 * numpy.max(numpy.abs(expected[c > 0])),
                    f"{name}: emit(0.3 x + 2.5 y) differs from 0.3 emit(x) + 2.5 emit(y) by "
                    f"{error:.3g} {_at(t, side, grid)}; a wall that is not linear sets "
                    "'linear = False' in its BoundaryTests")
