"""The collisionless gas in a box with four diffuse walls (docs/space.md, "The collisionless
box"): its exact steady state on the velocity nodes
(:class:`granframe.space.exact_box.FreeMolecularBox`) and a run that reaches it.

- four walls at one temperature, at rest: the state is the walls' Maxwellian everywhere;
- the walls of x exchanged and those of y sliding the other way: the state mirrored
  (x -> 1 - x, v_1 -> -v_1);
- it holds the mass it is given, and a run of the transport alone settles on it.
"""

import numpy
import pytest

from granframe.space.exact_box import FreeMolecularBox
from granframe.velocity.grid import VelocityGrid

GRID = VelocityGrid(2, 16, 3.5)
WALLS = ((1.0, 0.0), (1.5, 0.0), (1.2, 0.3), (0.8, -0.2))
REST = numpy.asarray(GRID.maxwellian(1.0, None, 1.0))


def test_walls_at_one_temperature_at_rest_hold_their_maxwellian_everywhere():
    """To 1e-6: the state leaves out the nodes v_a = -L, whose share of a wall's emission,
    exp(-L^2 / (2 T_w)) = 1e-10, the slow exchange between the walls amplifies."""
    box = FreeMolecularBox(GRID, (1.0, 0.7), [(1.3, 0.0)] * 4, 0.7, REST, panels=32)
    points = numpy.random.default_rng(2).random((2, 40)) * numpy.array([[1.0], [0.7]])
    f = box.f_at(*points)
    moving = box.moving
    want = numpy.asarray(GRID.maxwellian(1.0, None, 1.3))
    scale = f[0][moving].sum() / want[moving].sum()
    numpy.testing.assert_allclose(f[:, moving], numpy.broadcast_to(scale * want[moving],
                                                                    f[:, moving].shape),
                                  rtol=1e-6)
    assert box.sigma.max() / box.sigma.min() - 1 < 1e-6


def test_the_walls_of_x_exchanged_mirror_the_state():
    walls = [WALLS[1], WALLS[0]] + [(t, -u) for t, u in WALLS[2:]]   # u along v_1 turns
    box = FreeMolecularBox(GRID, (1.0, 1.0), WALLS, 1.0, REST, panels=64)
    mirror = FreeMolecularBox(GRID, (1.0, 1.0), walls, 1.0, REST, panels=64)
    x, y = numpy.random.default_rng(4).random((2, 30))
    f, g = box.f_at(x, y), mirror.f_at(1.0 - x, y)
    # v_1 -> -v_1 on the nodes: index i -> N - i (the node -L, left out, stays)
    flipped = g[:, (-numpy.arange(16)) % 16]
    numpy.testing.assert_allclose(f, flipped, rtol=1e-9, atol=1e-12 * f.max())


def test_the_state_holds_its_mass_and_a_transport_run_settles_on_it():
    """The transport alone (MUSCL) on 6 x 6 cells from the Maxwellian at rest to t = 24:
    steady (the L1 change of f over the last 2.4 below 1e-5), and its density, velocity and
    temperature within the scheme's error on 6 x 6 cells of the exact state's cell averages
    (the exact state's own bar, panels and points halved, is 5e-5 there; the study
    studies/box_2d.py refines the cells)."""
    import pathlib
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "studies"))
    from box_2d import averaged, description, fields

    from granframe.run.runner import Simulation

    run = Simulation(description(6)).run(None, progress=False).dataset
    f = run.f.values
    assert numpy.abs(f[-1] - f[-2]).sum() / numpy.abs(f[-1]).sum() < 1e-5
    exact = FreeMolecularBox(GRID, (1.0, 1.0), WALLS, 1.0, f[0, 0, 0], panels=192)
    truth = averaged(exact.cell_averages((6, 6), 32), 6)
    mass = truth.sum(axis=(2, 3)).mean() * GRID.cell_volume
    assert mass == pytest.approx(1.0, abs=2e-4)       # the averages' midpoint rule: 1.2e-4
    got, want = fields(GRID, f[-1]), fields(GRID, truth)
    errors = {k: float(numpy.abs(got[k] - want[k]).mean()) for k in got}
    # measured 3.8e-3, 5.6e-3, 5.4e-3, 2.5e-3 (the exact state's bar: 5e-5)
    assert errors["rho"] < 4.5e-3 and errors["T"] < 3e-3, errors
    assert errors["u1"] < 6.5e-3 and errors["u2"] < 6.5e-3, errors
    # the state is not uniform: the walls' differences are far above those errors
    assert want["T"].max() - want["T"].min() > 0.1
    assert numpy.abs(want["u1"]).max() > 0.05


def test_the_temperature_bound_is_the_first_order_change_of_t_when_the_nodes_agree():
    """studies/box_2d.py's bound sum_j |dT/df_j| |f_j - g_j|: a perturbation of each node
    by a small multiple of sign(dT/df_j) moves T by the bound to second order, and any
    other perturbation of the same sizes moves it less."""
    import pathlib
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "studies"))
    from box_2d import fields, temperature_bound

    rng = numpy.random.default_rng(7)
    base = numpy.stack([numpy.stack([numpy.asarray(GRID.maxwellian(
        1.0 + 0.2 * rng.random(), [0.3 * rng.random() - 0.1, 0.2 * rng.random()],
        0.8 + 0.5 * rng.random())) for _ in range(2)]) for _ in range(3)])   # (3, 2, *grid)
    size = 1e-7 * rng.random(base.shape) * base.max()
    p = numpy.asarray(GRID.points())
    v1, v2 = numpy.meshgrid(p, p, indexing="ij")
    state = fields(GRID, base)
    weight = [[(v1 - state["u1"][i, j]) ** 2 + (v2 - state["u2"][i, j]) ** 2
               - 2 * state["T"][i, j] for j in range(2)] for i in range(3)]
    aligned = base + size * numpy.sign(numpy.asarray(weight))
    bound = temperature_bound(GRID, aligned, base)
    moved = numpy.abs(fields(GRID, aligned)["T"] - state["T"]).mean()
    assert moved == pytest.approx(bound, rel=1e-5)
    shuffled = base + size * rng.choice([-1.0, 1.0], base.shape)
    assert numpy.abs(fields(GRID, shuffled)["T"] - state["T"]).mean() < 0.5 * bound
    assert temperature_bound(GRID, shuffled, base) == pytest.approx(bound, rel=1e-12)


def test_the_block_errors_see_through_a_shift_inside_the_blocks():
    """studies/box_2d.py's errors on 8 x 8 cells: a run that is the exact state with two
    cells exchanged inside every block of the 4 x 4 grid of blocks (2 x 2 cells each) has
    errors in its cells and none (round-off) over those blocks, while on the 8 x 8 grid of
    blocks (its cells) they are the cells' errors; a run off by a uniform factor has the
    same error on both."""
    import pathlib
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "studies"))
    from box_2d import errors, fields

    rng = numpy.random.default_rng(3)
    exact = numpy.stack([numpy.stack([numpy.asarray(GRID.maxwellian(
        1.0 + rng.random(), [0.2 * rng.random(), 0.0], 0.8 + rng.random()))
        for _ in range(8)]) for _ in range(8)])                       # (8, 8, *grid)
    swapped = exact.copy()
    swapped[0::2, 0::2], swapped[1::2, 1::2] = exact[1::2, 1::2], exact[0::2, 0::2]
    rows = [{"cells": 8}]
    errors(rows, {8: swapped}, GRID, exact, exact)
    row = rows[0]
    assert min(row[f"L1_{k}"] for k in ("rho", "u1", "T")) > 1e-3
    assert row["L1_f"] > 1e-2 and row["bound_T"] >= row["L1_T"]
    assert max(row[f"block4_{k}"] for k in ("rho", "u1", "u2", "T")) < 1e-13
    assert all(row[f"block8_{k}"] == row[f"L1_{k}"] for k in ("rho", "u1", "u2", "T"))
    scaled = [{"cells": 8}]
    errors(scaled, {8: 1.01 * exact}, GRID, exact, exact)
    rho = fields(GRID, exact)["rho"]
    assert scaled[0]["L1_rho"] == pytest.approx(0.01 * rho.mean(), rel=1e-12)
    assert scaled[0]["block4_rho"] == pytest.approx(0.01 * rho.mean(), rel=1e-12)
