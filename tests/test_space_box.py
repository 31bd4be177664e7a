"""Cells on a rectangle: the box, its ghost strips, the unsplit transport and its walls,
and a block decomposition over processes.

Data that vary along one axis step as on the line of that axis (bit for bit across a
periodic axis); free transport on a periodic square converges to the exact solution at
the reconstruction's order; what crosses the four walls is what the box gains; a gas at
rest at the walls' temperature stays as it is, corners included; four processes on a
2 x 2 grid of blocks, their ghost strips exchanged through a communicator, step as one
process owning every cell, bit for bit."""

import itertools
import math

import numpy
import pytest
from test_parallel import PostOffice, ThreadCommunicator, _in_threads

import granframe as gf
from granframe.parallel import BoxHalo, process_grid
from granframe.registry import default_registries
from granframe.space.boundaries import Diffuse, Periodic, Specular, Vibrating
from granframe.space.collisions import FreeFlight, SplitStep
from granframe.space.domain import Box, Domain
from granframe.space.reconstruction import MUSCL, WENO5, Upwind
from granframe.space.transport import (
    BoxTransport,
    Transport,
    box_step_limit,
    step_limit,
)
from granframe.velocity.moments import FieldMoments

GRID = gf.VelocityGrid(dimension=2, n_modes=16, support_radius=4.0)
SCHEMES = {"muscl": MUSCL(), "weno5": WENO5()}
#: with the upwind reconstruction, whose face values are views of the state
LINE_SCHEMES = {**SCHEMES, "upwind": Upwind()}


def _line(cells, seed, drift=True):
    """Smooth positive cells along a line: Maxwellians whose density, temperature and (with
    ``drift``) velocity vary from cell to cell."""
    rng = numpy.random.default_rng(seed)
    return numpy.stack([GRID.maxwellian(1.0 + 0.3 * rng.random(),
                                        (rng.normal(0, 0.4) if drift else 0.0, 0.0),
                                        0.6 + 0.5 * rng.random()) for _ in range(cells)])


def _swap(f):
    """f (..., v1, v2) with the velocity axes exchanged."""
    return numpy.swapaxes(f, -1, -2)


LINE_WALLS = {
    "periodic": (Periodic(), Periodic()),
    "diffuse-specular": (Diffuse(temperature=1.2, velocity=0.3, accommodation=0.6), Specular()),
    "vibrating-diffuse": (Vibrating(speed=0.4, temperature=0.9),
                          Diffuse(temperature=0.8, velocity=-0.2)),
}


def _run_line(domain, scheme, walls, f, steps=3, dt=0.01):
    transport = Transport(domain, scheme, *walls)
    step, array = SplitStep(FreeFlight(), transport), domain.from_cells(f)
    for k in range(steps):
        array = step.step(None, dt * k, array, dt)
    return domain.to_cells(array), transport.take_wall_totals()


def _run_box(box, scheme, walls, f, steps=3, dt=0.01):
    transport = BoxTransport(box, scheme, walls)
    step, array = SplitStep(FreeFlight(), transport), box.from_cells(f)
    for k in range(steps):
        array = step.step(None, dt * k, array, dt)
    return box.to_cells(array).reshape(box.sizes + box.grid.shape), transport.take_wall_totals()


@pytest.mark.parametrize("walls", list(LINE_WALLS))
@pytest.mark.parametrize("scheme", list(LINE_SCHEMES))
def test_data_along_x_step_as_on_the_line(walls, scheme):
    """Cells that vary along x only, periodic across y: each row of the rectangle steps as
    the line (three Strang steps of free flight through the walls of x), bit for bit (to
    round-off through a vibrating wall, whose kernel is a matrix product over the rows);
    what crossed each wall of x is the line's times the height ell_y, and nothing crosses
    y."""
    nx, ny, height = 12, 5, 0.7
    reconstruction, (left, right) = LINE_SCHEMES[scheme], LINE_WALLS[walls]
    f = _line(nx, 1)
    line, line_walls = _run_line(Domain(nx, 1.5, 4, reconstruction.ghost, GRID),
                                 reconstruction, (left, right), f)
    box = Box((nx, ny), (1.5, height), reconstruction.ghost, GRID)
    rows, box_walls = _run_box(box, reconstruction, (left, right, Periodic(), Periodic()),
                               numpy.repeat(f[:, None], ny, axis=1))
    assert numpy.abs(line - f).max() > 1e-3                 # it moved
    for j in range(ny):
        if walls == "vibrating-diffuse":     # its kernel is a matrix product over the rows
            numpy.testing.assert_allclose(rows[:, j], line, rtol=0, atol=1e-15 * f.max())
        else:
            numpy.testing.assert_array_equal(rows[:, j], line)
    numpy.testing.assert_allclose(box_walls[:2], height * line_walls, rtol=0,
                                  atol=1e-14 * numpy.abs(line_walls).max())
    numpy.testing.assert_array_equal(box_walls[2:], 0.0)
    if walls != "periodic":
        assert numpy.abs(line_walls[:, 1]).max() > 1e-4      # the walls took momentum


@pytest.mark.parametrize("across", ["periodic", "specular"])
@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_data_along_y_step_as_on_the_line_along_y(across, scheme):
    """Cells that vary along y only step as the line laid along y (its velocity axes
    exchanged, :class:`Domain` with axis 1) through walls at the bottom and the top: bit
    for bit across periodic sides of x, to round-off across specular ones (the data and
    the walls are even in v_1 there, which the reflection of the nodes keeps to
    round-off)."""
    nx, ny, width = 6, 12, 0.8
    reconstruction = SCHEMES[scheme]
    bottom = Diffuse(temperature=1.1, velocity=0.25 if across == "periodic" else 0.0)
    top = Specular()
    f = _swap(_line(ny, 2, drift=True))            # along y: its drift is along v_2
    line, line_walls = _run_line(Domain(ny, 1.5, 4, reconstruction.ghost, GRID, axis=1),
                                 reconstruction, (bottom, top), f)
    sides = (Periodic(), Periodic()) if across == "periodic" else (Specular(), Specular())
    box = Box((nx, ny), (width, 1.5), reconstruction.ghost, GRID)
    columns, box_walls = _run_box(box, reconstruction, sides + (bottom, top),
                                  numpy.repeat(f[None], nx, axis=0))
    assert numpy.abs(line - f).max() > 1e-3
    for i in range(nx):
        if across == "periodic":
            numpy.testing.assert_array_equal(columns[i], line)
        else:
            numpy.testing.assert_allclose(columns[i], line, rtol=0, atol=1e-15 * f.max())
    numpy.testing.assert_allclose(box_walls[2:], width * line_walls, rtol=0,
                                  atol=1e-14 * numpy.abs(line_walls).max())
    scale = 1e-14 * numpy.abs(line_walls).max()
    # the sides of x: no mass, energy or tangential momentum, and the pressure on one the
    # opposite of that on the other (a specular wall pushes back; periodic: nothing)
    numpy.testing.assert_allclose(box_walls[:2, [0, 2, 3]], 0.0, rtol=0, atol=scale)
    numpy.testing.assert_allclose(box_walls[0] + box_walls[1], 0.0, rtol=0, atol=scale)


def _average(edges, shift):
    """The cell averages of sin(2 pi (x - shift)) over the cells of ``edges``, for every
    shift (one per velocity node): (cos(2 pi (a - s)) - cos(2 pi (b - s))) / (2 pi dx)."""
    a, b = edges[:-1, None], edges[1:, None]
    return (numpy.cos(2 * numpy.pi * (a - shift)) - numpy.cos(2 * numpy.pi * (b - shift))) \
        / (2 * numpy.pi * (b - a))


def _exact_square(grid, cells, t):
    """The exact cell averages at t of free transport on the periodic unit square from
    f0 = (1 + 1/2 sin 2 pi x sin 2 pi y) M(v): f0(x - v t, v), a product of one-axis
    averages at every node."""
    edges = numpy.linspace(0.0, 1.0, cells + 1)
    v1, v2 = (numpy.broadcast_to(m, grid.shape).ravel() for m in grid.mesh())
    ax, ay = _average(edges, v1 * t), _average(edges, v2 * t)      # (cells, nodes)
    rho = 1.0 + 0.5 * ax[:, None, :] * ay[None, :, :]
    return rho.reshape((cells, cells) + grid.shape) * grid.maxwellian(temperature=0.5)


@pytest.mark.parametrize("scheme, order", [("muscl", 1.8), ("weno5", 4.5)])
def test_free_transport_on_a_periodic_square_converges_at_the_schemes_order(scheme, order):
    """Free transport on the periodic unit square against the exact solution f0(x - v t):
    the L1 error over cells and nodes falls at the reconstruction's order as the cells
    double (10, 20, 40 a side to t = 0.1; MUSCL at the CFL limit, WENO5 with sub-steps
    small enough, dt ~ dx^(5/3), that the third-order time error stays below the space
    error): observed orders at least 1.8 and 4.5 on the finest pair."""
    grid = gf.VelocityGrid(dimension=2, n_modes=6, support_radius=2.0)
    reconstruction, walls = SCHEMES[scheme], (Periodic(),) * 4
    final, errors = 0.1, []
    for cells in (10, 20, 40):
        box = Box((cells, cells), (1.0, 1.0), reconstruction.ghost, grid)
        transport = BoxTransport(box, reconstruction, walls)
        tau = transport.time_step_limit()
        if scheme == "weno5":
            tau = min(tau, 0.5 * (1.0 / cells) ** (5.0 / 3.0))
        steps = math.ceil(final / tau)
        array = box.from_cells(_exact_square(grid, cells, 0.0))
        for k in range(steps):
            transport.advance(array, final / steps, k * final / steps)
        error = box.interior(array) - _exact_square(grid, cells, final)
        errors.append(numpy.abs(error).mean())
    observed = [math.log2(a / b) for a, b in itertools.pairwise(errors)]
    assert observed[-1] >= order, (errors, observed)


WALLS = (Diffuse(temperature=1.3, velocity=0.2), Specular(),
         Diffuse(temperature=0.9, accommodation=0.7), Diffuse(temperature=1.0, velocity=0.5))


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_what_enters_through_the_four_walls_is_what_the_box_gains(scheme):
    """A gas in a box with four different walls (a hot wall, a specular one, a partly
    accommodating one and a moving lid): over Strang steps of free flight, the change of
    its mass, momentum and energy is what the wall totals say entered, to round-off, and
    the walls keep the mass (zero net mass flux at every diffuse or specular wall)."""
    reconstruction = SCHEMES[scheme]
    box = Box((8, 6), (1.0, 0.75), reconstruction.ghost, GRID)
    rng = numpy.random.default_rng(3)
    f = numpy.stack([GRID.maxwellian(1 + 0.3 * rng.random(), tuple(rng.normal(0, 0.3, 2)),
                                     0.7 + 0.4 * rng.random()) for _ in range(48)])
    fields = FieldMoments(GRID, box.cell_volume, transport_axes=(0, 1))
    before = fields(f)
    cells, walls = _run_box(box, reconstruction, WALLS, f, steps=4, dt=0.02)
    after = fields(cells.reshape((-1,) + GRID.shape))
    entered = walls.sum(axis=0)

    def momentum(moments):
        return (moments["density"][:, None] * moments["velocity"]).sum(axis=0) \
            * box.cell_volume

    for name, change, expected in (
            ("mass", after["mass"] - before["mass"], entered[0]),
            ("momentum", momentum(after) - momentum(before), entered[1:3]),
            ("energy", after["kinetic_energy"] - before["kinetic_energy"], entered[3])):
        numpy.testing.assert_allclose(change, expected, rtol=0, atol=5e-14, err_msg=name)
    numpy.testing.assert_allclose(walls[:, 0], 0.0, rtol=0, atol=1e-14)
    assert numpy.abs(walls[:, 3]).max() > 1e-3               # heat crossed the walls


def test_a_gas_at_rest_at_the_walls_temperature_stays_as_it_is_corners_included():
    """Four diffuse walls at rest at T_w = 0.9, the gas a Maxwellian at rest at T_w: what
    each wall sends equals what arrives node by node, so every cell, the four corners
    too, keeps its f to round-off."""
    walls = (Diffuse(temperature=0.9),) * 4
    for reconstruction in SCHEMES.values():
        box = Box((7, 6), (1.0, 1.0), reconstruction.ghost, GRID)
        f = numpy.broadcast_to(GRID.maxwellian(temperature=0.9), (42,) + GRID.shape)
        cells, _ = _run_box(box, reconstruction, walls, f, steps=3, dt=0.02)
        numpy.testing.assert_allclose(cells.reshape(f.shape), f, rtol=0, atol=1e-15)


def test_muscl_keeps_f_non_negative_at_the_box_limit_and_not_at_the_lines():
    """A square pulse of gas on the fastest nodes (v_1 and v_2 both +-(L - h)), MUSCL (mc,
    the default) at the CFL limit of the box, where each half step moves those nodes cfl
    cells along x and along y at once: f stays non-negative at every node; at the line's
    limit of the same dx, twice the box's on a square, it goes below zero."""
    grid = gf.VelocityGrid(dimension=2, n_modes=8, support_radius=3.0)
    reconstruction = MUSCL()
    box = Box((16, 16), (1.0, 1.0), reconstruction.ghost, grid)
    pulse = numpy.zeros((16, 16))
    pulse[4:8, 4:8] = 1.0
    nodes = numpy.zeros(grid.shape)
    nodes[-1, -1] = nodes[1, -1] = nodes[-1, 1] = 1.0
    f = (pulse[:, :, None, None] * nodes).reshape((-1,) + grid.shape)
    dt = box_step_limit(grid, box.spacing, reconstruction.cfl)
    line = step_limit(grid, 1.0 / 16, reconstruction.cfl)
    assert dt == pytest.approx(0.5 * line, rel=1e-15)
    lows = [_run_box(box, reconstruction, (Periodic(),) * 4, f, steps=6, dt=step)[0].min()
            for step in (dt, line)]
    assert lows[0] >= 0.0 and lows[1] < -1e-4, lows


# -- processes -------------------------------------------------------------------------------

class Queues(PostOffice):
    """A post office that queues the messages of one (source, destination, tag) in the
    order they were sent, as MPI does (its messages do not overtake one another): a block
    may post the next stage's strips before its neighbour took the last ones."""

    def post(self, source, destination, tag, array):
        with self.changed:
            key = (source, destination, tag)
            self.letters.setdefault(key, []).append(numpy.array(array, copy=True))
            self.log.append(key + (array.shape,))
            self.changed.notify_all()

    def take(self, source, destination, tag):
        key = (source, destination, tag)
        with self.changed:
            assert self.changed.wait_for(lambda: self.letters.get(key), timeout=20), (
                f"no message {key} came")
            return self.letters[key].pop(0)


@pytest.mark.parametrize("ends", ["periodic", "walls"])
@pytest.mark.parametrize("counts", [(2, 2), (4, 1), (1, 3)])
def test_blocks_of_processes_step_as_one_box_owning_every_cell(ends, counts):
    """Processes on a P_x x P_y grid of blocks (threads, their ghost strips exchanged
    through a communicator that matches messages by (peer, tag) and takes contiguous
    arrays only) step as one box owning every cell, bit for bit, through walls at every
    side or across periodic ones; the wall totals of each side are the sums of the blocks
    on it."""
    reconstruction = WENO5()
    cells = (12, 12)
    walls = (Periodic(),) * 4 if ends == "periodic" else WALLS
    rng = numpy.random.default_rng(5)
    f = numpy.stack([GRID.maxwellian(1 + 0.3 * rng.random(), tuple(rng.normal(0, 0.3, 2)),
                                     0.7 + 0.4 * rng.random()) for _ in range(144)])
    whole = Box(cells, (1.0, 1.0), reconstruction.ghost, GRID)
    expected, expected_walls = _run_box(whole, reconstruction, walls, f)
    size = counts[0] * counts[1]
    office = Queues()
    grid_f = f.reshape(cells + GRID.shape)

    def process(rank):
        place = numpy.unravel_index(rank, counts)
        owned = tuple((int(p) * n // c, (int(p) + 1) * n // c)
                      for p, n, c in zip(place, cells, counts))
        box = Box(cells, (1.0, 1.0), reconstruction.ghost, GRID, owned=owned)
        box.neighbours = BoxHalo.of(ThreadCommunicator(rank, size, office), counts,
                                    (ends == "periodic",) * 2)
        part = grid_f[box.owned].reshape((-1,) + GRID.shape)
        return box, _run_box(box, reconstruction, walls, part)

    results = _in_threads(process, size)
    totals = numpy.zeros_like(expected_walls)
    for box, (block, block_walls) in results:
        numpy.testing.assert_array_equal(block, expected[box.owned])
        totals += block_walls
    numpy.testing.assert_allclose(totals, expected_walls, rtol=0,
                                  atol=1e-14 * max(1.0, numpy.abs(expected_walls).max()))
    if size > 1:
        assert office.log and not any(office.letters.values())  # every one was taken


def test_a_process_grid_crosses_the_fewest_faces():
    assert process_grid(4, (64, 64), (16, 16), 2) == (2, 2)
    assert process_grid(2, (64, 64), (16, 16), 2) == (1, 2)
    assert process_grid(4, (128, 32), (16, 16), 2) == (4, 1)
    assert process_grid(8, (64, 64), (16, 16), 2) == (2, 4)
    assert process_grid(1, (8, 8), (8, 8), 3) == (1, 1)
    with pytest.raises(ValueError, match=r"^process_grid: parameter 'processes' = 32 is "
                                         r"invalid; must factor into processes along each "
                                         r"axis that share its store chunks \(4 x 4 chunks"):
        process_grid(32, (64, 64), (16, 16), 2)


@pytest.mark.parametrize("arguments, parameter, allowed", [
    ({"cells": (40,)}, "cells", "must give the cells along 2 space axes"),
    ({"cells": (4, 4, 4)}, "cells", (r"must give the cells along 2 space axes \(x, y\), at "
                                     "most the velocity dimension 2")),
    ({"length": (1.0,)}, "length", "must give a length for each of the 2 axes"),
    ({"owned": ((0, 8), (0, 9))}, "owned", "must be \\(start, stop\\) along each"),
    ({"owned": ((0, 2), (0, 8))}, "owned", "must hold at least 3 cells along every axis"),
])
def test_a_box_refuses_what_it_cannot_hold_by_name(arguments, parameter, allowed):
    given = {"cells": (8, 8), "length": (1.0, 1.0), "owned": None, **arguments}
    with pytest.raises(ValueError, match=f"^Box: parameter '{parameter}' = .* is invalid; "
                                         f"{allowed}"):
        Box(given["cells"], given["length"], 3, GRID, owned=given["owned"])


def test_a_box_transport_refuses_walls_that_do_not_close_the_box():
    box = Box((8, 8), (1.0, 1.0), 2, GRID)
    with pytest.raises(ValueError, match="has 2 boundaries; must give one for each side "
                                         r"\(left, right, bottom, top\)"):
        BoxTransport(box, MUSCL(), (Periodic(), Periodic()))
    with pytest.raises(ValueError, match="the sides bottom and top must be both periodic or "
                                         "both walls"):
        BoxTransport(box, MUSCL(), (Periodic(), Periodic(), Periodic(), Specular()))
    corner = Box((8, 8), (1.0, 1.0), 2, GRID, owned=((0, 4), (0, 4)))
    transport = BoxTransport(corner, MUSCL(), (Specular(),) * 4)
    with pytest.raises(RuntimeError, match="has a side that another process owns"):
        transport.rate(corner.from_cells(numpy.ones((16,) + GRID.shape)), 0.0)


def test_the_walls_of_a_box_come_from_the_registry_by_their_side_names():
    """The sides of a box are named as the description's walls: left, right, bottom,
    top."""
    box = Box((6, 6), (1.0, 1.0), 1, GRID)
    assert [str(side) for side in box.sides] == ["left", "right", "bottom", "top"]
    assert box.axes == ("x", "y") and box.cell_volume == pytest.approx(1 / 36)
    registries = default_registries()
    walls = [registries.create("boundaries", name) for name in ("periodic",) * 2
             + ("specular",) * 2]
    BoxTransport(box, MUSCL(), walls)
