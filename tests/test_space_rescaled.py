"""The rescaled (self-similar) formulation of a space run (granframe.space.collisions,
granframe.equations.rescaled): g(s, x, xi) with f(t, x, v) = omega^d g(s, x, omega v).

- data uniform in x: every cell is the space-homogeneous rescaled run;
- a shear mode of a cooling gas: the rescaled run, mapped back (u_2 / sqrt(T), rho), is the
  physical run at the same resolution, for hard spheres (kappa = 1, the transport of g is
  that of f) and for Maxwell molecules (kappa = 0, the transport slowed by 1/omega);
- on a rectangle: data along x follow the interval's run up to their frames' offset, and a
  shear mode along the diagonal, mapped back, is the physical run on the square;
- what the self-similar variables do not hold for is refused by name.
"""

import math

import numpy
import pytest

import granframe
from granframe.equations.rescaled import Rescaling
from granframe.run.storage import RunStore
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation

GRID = {"dimension": 2, "n_modes": 24, "support_radius": 4.0}
SHEAR = {"name": "sinusoidal_mode", "field": "velocity", "component": 2, "amplitude": 0.2}
PERIODIC_Y = {"bottom": "periodic", "top": "periodic"}


def _description(rescaled=True, initial=SHEAR, kernel="hard_spheres", final=0.4, dt=0.02,
                 cells=6, space=None, e=0.8, grid=GRID, **options):
    return RunDescription(
        grid=grid, kernel=kernel, restitution={"name": "constant", "value": e},
        initial=initial, integrator="rk4", time_step=dt, final_time=final, rescaled=rescaled,
        conservative=True, output={"snapshot_interval": final},
        space={"cells": cells, **(space or {})}, **options)


def _run(description):
    return Simulation(description).run(None, progress=False).dataset


def test_transport_time_is_the_integral_of_omega_to_the_kappa_minus_one():
    for degree, rate in ((0.0, 0.3), (0.5, 0.7), (1.0, 0.4), (0.0, 0.0)):
        law = Rescaling(rate, degree, (0.0, 0.0))
        nodes, weights = numpy.polynomial.legendre.leggauss(20)
        s0, ds = 1.3, 0.25
        sigma = s0 + 0.5 * ds * (nodes + 1.0)
        exact = 0.5 * ds * float(numpy.sum(weights * law.scale(sigma) ** (degree - 1.0)))
        assert law.transport_time(s0, ds) == pytest.approx(exact, rel=1e-13)


def test_uniform_data_follow_the_homogeneous_rescaled_run_in_every_cell():
    """Hard spheres, e = 0.8: the same a_0 to 3e-7 (measured 1.1e-7: the space run's fixed
    point has u_1 = 0 exactly, the homogeneous one the periodic grid's mean, 8e-5 off) and
    the same g to 5e-6 of its peak after 20 steps, in every cell (measured 2.2e-6: the two
    fixed points part by a_0 s u_1 = 4e-6 in xi_1)."""
    space = _run(_description(initial={"name": "maxwellian"}))
    homogeneous = _run(RunDescription(
        grid=GRID, kernel="hard_spheres", restitution={"name": "constant", "value": 0.8},
        initial={"name": "maxwellian"}, integrator="rk4", time_step=0.02, final_time=0.4,
        rescaled=True, conservative=True, output={"snapshot_interval": 0.4}))
    rate = space.attrs["rescaling_rate"]
    assert rate > 0.1 and space.attrs["rescaling_degree"] == 1.0
    assert rate == pytest.approx(homogeneous.attrs["rescaling_rate"], rel=3e-7)
    g, g_h = space.f.values[-1], homogeneous.f.values[-1]
    assert numpy.abs(g - g_h[None]).max() < 5e-6 * g_h.max()
    assert numpy.ptp(space.temperature.values[-1]) < 1e-12


@pytest.mark.parametrize("kernel", ["hard_spheres", "maxwell"])
def test_a_shear_mode_mapped_back_is_the_physical_run(kernel):
    """u_2 / sqrt(T), rho and T of the rescaled run at s against those of the physical run
    at t(s): 16 cells, WENO5, eps = 0.2, the same velocity grid N = 32, dt = 0.005 in s and
    in t. The mode decays to a third. About their means, u_2 / sqrt(T) agree to 3e-4 of the
    initial amplitude (measured 1.3e-4 for hard spheres, 8.6e-6 for Maxwell molecules), rho
    to 2e-5 (7.2e-6, 4.5e-6) and T = T_g / omega^2 to 3e-4 (1.5e-4, 4.6e-5): the same
    equation in other variables, the runs differing by their discretisations. (The means
    differ by 1e-5 to 1e-4: the node -L, which the fields take as two halves, carries a
    different share of u_2 as T falls on a fixed grid.)"""
    options = dict(kernel=kernel, cells=16, dt=0.005, space={"reconstruction": "weno5"},
                   knudsen=0.2, grid={**GRID, "n_modes": 32})
    rescaled = _run(_description(final=0.4, **options))
    rate, degree = rescaled.attrs["rescaling_rate"], rescaled.attrs["rescaling_degree"]
    assert degree == (1.0 if kernel == "hard_spheres" else 0.0) and rate > 0.1
    t = Rescaling(rate, degree, (0.0, 0.0)).physical_time(0.4)
    steps = round(float(t) / 0.005)
    physical = _run(_description(rescaled=False, final=float(t), **{**options,
                                                                       "dt": float(t) / steps}))

    def shear(ds):      # about its mean: the node -L's share of the mean u_2 differs
        wave = ds.velocity.values[-1][:, 1] / numpy.sqrt(ds.temperature.values[-1])
        return wave - wave.mean()

    initial = numpy.abs(rescaled.velocity.values[0][:, 1]).max()
    assert numpy.abs(shear(physical)).max() < 0.5 * initial        # it has decayed
    assert numpy.abs(shear(rescaled) - shear(physical)).max() < 3e-4 * initial
    assert numpy.abs(rescaled.density.values[-1] - physical.density.values[-1]).max() < 2e-5
    # T_g = omega^2 T: the map of the temperatures, cell by cell
    omega = math.exp(rate * 0.4)
    mapped = rescaled.temperature.values[-1] / omega ** 2
    assert numpy.allclose(mapped, physical.temperature.values[-1], rtol=3e-4)


@pytest.mark.parametrize("change, name", [
    (dict(space={"left": {"name": "diffuse", "temperature": 1.0}, "right": "specular"}),
     "space.left"),
    (dict(space={"left": "specular", "right": {"name": "diffuse", "temperature": 1.0}}),
     "space.right"),
    (dict(space={"collisions": False}), "rescaled"),
    (dict(kernel={"name": "vhs", "exponent": 1.0, "energy_exponent": 0.5}), "kernel"),
    (dict(space={"hierarchy": {}}), "space.hierarchy"),
    (dict(heat_bath=0.1), "heat_bath"),
])
def test_what_the_self_similar_variables_do_not_hold_for_is_refused(change, name):
    with pytest.raises((ValueError, TypeError), match=f"parameter '{name}'"):
        _description(**change)


def test_a_flow_along_x_is_refused_naming_the_initial_condition():
    flow = {"name": "maxwellian", "velocity": [0.3, 0.0]}
    with pytest.raises(ValueError, match="parameter 'initial'.*mean velocity 0 along x \\("):
        Simulation(_description(initial=flow))


def test_a_flow_along_y_on_a_rectangle_is_refused_naming_the_initial_condition():
    flow = {"name": "maxwellian", "velocity": [0.0, 0.3]}
    with pytest.raises(ValueError, match="parameter 'initial'.*u_2 = .*along x and y"):
        Simulation(_description(initial=flow, cells=[6, 5], dt=0.01, space=PERIODIC_Y))


@pytest.mark.parametrize("side", ["bottom", "top"])
def test_a_wall_with_a_temperature_across_y_is_refused_by_its_name(side):
    space = {**PERIODIC_Y, side: {"name": "diffuse", "temperature": 1.0}}
    space["top" if side == "bottom" else "bottom"] = "specular"
    with pytest.raises(ValueError, match=f"parameter 'space.{side}'"):
        _description(cells=[6, 5], dt=0.01, space=space)


def test_data_along_x_on_a_rectangle_follow_the_interval_run_up_to_their_frames():
    """The shear mode u_2 = 0.2 sin 2 pi x on 6 x 5 cells (periodic across) and on the
    interval's 6 cells, 10 steps. The rectangle reads u_2 with the node -L in halves, as the
    fields do, so its frame is u = 0 exactly; the interval reads the velocity across x with
    the node -L at -L (the collision operator's own reading), u_2 = 6.7e-5. The drifts
    a_0 div((xi - u) g) then differ by a_0 du_2 d_xi2 g, and over s the profiles part by at
    most a_0 s |du_2| max|d_xi2 g| (1.6e-7; measured 7.6e-8), a_0 by 1e-7 (5.5e-8); every
    row along y stays the same profile to round-off."""
    line = _run(_description(final=0.1, dt=0.01))
    rect = _run(_description(final=0.1, dt=0.01, cells=[6, 5], space=PERIODIC_Y))
    rate = line.attrs["rescaling_rate"]
    assert rect.attrs["rescaling_velocity"] == [0.0, 0.0]
    offset = line.attrs["rescaling_velocity"][1]
    assert 1e-5 < abs(offset) < 1e-4
    assert rect.attrs["rescaling_rate"] == pytest.approx(rate, rel=1e-7)
    g_line, g_rect = line.f.values[-1], rect.f.values[-1]
    slope = numpy.abs(numpy.diff(g_line, axis=-1)).max() / (2 * GRID["support_radius"] / 24)
    assert numpy.abs(g_rect - g_line[:, None]).max() <= rate * 0.1 * abs(offset) * slope
    assert numpy.abs(g_rect - g_rect[:, :1]).max() < 1e-15 * g_rect.max()


def test_a_rescaled_rectangle_plots_its_physical_fields(tmp_path):
    """granframe plot draws a rescaled run on a rectangle (it failed on the cell size of
    the kinetic energy: a length and a count per axis), its energy that of f."""
    from granframe.tools.cli import main
    from granframe.tools.plot_data import RunData

    path = tmp_path / "square.zarr"
    Simulation(_description(final=0.02, dt=0.01, cells=[6, 5], space=PERIODIC_Y,
                            initial={**SHEAR, "mode": [1, 1]})).run(path, progress=False)
    run = RunData(granframe.open_run(path))
    ds = granframe.open_run(path)
    law = Rescaling.from_store(RunStore.open(path))
    fields = law.physical_fields(ds.step_time.values, *(
        ds[name].values for name in ("density", "velocity", "temperature", "pressure_tensor",
                                     "heat_flux")))
    energy = fields["energy_density"].sum(axis=(1, 2)) / 30
    numpy.testing.assert_allclose(run.moments["kinetic_energy"], energy, rtol=1e-14)
    assert main(["plot", str(path), "--out", str(tmp_path / "plots")]) == 0
    assert {"plane_0.png", "plane_1.png"} <= {p.name for p in (tmp_path / "plots").iterdir()}


def test_a_diagonal_shear_mode_mapped_back_is_the_physical_run_on_a_square():
    """Maxwell molecules (the transport of g slowed by 1/omega), e = 0.8, eps = 0.2: the shear
    mode u = 0.2 sin 2 pi (x + y) (-1, 1)/sqrt 2 on a periodic 8 x 8 square, MUSCL, rescaled to
    s = 0.2 against the physical run to t(s), dt = 0.005 in both. The mode decays to 0.27;
    about their means, its u/sqrt(T) agree to 2e-3 of the initial amplitude (measured
    8.1e-4), rho to 1e-4 (3.3e-5) and T = T_g / omega^2 to 6e-4 (3.3e-4). With the
    transport of g left unslowed (transport_time = ds) the modes part by 1.4e-2 (checked by
    hand)."""
    options = dict(kernel="maxwell", cells=[8, 8], dt=0.005, space=PERIODIC_Y, knudsen=0.2,
                   initial={**SHEAR, "mode": [1, 1]}, final=0.2)
    rescaled = _run(_description(**options))
    rate = rescaled.attrs["rescaling_rate"]
    t = float(Rescaling(rate, 0.0, (0.0, 0.0)).physical_time(0.2))
    physical = _run(_description(rescaled=False, **options))
    assert t == 0.2

    def shear(ds, record=-1):
        u = ds.velocity.values[record]
        wave = (u[..., 1] - u[..., 0]) / math.sqrt(2) / numpy.sqrt(ds.temperature.values[record])
        return wave - wave.mean()

    initial = numpy.abs(shear(rescaled, 0)).max()
    assert numpy.abs(shear(physical)).max() < 0.3 * initial
    assert numpy.abs(shear(rescaled) - shear(physical)).max() < 2e-3 * initial
    assert numpy.abs(rescaled.density.values[-1] - physical.density.values[-1]).max() < 1e-4
    mapped = rescaled.temperature.values[-1] / math.exp(rate * 0.2) ** 2
    assert numpy.allclose(mapped, physical.temperature.values[-1], rtol=6e-4, atol=0)


def test_a_specular_box_is_accepted_and_its_mass_kept():
    ds = _run(_description(initial={"name": "sinusoidal_mode", "field": "density",
                                    "amplitude": 0.3},
                           space={"left": "specular", "right": "specular"}, final=0.1))
    mass = ds.mass.values
    assert abs(mass[-1] / mass[0] - 1.0) < 1e-13


def test_the_fields_of_a_rescaled_run_map_to_those_of_f_and_its_store_plots(tmp_path):
    """Rescaling.physical_fields of the recorded fields of g equal the fields of the
    physical f of the last snapshot (Rescaling.physical: f = omega^d g on the grid
    v = u + (xi - u)/omega; its node -L of v_1 read in halves, as the fields read it),
    to round-off; granframe plot draws the store (it raised
    KeyError: 'temperature') with the physical fields against t."""
    from granframe.tools.cli import main
    from granframe.tools.plot_data import RunData
    path = tmp_path / "rescaled.zarr"
    d = _description(final=0.1, dt=0.02, initial=dict(SHEAR, component=2))
    Simulation(d).run(path, progress=False)
    ds = granframe.open_run(path)
    law = Rescaling.from_store(RunStore.open(path))
    s, step = float(ds.time.values[-1]), int(ds.snapshot_step.values[-1])
    fields = law.physical_fields(ds.step_time.values[step:step + 1], *(
        ds[name].values[step:step + 1] for name in ("density", "velocity", "temperature",
                                                     "pressure_tensor", "heat_flux")))
    grid = d.grid
    omega = float(law.scale(s))
    assert omega > 1.01          # the gas has cooled: f and g differ by 1 % and more
    axes, f = law.physical(grid, ds.f.values[-1], s)
    h = (axes[0][1] - axes[0][0]) ** grid.dimension
    # the fields read the node -L of v_1 (the transport component) in halves, at -L and +L
    axes[0] = numpy.append(axes[0], -axes[0][0])
    f = numpy.concatenate([f, f[:, :1]], axis=1)
    f[:, [0, -1]] *= 0.5
    mesh = numpy.meshgrid(*axes, indexing="ij")
    rho = f.sum(axis=(1, 2)) * h
    u = numpy.stack([(f * m).sum(axis=(1, 2)) * h / rho for m in mesh], axis=1)
    c = [m[None] - u[:, i, None, None] for i, m in enumerate(mesh)]
    pressure = numpy.stack([numpy.stack([(f * c[i] * c[j]).sum(axis=(1, 2)) * h
                                         for j in range(2)], axis=1) for i in range(2)], axis=1)
    numpy.testing.assert_allclose(fields["density"][0], rho, rtol=1e-12)
    numpy.testing.assert_allclose(fields["velocity"][0], u, rtol=0, atol=1e-12)
    numpy.testing.assert_allclose(fields["pressure_tensor"][0], pressure, rtol=0,
                                  atol=1e-10 * numpy.abs(pressure).max())
    speed2 = c[0] ** 2 + c[1] ** 2
    heat = numpy.stack([(f * c[i] * speed2).sum(axis=(1, 2)) * h / 2 for i in range(2)],
                       axis=1)
    numpy.testing.assert_allclose(fields["heat_flux"][0], heat, rtol=0,
                                  atol=1e-10 * numpy.abs(heat).max())
    numpy.testing.assert_allclose(fields["temperature"][0],
                                  numpy.trace(pressure, axis1=1, axis2=2) / (2 * rho),
                                  rtol=1e-10)
    run = RunData(ds)
    numpy.testing.assert_allclose(run.field("temperature")[step], fields["temperature"][0])
    assert run.step_time[-1] == pytest.approx(float(law.physical_time(s)))
    assert run.moments["kinetic_energy"][-1] < run.moments["kinetic_energy"][0]
    assert main(["plot", str(path), "--out", str(tmp_path / "figures")]) == 0
    assert {p.name for p in (tmp_path / "figures").iterdir()} >= {"maps.png", "totals.png"}
