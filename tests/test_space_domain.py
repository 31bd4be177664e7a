"""The domain: what a process owns, and ghost cells filled through it.

One domain that owns every cell touches both ends; a domain that owns a range of whole
blocks touches a wall only where its range does, applies that wall only there, and asks
its neighbours for the ghosts of an end inside the interval. Three domains that own a
third of the cells each, their ghosts filled from one another, give the transport of one
domain that owns all, to the last bit."""

import numpy
import pytest

import granframe as gf
from granframe.space.boundaries import Diffuse, Periodic
from granframe.space.domain import Domain
from granframe.space.reconstruction import WENO5
from granframe.space.transport import Transport

GRID = gf.VelocityGrid(dimension=2, n_modes=16, support_radius=3.0)
CELLS, BLOCK = 24, 4


def _f(seed=0):
    rng = numpy.random.default_rng(seed)
    x = (numpy.arange(CELLS) + 0.5) / CELLS
    rho = 1.0 + 0.3 * numpy.sin(2 * numpy.pi * x) + 0.05 * rng.random(CELLS)
    m = GRID.maxwellian(temperature=0.8)
    return rho[:, None, None] * m[None]


class Neighbours:
    """Ghosts of an end of an owned range, from the owners of the cells beyond it (here:
    other domains in this process); what an MPI exchange does between ranks."""

    def __init__(self, owners, periodic):
        self.owners, self.periodic = owners, periodic

    def cells(self, start, stop):
        values = []
        for j in range(start, stop):
            j = j % CELLS if self.periodic else j
            for domain, array in self.owners:
                if domain.start <= j < domain.stop:
                    block, offset = divmod(j - domain.start, domain.block_cells)
                    values.append(array[block, domain.ghost + offset])
        return numpy.stack(values)

    def start(self, domain, array, sides):
        g = domain.ghost
        if "left" in sides:
            array[0, :g] = self.cells(domain.start - g, domain.start)
        if "right" in sides:
            array[-1, -g:] = self.cells(domain.stop, domain.stop + g)
        return self

    def wait(self):
        """Filled at start."""


def _split_step(left, right, tau, t=0.0, parts=3):
    """One SSPRK3 transport sub-step of three domains that own a third each, in lockstep."""
    reconstruction = WENO5()
    size = CELLS // parts
    domains = [Domain(CELLS, 1.0, BLOCK, reconstruction.ghost, GRID,
                      owned=(k * size, (k + 1) * size)) for k in range(parts)]
    owners = [(domain, domain.from_cells(_f()[domain.owned])) for domain in domains]
    for domain in domains:
        domain.neighbours = Neighbours(owners, left.periodic)
    transports = [Transport(domain, reconstruction, left, right) for domain in domains]
    starts = [domain.interior(array).copy() for domain, array in owners]
    stages = ((0.0, lambda s, k: s + tau * k[0]),
              (tau, lambda s, k: s + 0.25 * tau * (k[0] + k[1])),
              (0.5 * tau, lambda s, k: s + tau / 6.0 * (k[0] + k[1] + 4.0 * k[2])))
    rates = [[] for _ in domains]
    for offset, update in stages:
        for i, (transport, (domain, array)) in enumerate(zip(transports, owners)):
            rates[i].append(transport.rate(array, t + offset)[0])
        for i, (domain, array) in enumerate(owners):
            domain.interior(array)[...] = update(starts[i], rates[i])
    return numpy.concatenate([domain.to_cells(array) for domain, array in owners])


def _whole_step(left, right, tau, t=0.0):
    reconstruction = WENO5()
    domain = Domain(CELLS, 1.0, BLOCK, reconstruction.ghost, GRID)
    array = domain.from_cells(_f())
    Transport(domain, reconstruction, left, right).advance(array, tau, t)
    return domain.to_cells(array)


@pytest.mark.parametrize("ends", ["periodic", "walls"])
def test_three_owners_transport_as_one_to_the_last_bit(ends):
    if ends == "periodic":
        left = right = Periodic()
    else:
        left, right = Diffuse(temperature=1.2, accommodation=0.6), Diffuse(temperature=0.7)
    tau = 0.4 / CELLS / GRID.half_width
    assert numpy.array_equal(_split_step(left, right, tau), _whole_step(left, right, tau))


class CountingWall(Diffuse):
    """A diffuse wall that counts where it was asked for ghost cells."""

    def ghosts(self, inside, grid, xp, *, t=0.0, side="left"):
        self.calls.append(side)
        return super().ghosts(inside, grid, xp, t=t, side=side)


def test_a_domain_applies_a_wall_only_where_its_range_touches_it():
    wall = CountingWall()
    object.__setattr__(wall, "calls", [])
    middle = Domain(CELLS, 1.0, BLOCK, 3, GRID, owned=(8, 16))
    assert not middle.touches_left and not middle.touches_right
    first = Domain(CELLS, 1.0, BLOCK, 3, GRID, owned=(0, 8))
    assert first.touches_left and not first.touches_right
    whole = Domain(CELLS, 1.0, BLOCK, 3, GRID)
    assert whole.touches_left and whole.touches_right and whole.owned_cells == CELLS

    class Recorder:
        sides = []

        def start(self, domain, array, sides):
            self.sides.extend(sides)
            return self

        def wait(self):
            """Nothing in flight."""

    for domain in (middle, first):
        domain.neighbours = Recorder()
        domain.exchange(domain.from_cells(_f()[domain.owned]), wall, wall, 0.0)
    assert wall.calls == ["left"]                      # only the first range meets a wall
    assert Recorder.sides == ["left", "right", "right"]


def test_a_range_inside_the_interval_without_neighbours_is_refused_clearly():
    domain = Domain(CELLS, 1.0, BLOCK, 3, GRID, owned=(8, 16))
    with pytest.raises(RuntimeError, match="cells 8..15 of 24 have an end that another"):
        domain.exchange(domain.from_cells(_f()[8:16]), Diffuse(), Diffuse(), 0.0)


@pytest.mark.parametrize("owned, parameter", [((3, 8), "block_cells"), ((8, 8), "owned"),
                                              ((0, 28), "owned")])
def test_an_owned_range_of_partial_blocks_is_refused(owned, parameter):
    with pytest.raises(ValueError, match=f"parameter '{parameter}'"):
        Domain(CELLS, 1.0, BLOCK, 3, GRID, owned=owned)
