"""The sides of the space domain (granframe.abc.Side) and the one problem of every run.

A side is a space axis and an end; a wall sees its side in its own frame (the normal velocity
first, leaving with v_1 > 0). The transport's speeds and wall weights take the axis too. A
space-homogeneous run is the problem of zero space dimensions.
"""

import numpy
import pytest

from granframe.abc import SIDE_NAMES, Side, reflect_nodes
from granframe.parallel import CellLayout, SerialCommunicator, check_store_chunks
from granframe.registry import default_registries
from granframe.run.description import RunDescription
from granframe.run.problems import Interval, Point, SpaceProblem, make_problem
from granframe.run.problems.spaces import space_layout
from granframe.space.boundaries import Diffuse, Specular, Vibrating
from granframe.space.collisions import FreeFlight, SplitStep
from granframe.space.domain import Domain
from granframe.space.hierarchy import realizability
from granframe.space.transport import Transport, upwind_speeds, wall_weights
from granframe.testing.conformance import WALL_SIDES
from granframe.velocity.grid import VelocityGrid
from granframe.velocity.moments import FieldMoments
from test_parallel import SPACE

SIDES = [Side(axis, end) for axis in range(3) for end in (0, 1)]


@pytest.mark.parametrize("side", SIDES, ids=str)
def test_a_side_is_named_as_the_walls_of_a_description(side):
    assert Side.named(side.name) == side
    assert Side.named(side) is side
    assert str(side) == SIDE_NAMES[side.axis][side.end]
    assert side.normal_sign == (1.0 if side.end == 0 else -1.0)


@pytest.mark.parametrize("name", ["up", "", None, 3])
def test_an_unknown_side_is_refused_by_name(name):
    with pytest.raises(ValueError, match="^Side: parameter 'side' = .* is invalid; must be one "
                                         "of 'left', 'right', 'bottom'"):
        Side.named(name)


@pytest.mark.parametrize("axis, end", [(3, 0), (-1, 0), (0, 2), (True, 0), (0, False)])
def test_a_side_out_of_range_is_refused(axis, end):
    with pytest.raises(ValueError, match="^Side: parameter '(axis|end)' = .* is invalid; must "
                                         "be 0 "):
        Side(axis, end)


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_wall_frame_is_a_permutation_of_the_nodes_and_its_inverse(dimension):
    rng = numpy.random.default_rng(dimension)
    f = rng.random((3,) + (8,) * dimension)
    for side in SIDES[:2 * dimension]:
        if side.axis >= dimension:
            continue
        wall = side.to_wall(f, dimension, numpy)
        assert numpy.array_equal(side.from_wall(wall, dimension, numpy), f)
        assert sorted(wall.ravel()) == sorted(f.ravel())
    assert Side(0, 0).to_wall(f, dimension, numpy) is f
    assert numpy.array_equal(Side(0, 1).to_wall(f, dimension, numpy),
                             reflect_nodes(f, dimension, numpy))


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_speeds_and_wall_weights_of_an_axis_are_those_of_x_with_the_axes_exchanged(
        dimension):
    grid = VelocityGrid(dimension, 16, 4.0)
    for axis in range(1, dimension):
        for along, along_x in zip(upwind_speeds(grid, numpy, axis),
                                  upwind_speeds(grid, numpy, 0)):
            assert numpy.array_equal(numpy.swapaxes(along, 0, axis), along_x)
        weights, weights_x = wall_weights(grid, axis), wall_weights(grid, 0)
        rows = list(range(dimension + 2))       # mass, momentum v_1 .. v_d, energy
        rows[1], rows[1 + axis] = rows[1 + axis], rows[1]
        # equal but for the order of the sum |v|^2 in the energy
        assert numpy.allclose(numpy.swapaxes(weights, 1, 1 + axis)[rows], weights_x,
                              rtol=1e-15, atol=0)


@pytest.mark.parametrize("wall", [Diffuse(temperature=0.8, velocity=0.3),
                                  Diffuse(temperature=1.2, accommodation=0.4), Specular()],
                         ids=repr)
@pytest.mark.parametrize("side", [Side(1, 0), Side(1, 1)], ids=str)
def test_a_wall_across_y_lets_no_mass_through_along_v2(wall, side):
    """A wall at the bottom or top, mapped by its side, emits along v_2 exactly the mass that
    arrives along v_2 (the flux c^+ f^- + c^- f^+ of the y speeds sums to zero), as a wall
    across x does along v_1."""
    grid = VelocityGrid(2, 24, 4.0)
    mesh = grid.mesh()
    incoming = numpy.exp(-((mesh[0] - 0.4) ** 2 + (mesh[1] + 0.2) ** 2) / 1.3)
    wall.check(grid)
    out = side.from_wall(wall.emit(side.to_wall(incoming, 2, numpy), grid, numpy, t=0.03,
                                   side=side), 2, numpy)
    positive, negative = upwind_speeds(grid, numpy, axis=1)
    flux = (positive * out + negative * incoming if side.end == 0
            else positive * incoming + negative * out)
    scale = float((positive * incoming).sum() - (negative * incoming).sum())
    assert abs(float(flux.sum())) <= 1e-14 * scale


def _description(space: bool) -> RunDescription:
    """test_parallel's space run of 12 cells, or the same without its space section."""
    return RunDescription.from_toml(SPACE if space else SPACE.split("[space]")[0])


def test_a_space_homogeneous_run_is_the_problem_of_zero_space_dimensions():
    problem = make_problem(_description(space=False))
    assert type(problem) is SpaceProblem and isinstance(problem.space, Point)
    assert problem.space.dimension == 0
    assert problem.owned == slice(None) and problem.ranges == ((0, 1),)
    assert isinstance(problem.communicator, SerialCommunicator)
    assert problem.integrator is problem.collision_integrator      # no transport to split
    assert problem.domain is None and problem.transport is None
    layout = problem.layout()
    assert layout.snapshot_dimensions == ("v1", "v2")
    state = problem.state(problem.f0)
    assert numpy.array_equal(problem.snapshot(problem.step(0.0, state, 0.002)).shape,
                             problem.f0.shape)
    assert set(problem.record(state)) >= {"mass", "temperature", "kurtosis", "heat_flux"}


def test_a_run_with_a_space_section_is_the_same_problem_on_an_interval():
    problem = make_problem(_description(space=True), communicator=SerialCommunicator())
    assert type(problem) is SpaceProblem and isinstance(problem.space, Interval)
    assert problem.space.dimension == 1 and problem.domain.axes == ("x",)
    assert [str(side) for side in problem.domain.sides] == ["left", "right"]
    assert problem.transport.axis == 0 and problem.fields.transport_axes == (0,)
    assert problem.layout().snapshot_dimensions == ("x", "v1", "v2")
    assert problem.owned == slice(0, 12) and tuple(problem.ranges) == ((0, 12),)


def test_a_side_equals_its_name_for_walls_written_against_names():
    assert Side(0, 1) == "right" and Side(1, 0) == "bottom" and Side(0, 0) != "right"
    assert {"left": 1.0, "right": -1.0}[Side(0, 1)] == -1.0
    assert Side(1, 1) != Side(0, 1) and Side(1, 1) == Side(1, 1)


def test_the_vibrating_wall_is_the_same_on_every_side():
    """In the small-amplitude limit the wall averages over the phase: what it sends back
    in its own frame does not depend on its side or on t (a half period reverses U)."""
    grid = VelocityGrid(2, 16, 5.0)
    f = numpy.random.default_rng(5).uniform(0.1, 1.0, grid.shape)
    for reflection in ("diffuse", "specular"):
        wall = Vibrating(speed=0.3, reflection=reflection)
        left = wall.emit(f, grid, numpy, t=0.0, side="left")
        for side in (Side(0, 1), Side(1, 0), Side(1, 1)):
            assert numpy.array_equal(wall.emit(f, grid, numpy, t=0.7, side=side), left)
    assert wall.period is None
    assert WALL_SIDES == ("left", "right")


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_moments_read_the_node_of_every_transport_axis_in_halves(dimension):
    """With v_1 and v_2 both transport components, the "halves" reading counts the node -L
    of each as zero in the odd powers of that component, and the "periodic" reading turns
    it back into the grid's own moments (the node at -L) to round-off, cross terms of the
    corner node included."""
    grid = VelocityGrid(dimension, 12, 3.0)
    f = numpy.random.default_rng(dimension).random((4,) + grid.shape)
    moments = FieldMoments(grid, 1.0, transport_axes=(0, 1))
    raw = moments.raw(f)
    flat = f.reshape(4, -1) * grid.cell_volume
    actual = [numpy.broadcast_to(m, grid.shape).reshape(-1) for m in grid.mesh()]
    halves = [numpy.where(m == -grid.half_width, 0.0, m) if a < 2 else m
              for a, m in enumerate(actual)]
    squared = sum(m * m for m in actual)
    for node, v in (("halves", halves), ("periodic", actual)):
        read = moments.central(raw, node)
        scale = numpy.abs(flat).sum(axis=1) * grid.half_width ** 3
        assert numpy.allclose(read["momentum"], flat @ numpy.stack(v, 1), rtol=0,
                              atol=1e-14 * scale.max())
        second = numpy.einsum("cn,in,jn->cij", flat, v, v)
        for i in range(dimension):          # the diagonal holds the true v_i^2 in both
            second[:, i, i] = flat @ (actual[i] * actual[i])
        assert numpy.allclose(read["second"], second, rtol=0, atol=1e-14 * scale.max())
        assert numpy.allclose(read["third"], flat @ numpy.stack([m * squared for m in v], 1),
                              rtol=0, atol=1e-14 * scale.max())
    assert numpy.allclose(moments.central(raw, "periodic")["momentum"][0],
                          grid.momentum(f[0]), rtol=1e-13, atol=0)


def test_the_default_transport_axis_is_v1_and_bad_axes_are_refused():
    grid = VelocityGrid(2, 12, 3.0)
    assert FieldMoments(grid, 1.0).transport_axes == (0,)
    for axes in [(1, 0), (0, 0), (2,), ("x",), None, (True,)]:
        with pytest.raises(ValueError, match="FieldMoments: parameter 'transport_axes'"):
            FieldMoments(grid, 1.0, transport_axes=axes)


def test_the_shapes_of_space_have_one_interface():
    """What SpaceProblem reads of its shape, every shape has: a further axis is a further
    shape with these members."""
    members = {"dimension", "collisions", "owned", "owned_cells", "ranges", "communicator",
               "domain", "transport", "fields", "left", "right", "reconstruction",
               "cell_layout", "reduction_seconds", "build", "initial", "integrator",
               "layout", "record_names", "state", "snapshot", "record", "monitors", "report",
               "progress_text"}
    point = Point(_description(space=False), outline=True)
    interval = Interval(_description(space=True), outline=True)
    for shape in (point, interval):
        missing = {name for name in members if not hasattr(shape, name)}
        assert not missing, (type(shape).__name__, missing)
    assert (point.dimension, interval.dimension) == (0, 1)


# -- cells along an axis: the domain, its layout, the transport, the fields, the store -------

def _swap(f, dimension=2):
    """f (..., *grid.shape) with the velocity axes 1 and 2 exchanged."""
    return numpy.swapaxes(f, f.ndim - dimension, f.ndim - dimension + 1)


def _cells(grid, cells, seed):
    """Smooth positive cells: Maxwellians whose drift and temperature vary from cell to
    cell along both velocity components."""
    rng = numpy.random.default_rng(seed)
    return numpy.stack([grid.maxwellian(1.0 + 0.3 * rng.random(), (rng.normal(0, 0.4),
                                                                   rng.normal(0, 0.4)),
                                        0.6 + 0.5 * rng.random()) for _ in range(cells)])


WALL_PAIRS = {
    "periodic": ("periodic", {}, "periodic", {}),
    "diffuse-specular": ("diffuse", {"temperature": 1.2, "velocity": 0.3, "accommodation": 0.6},
                         "specular", {}),
    "specular-diffuse": ("specular", {}, "diffuse", {"temperature": 0.8, "velocity": -0.2}),
}


@pytest.mark.parametrize("walls", list(WALL_PAIRS))
@pytest.mark.parametrize("reconstruction", ["muscl", "weno5"])
def test_cells_along_y_are_the_cells_along_x_with_the_velocity_axes_exchanged(walls,
                                                                                reconstruction):
    """The domain, the transport and its walls, and the fields take their axis: the same
    cells laid along y, with f's velocity axes 1 and 2 exchanged, step as those along x
    (three blocks, three Strang steps of free flight through the walls): bitwise when
    periodic, to round-off through a diffuse wall (its emission sums over the nodes in
    another order); the wall totals with the momentum components exchanged and the fields
    with theirs to round-off too."""
    registries = default_registries()
    grid = VelocityGrid(2, 16, 4.0)
    lower, low_params, upper, up_params = WALL_PAIRS[walls]
    scheme = registries.create("reconstructions", reconstruction)
    f0 = _cells(grid, 12, 1)
    results = []
    for axis, f in ((0, f0), (1, _swap(f0))):
        domain = Domain(12, 1.5, 4, scheme.ghost, grid, axis=axis)
        transport = Transport(domain, scheme, registries.create("boundaries", lower, **low_params),
                              registries.create("boundaries", upper, **up_params))
        step, array = SplitStep(FreeFlight(), transport), domain.from_cells(f)
        for k in range(3):
            array = step.step(None, 0.01 * k, array, 0.01)
        cells = domain.to_cells(array)
        fields = FieldMoments(grid, domain.dx, transport_axes=(transport.axis,))
        results.append((domain, cells, transport.take_wall_totals(), fields(cells)))
    (x, at_x, walls_x, fields_x), (y, at_y, walls_y, fields_y) = results
    assert (x.axes, y.axes) == (("x",), ("y",)) and y.sides == ("bottom", "top")
    assert numpy.abs(at_x - f0).max() > 1e-3                  # f moved, and through the walls
    if walls == "periodic":
        numpy.testing.assert_array_equal(at_y, _swap(at_x))
    else:       # a diffuse wall sums its emission over the nodes in the other order
        numpy.testing.assert_allclose(at_y, _swap(at_x), rtol=0, atol=1e-15 * at_x.max())
    numpy.testing.assert_allclose(walls_y[:, [0, 2, 1, 3]], walls_x, rtol=0,
                                  atol=1e-14 * numpy.abs(walls_x).max())
    for name, exchanged in (("density", lambda a: a), ("velocity", lambda a: a[:, ::-1]),
                            ("pressure_tensor", lambda a: a[:, ::-1, ::-1]),
                            ("heat_flux", lambda a: a[:, ::-1])):
        numpy.testing.assert_allclose(fields_y[name], exchanged(fields_x[name]), rtol=0,
                                      atol=1e-14 * numpy.abs(fields_x[name]).max(),
                                      err_msg=name)
    if walls != "periodic":
        assert numpy.abs(walls_x[:, 1]).max() > 1e-4          # the walls took momentum


def test_the_layout_and_the_store_of_cells_along_y_name_that_axis():
    grid = VelocityGrid(2, 8, 4.0)
    layout = CellLayout(24, 2, 3, 1, block_cells=4, axis=1)
    assert (layout.axis, layout.ranges, layout.owned, layout.block) == (
        1, [(0, 8), (8, 16), (16, 24)], slice(8, 16), 4)
    domain = Domain(24, 2.0, layout.block, 2, grid, owned=(layout.start, layout.stop),
                    axis=layout.axis)
    store = space_layout(grid, domain, layout.chunk)
    assert store.snapshot_dimensions == ("y", "v1", "v2")
    assert store.snapshot_chunks[0] == layout.chunk == 4
    assert [c[0] for c in store.coordinates] == ["v1", "v2", "y"]
    numpy.testing.assert_array_equal(store.coordinates[-1][1], domain.centres())
    numpy.testing.assert_allclose(domain.centres(), (numpy.arange(24) + 0.5) / 12, rtol=1e-15)
    cells = [r for r in store.records if r.cells_chunk is not None]
    assert {r.name for r in cells} >= {"density", "velocity", "temperature"}
    assert all(r.dimensions[0] == "y" and r.chunks[1] == 4 for r in cells)
    for index in (3, -1, 1.0):
        with pytest.raises(ValueError, match="^CellLayout: parameter 'index' = .* is invalid; "
                                             "must be this process's place among the 3 "):
            CellLayout(24, 2, 3, index, block_cells=4, axis=1)
    with pytest.raises(ValueError, match="store is cut into along y"):
        CellLayout(24, 2, 7, 0, block_cells=4, axis=1)
    with pytest.raises(ValueError, match="chunked by 8 cells along y"):
        check_store_chunks([(0, 12), (12, 24)], 8, 24, "run.zarr", axis=1)


@pytest.mark.parametrize("axis", [2, -1, True, 1.0])
def test_a_domain_refuses_an_axis_the_velocity_grid_does_not_have(axis):
    with pytest.raises(ValueError, match="^Domain: parameter 'axis' = .* is invalid; must be "
                                         "a space axis below the velocity dimension 2: 0 "
                                         r"\(x\), 1 \(y\)"):
        Domain(12, 1.0, 4, 2, VelocityGrid(2, 8, 4.0), axis=axis)


def test_the_realizability_of_cells_along_y_differentiates_along_y():
    """kappa of a profile along y with the velocity components exchanged is kappa of the
    same profile along x (the stress and the heat flux of the normal component a)."""
    rng = numpy.random.default_rng(3)
    rho, temperature = 1.0 + 0.2 * rng.random(10), 0.8 + 0.4 * rng.random(10)
    for d in (2, 3):
        velocity = rng.normal(0, 0.3, (10, d))
        swapped = velocity.copy()
        swapped[:, [0, 1]] = velocity[:, [1, 0]]
        for periodic in (True, False):
            along_x = realizability(rho, velocity, temperature, 0.1, periodic, 0.01, rho)
            along_y = realizability(rho, swapped, temperature, 0.1, periodic, 0.01, rho,
                                    axes=(1,))
            numpy.testing.assert_allclose(along_y, along_x, rtol=1e-14, atol=0)
            assert along_x.max() > 0.0
