"""Runs on a rectangle, ``space.cells = [Cx, Cy]``, through the description, the runner and
the store.

- uniform data are the space-homogeneous run in every cell; data along x alone (a
  Riemann problem between diffuse walls, periodic across y) are the interval's run in every
  row, and data along y alone (a mode with the wave vector [0, 1]) the interval's run with
  the velocity components exchanged, in every column;
- the store holds f (time, x, y, v) and the fields (step_time, x, y, ...) chunked on both
  axes, the wall records of the four sides, and opens with the coordinates x and y;
- a wave vector off the axes, the four quadrants of a two-dimensional Riemann problem and
  f0(x, y, v) give the cell averages they name;
- what a rectangle cannot run is refused by name before anything is written.
"""

import numpy
import pytest

import granframe
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore
from granframe.space.initial import QuadrantProblem, SinusoidalMode, SpaceFunction
from granframe.tools.cli import main

GRID = {"dimension": 2, "n_modes": 24, "support_radius": 3.5}
SOD = {"name": "riemann", "left": {"density": 1.0, "temperature": 1.0},
       "right": {"density": 0.5, "temperature": 0.8}}


FAST = {"name": "fast_spectral", "radial_points": 8,
        "sphere": {"name": "circle_trapezoid", "n_points": 8}}


def _description(space, initial=SOD, final=0.03, dt=0.005, operator=FAST, **options):
    return RunDescription.from_dict({
        "title": "rectangle", "grid": GRID, "kernel": "maxwell",
        "restitution": {"name": "constant", "value": 0.9}, "initial": initial,
        "operator": operator, "backend": {"name": "numpy", "threads": 1}, "knudsen": 0.1,
        "time_step": dt, "final_time": final, "output": {"snapshot_interval": final},
        "space": space, **options})


def _run(description, out=None):
    return Simulation(description).run(out, progress=False).dataset


def test_uniform_data_on_a_rectangle_are_the_homogeneous_run_in_every_cell():
    """A Maxwellian at rest in a periodic rectangle: every cell steps as the
    space-homogeneous run (the transport moves nothing, the collision step is the same),
    to round-off over six steps."""
    maxwellian = {"name": "maxwellian", "temperature": 1.0}
    box = _run(_description({"cells": [5, 6], "length": [1.0, 0.8]}, initial=maxwellian))
    point = _run(_description(None, initial=maxwellian))
    f, f_point = box.f.values[-1], point.f.values[-1]
    assert numpy.abs(f_point - point.f.values[0]).max() > 1e-4 * f_point.max()   # it cooled
    numpy.testing.assert_allclose(f, numpy.broadcast_to(f_point, f.shape), rtol=0,
                                  atol=1e-14 * f_point.max())


def test_data_along_x_are_the_interval_run_in_every_row():
    """A Riemann problem along x between a hot diffuse wall and a specular one, periodic
    across y: f in every row is the interval's, bit for bit; what crossed each wall of x is
    the interval's times the height, and nothing crosses the sides of y. The fields that do
    not involve v_2 (rho, u_1, P_11) are the interval's to round-off; on a rectangle v_2 is
    carried along y, so its node -L counts as half moving each way (no net v_2), as v_1's
    does on both: rho u_2 differs from the interval's by exactly the content of that node,
    -L h^2 sum_{v_1} f(v_1, -L)."""
    walls = {"left": {"name": "diffuse", "temperature": 1.2}, "right": "specular",
             "reconstruction": "weno5"}
    line = _run(_description({"cells": 16, **walls}, final=0.032, dt=0.004))
    box = _run(_description({"cells": [16, 7], "length": [1.0, 0.4], **walls}, final=0.032,
                            dt=0.004))
    assert box.density.dims == ("step_time", "x", "y")
    f_line = line.f.values
    assert numpy.abs(f_line[-1] - f_line[0]).max() > 1e-3
    for j in range(7):
        numpy.testing.assert_array_equal(box.f.values[:, :, j], f_line)
    for name, pick in (("density", lambda a: a), ("velocity", lambda a: a[..., 0]),
                       ("pressure_tensor", lambda a: a[..., 0, 0])):
        want = pick(line[name].values)[:, :, None]
        numpy.testing.assert_allclose(pick(box[name].values), numpy.broadcast_to(
            want, box.density.shape), rtol=0, atol=1e-14 * numpy.abs(want).max(),
            err_msg=name)
    grid = granframe.VelocityGrid(**GRID)
    node = -grid.half_width * grid.spacing ** 2 * f_line[-1][..., 0].sum(axis=-1)
    rho = line.density.values[-1]
    difference = rho * (line.velocity.values[-1, :, 1] - box.velocity.values[-1, :, 0, 1])
    assert numpy.abs(node).max() > 1e-7                    # the node holds something
    numpy.testing.assert_allclose(difference, node, rtol=0, atol=1e-14)
    numpy.testing.assert_allclose(box.wall_energy.values[:, :2], 0.4 * line.wall_energy.values,
                                  rtol=0, atol=1e-15)
    numpy.testing.assert_allclose(box.wall_momentum.values[:, :2],
                                  0.4 * line.wall_momentum.values, rtol=0, atol=1e-15)
    assert numpy.abs(line.wall_energy.values).max() > 1e-5
    numpy.testing.assert_array_equal(box.wall_energy.values[:, 2:], 0.0)


def test_data_along_y_are_the_interval_run_with_the_velocity_axes_exchanged():
    """A density mode with the wave vector [0, 1] between specular sides of x (the data are
    even in v_1) and diffuse walls at the bottom and the top: every column is the interval's
    run of the mode along x with its velocity components exchanged, to round-off. The
    direct spectral operator commutes with the exchange to round-off (2e-15 of |Q|); the
    fast one at these settings (8 radial points, 8 or 16 directions, N = 24) does not, by
    1 % of |Q|, and its runs part by 2e-5 of max f over six steps."""
    mode = {"name": "sinusoidal_mode", "field": "density", "amplitude": 0.3}
    wall = {"name": "diffuse", "temperature": 1.1}
    direct = {"operator": {"name": "direct_spectral"}}
    line = _run(_description({"cells": 12, "left": wall, "right": wall}, initial=mode,
                             **direct))
    box = _run(_description({"cells": [5, 12], "left": "specular", "right": "specular",
                             "bottom": wall, "top": wall},
                            initial={**mode, "mode": [0, 1]}, **direct))
    f_line, f_box = line.f.values[-1], box.f.values[-1]
    assert numpy.abs(f_line - line.f.values[0]).max() > 1e-3 * f_line.max()
    for i in range(5):
        numpy.testing.assert_allclose(f_box[i], numpy.swapaxes(f_line, -1, -2), rtol=0,
                                      atol=1e-13 * f_line.max())
    numpy.testing.assert_allclose(box.density.values[:, 1], line.density.values, rtol=1e-14)


def test_the_store_of_a_rectangle_is_chunked_on_both_axes(tmp_path):
    """f (time, x, y, v1, v2) in chunks of block_cells along x and y, the fields too; the
    coordinates x and y are the cell centres, the walls named left, right, bottom, top;
    ``granframe info`` shows the rectangle and its four walls."""
    space = {"cells": [8, 6], "length": [1.0, 0.75], "block_cells": [4, 2],
             "left": "specular", "right": "specular",
             "bottom": {"name": "diffuse", "temperature": 1.0},
             "top": {"name": "diffuse", "temperature": 1.0, "velocity": 0.3}}
    mode = {"name": "sinusoidal_mode", "field": "temperature", "amplitude": 0.2,
            "mode": [1, 1]}
    _run(_description(space, initial=mode), tmp_path / "box.zarr")
    ds = granframe.open_run(tmp_path / "box.zarr")
    store = RunStore.open(tmp_path / "box.zarr")
    assert store.group["f"].chunks == (1, 4, 2, 24, 24)
    assert store.group["density"].chunks[1:] == (4, 2)
    assert store.group["velocity"].chunks[1:] == (4, 2, 2)
    assert ds.f.dims == ("time", "x", "y", "v1", "v2")
    numpy.testing.assert_allclose(ds.x.values, (numpy.arange(8) + 0.5) / 8)
    numpy.testing.assert_allclose(ds.y.values, (numpy.arange(6) + 0.5) / 8)
    assert list(ds.wall.values) == ["left", "right", "bottom", "top"]
    assert ds.y.attrs["long_name"] == "cell centre along y"
    # the moving lid drags the gas along x next to it, and nothing crosses a wall
    assert ds.velocity.values[-1, :, -1, 0].mean() > 1e-4
    numpy.testing.assert_allclose(ds.wall_mass.values, 0.0, atol=1e-15)
    assert abs(ds.mass.values[-1] / ds.mass.values[0] - 1.0) < 1e-13
    assert main(["info", str(tmp_path / "box.zarr")]) == 0


def test_initial_data_on_a_rectangle_are_their_cell_averages():
    """A mode along the diagonal is the mode along x rotated: its cell averages on a square
    are symmetric under the mirror about the diagonal (x <-> y, v_1 <-> v_2), which
    reverses its transverse velocity; the quadrants give
    each cell the mixture by its area share; f0(x, y, v) is averaged by the tensor rule
    (a product x^2 y^3 exactly: 1/3 * 1/4 on the unit square)."""
    import granframe as gf

    grid = gf.VelocityGrid(2, 16, 3.5)
    edges = (numpy.linspace(0, 1, 9), numpy.linspace(0, 1, 9))
    shear = SinusoidalMode(field="velocity", amplitude=0.2, mode=[1, 1], component=2)
    f, mass = shear.sample_box(grid, edges)
    inner = (..., slice(1, None), slice(1, None))    # -L has no mirror node (+L)
    numpy.testing.assert_allclose(numpy.transpose(f, (1, 0, 3, 2))[inner],
                                  _negated_v(f, grid)[inner], rtol=0, atol=1e-15 * f.max())
    numpy.testing.assert_allclose(mass, 1.0, rtol=1e-14)
    quadrants = QuadrantProblem(upper_right={"density": 1.0, "temperature": 1.0},
                                upper_left={"density": 0.5, "temperature": 1.0},
                                lower_left={"density": 0.25, "temperature": 1.0},
                                lower_right={"density": 0.125, "temperature": 1.0},
                                interface=[0.3, 0.5])
    _, mass = quadrants.sample_box(grid, edges)
    assert mass[2, 0] == pytest.approx(0.4 * 0.25 + 0.6 * 0.125)        # x = 0.3 in cell 2
    assert mass[0, 7] == 0.5 and mass[7, 7] == 1.0 and mass[7, 0] == 0.125
    cubic = SpaceFunction(function=lambda x, y, v1, v2: x ** 2 * y ** 3 + 0 * v1 * v2)
    f, _ = cubic.sample_box(grid, edges)
    assert f[..., 0, 0].mean() == pytest.approx(1.0 / 12.0, rel=1e-13)


def _negated_v(f, grid):
    """f(x, y, -v1, -v2) on the nodes: a transverse mode along the diagonal mirrored about
    it, f(y, x, v2, v1), has u(x, y) mirrored, (u_2, u_1) = -u(x, y)."""
    from granframe.space.domain import reflect

    mirrored = reflect(f, 2)                                    # v1 -> -v1 on the nodes
    return numpy.swapaxes(reflect(numpy.swapaxes(mirrored, -1, -2), 2), -1, -2)   # v2


@pytest.mark.parametrize("change, parameter, allowed", [
    ({"space": {"cells": [4, 16], "reconstruction": "weno5"}}, "space.cells",
     r"must be >= 7 along every axis"),
    ({"space": {"cells": [8, 8], "bottom": "specular"}}, "space.bottom",
     r"must be periodic too: an axis is periodic at both ends or at neither \(bottom, top\)"),
    ({"space": {"cells": 8}, "initial": {"name": "sinusoidal_mode", "mode": [1, 1]}},
     "mode", r"must be one number k >= 1 on an interval"),
    ({"space": {"cells": [8, 8]}, "time_step": 0.02, "final": 0.04}, "time_step",
     r"must be <= 0.0.*along x and along y at once"),
    ({"space": {"cells": [3000, 3000], "length": [300.0, 300.0]}}, "space.cells",
     (r"with grid.n_modes = 24 \(d = 2\) needs about 7\d\d GiB for this run \(19 copies of "
      r"every cell's f at 38.6 GiB\), more than the memory budget")),
])
def test_what_a_rectangle_cannot_run_is_refused_by_name(change, parameter, allowed):
    settings = {"space": change.pop("space")}
    with pytest.raises(ValueError, match=f"parameter '{parameter}' = .* is invalid; {allowed}"):
        Simulation(_description(settings["space"], **change))


def test_a_wall_of_y_on_an_interval_is_refused_by_name():
    with pytest.raises(ValueError, match="parameter 'bottom' = 'specular' is invalid; is a "
                                         "wall of y: an interval"):
        _description({"cells": 8, "bottom": "specular"})


def test_the_figures_of_a_rectangle_are_maps_at_every_snapshot_and_an_animation(tmp_path,
                                                                               capsys):
    """``granframe plot`` of a run on a rectangle: a figure of maps (rho, T, the speed with
    streamlines, the vorticity) per snapshot and the totals; ``--animate FIELD`` a GIF of
    one frame per snapshot; a field it does not know, or an animation of an interval,
    refused by name."""
    from PIL import Image

    mode = {"name": "sinusoidal_mode", "field": "velocity", "component": 2,
            "amplitude": 0.2, "mode": [1, 1]}
    out = tmp_path / "shear.zarr"
    _run(_description({"cells": [8, 8]}, initial=mode, final=0.02), out)
    folder = tmp_path / "figures"
    assert main(["plot", str(out), "--out", str(folder), "--animate", "vorticity"]) == 0
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["plane_0.png", "plane_1.png", "totals.png", "vorticity.gif"]
    with Image.open(folder / "vorticity.gif") as gif:
        assert gif.n_frames == 2
    from granframe.tools.plot_data import RunData
    from granframe.tools.plot_plane import plane_field

    run = RunData(out)
    vorticity, _ = plane_field(run, "vorticity", 0)
    # a transverse wave along the diagonal: u = A sin(2 pi (x + y)) (-1, 1)/sqrt(2) has
    # omega = d_x u_2 - d_y u_1 = 2 sqrt(2) pi A cos(2 pi (x + y)): the differences see it
    x, y = numpy.meshgrid(run.ds.x.values, run.ds.y.values, indexing="ij")
    exact = 2 * numpy.sqrt(2) * numpy.pi * 0.2 * numpy.cos(2 * numpy.pi * (x + y))
    assert numpy.abs(vorticity - exact).max() < 0.15 * numpy.abs(exact).max()
    capsys.readouterr()
    assert main(["plot", str(out), "--out", str(folder), "--animate", "pressure"]) == 2
    assert "parameter 'animate' = 'pressure' is invalid; must name a field of a run on a " \
           "rectangle" in capsys.readouterr().err


def test_advise_refuses_a_rectangle_by_name(tmp_path, capsys):
    """``granframe advise`` prices runs on an interval only: a rectangle, as a run
    description or as a scene, is refused naming space.cells, with status 2."""
    toml = tmp_path / "box.toml"
    toml.write_text(_description({"cells": [8, 8]}).to_toml())
    assert main(["advise", str(toml)]) == 2
    assert "parameter 'space.cells' = [8, 8] is invalid; advise prices runs on an interval" \
        in capsys.readouterr().err
    scene = tmp_path / "scene.toml"
    scene.write_text("\n".join([
        "dimension = 2", "final_time = 0.5", 'quantity = "temperature"', "tolerance = 0.01",
        'kernel = "maxwell"', "knudsen = 0.1",
        "[restitution]", 'name = "constant"', "value = 0.9", "[initial]",
        'name = "maxwellian"', "[space]", "cells = [8, 8]", ""]))
    assert main(["advise", str(scene)]) == 2
    assert "parameter 'space.cells' = [8, 8] is invalid" in capsys.readouterr().err


def test_plane_modes_are_the_sinusoidal_modes_and_the_heat_mode_of_the_line():
    """granframe.theory.modes:plane_modes_maxwellian as a space function: one transverse mode
    on the wave vector [1, 1] has the cell averages of the sinusoidal mode (component 2) to
    round-off; the heat mode's three parts along x are
    :func:`~granframe.theory.modes.longitudinal_maxwellian` (3D velocities) in every row;
    two transverse modes, along x and along y, are a lattice of vortices whose velocity is
    the sum of the two; bad modes are refused by name."""
    import math
    import re

    import granframe as gf
    from granframe.theory.modes import plane_modes_maxwellian

    grid = gf.VelocityGrid(2, 16, 3.5)
    edges = (numpy.linspace(0, 1, 9), numpy.linspace(0, 1, 9))
    name = "granframe.theory.modes:plane_modes_maxwellian"
    shear = SinusoidalMode(field="velocity", amplitude=0.2, mode=[1, 1], component=2)
    plane = SpaceFunction(function=name, params={"lengths": [1.0, 1.0], "modes": [
        {"field": "transverse", "wave": [1, 1], "amplitude": 0.2}]})
    f_mode, _ = shear.sample_box(grid, edges)
    f_plane, _ = plane.sample_box(grid, edges)
    numpy.testing.assert_allclose(f_plane, f_mode, rtol=0, atol=1e-14 * f_mode.max())

    grid3 = gf.VelocityGrid(3, 8, 4.0)
    k, (r, w, theta) = 2 * math.pi / 3.0, (0.7, -0.4, 0.5)
    heat = SpaceFunction(function=name, params={"lengths": [3.0, 1.0], "modes": [
        {"field": "density", "wave": [1, 0], "amplitude": 0.1 * r},
        {"field": "longitudinal", "wave": [1, 0], "amplitude": 0.1 * w,
         "phase": math.pi / 2},
        {"field": "temperature", "wave": [1, 0], "amplitude": 0.1 * theta}]})
    line = SpaceFunction(function="granframe.theory.modes:longitudinal_maxwellian",
                         params={"k": k, "amplitude": 0.1, "density": r, "velocity": w,
                                 "temperature": theta})
    x_edges = numpy.linspace(0, 3, 7)
    f_heat, _ = heat.sample_box(grid3, (x_edges, numpy.linspace(0, 1, 3)))
    f_line, _ = line.sample_cells(grid3, x_edges)
    for row in range(2):
        numpy.testing.assert_allclose(f_heat[:, row], f_line, rtol=0, atol=1e-14 * f_line.max())

    x, y = numpy.meshgrid(numpy.linspace(0, 1, 5), numpy.linspace(0, 1, 5), indexing="ij")
    vortices = [{"field": "transverse", "wave": [1, 0], "amplitude": 0.1},
                {"field": "transverse", "wave": [0, 1], "amplitude": 0.1}]
    v = grid.points()
    f = plane_modes_maxwellian(x[..., None, None], y[..., None, None], v[:, None], v[None],
                               lengths=[1.0, 1.0], modes=vortices)
    u1 = (f * v[:, None]).sum(axis=(-2, -1)) / f.sum(axis=(-2, -1))
    u2 = (f * v[None]).sum(axis=(-2, -1)) / f.sum(axis=(-2, -1))
    numpy.testing.assert_allclose(u1, -0.1 * numpy.sin(2 * math.pi * y), atol=1e-6)
    numpy.testing.assert_allclose(u2, 0.1 * numpy.sin(2 * math.pi * x), atol=1e-6)
    for modes, bad in (([{"field": "shear", "wave": [1, 0], "amplitude": 0.1}], "[0].field"),
                       ([{"field": "density", "wave": [0, 0], "amplitude": 0.1}], "[0].wave"),
                       ([{"field": "density", "wave": [1.5, 0], "amplitude": 0.1}],
                        "[0].wave"),
                       ([{"field": "density", "wave": [1, 0], "amplitude": "big"}],
                        "[0].amplitude"),
                       ([], "")):
        with pytest.raises(ValueError, match=f"parameter 'modes{re.escape(bad)}'"):
            plane_modes_maxwellian(0.5, 0.5, v, v, lengths=[1.0, 1.0], modes=modes)
