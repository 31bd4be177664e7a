"""Validation of the space solver against exact results (docs/space.md), the functions
behind tests/test_space_validation.py and the tables of studies/space_validation.py.

1. Data uniform in x reproduce the space-homogeneous run to round-off (periodic and
   specular ends, explicit and penalised collision steps, heat bath):
   :func:`uniform_difference`.
2. Free transport: the exact cell averages of f0(x - c t, v) (periodic) and of the method
   of images (specular walls); the observed order of each reconstruction:
   :func:`exact_transport`, :func:`convergence`, :func:`orders`.
3. Free-molecular heat transfer between two diffuse walls: the steady state against the
   closed forms on the grid and in the continuum: :func:`free_molecular`.
4. Diffuse walls: mass conserved to round-off; an elastic gas between two walls at the same
   temperature relaxes to the wall Maxwellian: :func:`relaxation`.
"""

from __future__ import annotations

import math

import numpy

from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.space import exact
from granframe.velocity.moments import FieldMoments
from granframe.space.transport import transport_speeds
from granframe.velocity.grid import VelocityGrid

#: the non-Maxwellian uniform state of test 1: two Maxwellians moving apart
MIXTURE = {"name": "gaussian_mixture", "components": [
    {"density": 0.6, "velocity": [0.5, 0.2], "temperature": 0.8},
    {"density": 0.4, "velocity": [-0.75, -0.3], "temperature": 0.5}]}
#: a non-Maxwellian state even in v_1 (a uniform state must be even in v_1 to be steady at a
#: specular wall)
EVEN_MIXTURE = {"name": "gaussian_mixture", "components": [
    {"density": 0.6, "velocity": [0.0, 0.4], "covariance": [[0.5, 0.0], [0.0, 0.8]]},
    {"density": 0.4, "velocity": [0.0, -0.6], "temperature": 0.5}]}
#: a small velocity grid for free transport (L = 6.18, h = 0.77, max |c| = L - h = 5.41)
TRANSPORT_GRID = {"dimension": 2, "n_modes": 16, "support_radius": 2.8}
#: the temperature of the Maxwellian of the free-transport data
T0 = 0.6
COLLISIONS = {"kernel": {"name": "maxwell"},
              "restitution": {"name": "constant", "value": 1.0}}


def run_dataset(**description):
    """The dataset of a run in memory."""
    return Simulation(RunDescription.from_dict(description)).run(None, progress=False).dataset


def dividing_step(final_time, largest):
    """The time step final_time / n with n the fewest steps of at most ``largest``."""
    return final_time / math.ceil(final_time / largest * (1.0 + 1e-12))


# -- 1. uniform data: the homogeneous run, cell by cell ---------------------------------------

def uniform_difference(ends, integrator, heat_bath):
    """The largest differences between a space run of 8 cells from x-uniform data and the
    space-homogeneous run of the same description: of f (relative to max f) and of rho,
    u, T, P (relative to their largest value; u to 1) and q (relative to rho T^{3/2})."""
    periodic = ends == "periodic"
    # fast_spectral's Q commutes with v_1 -> -v_1 only to its quadrature error (2.6e-6 of
    # max |Q| here): from data even in v_1 it makes an odd part of 2e-8 of max f by
    # t = 0.02 (direct_spectral: 7e-16), which a specular wall reflects; the specular runs
    # take direct_spectral.
    base = dict(final_time=0.04, time_step=0.004,
                grid={"dimension": 2, "n_modes": 24, "support_radius": 3.0},
                kernel={"name": "maxwell"}, restitution={"name": "constant", "value": 0.5},
                initial=MIXTURE if periodic else EVEN_MIXTURE,
                operator={"name": "fast_spectral" if periodic else "direct_spectral"},
                integrator={"name": integrator}, heat_bath=heat_bath, knudsen=0.5,
                output={"snapshot_interval": 0.02})
    homogeneous = run_dataset(**base)
    space = run_dataset(**base, space={"cells": 8, "block_cells": 4, "left": ends,
                                       "right": ends})
    f, g = homogeneous.f.values, space.f.values                     # (time, v), (time, x, v)
    assert f.shape[0] == 3 and g.shape[:2] == (3, 8)
    assert numpy.abs(f[-1] - f[0]).max() > 1e-3 * numpy.abs(f).max()   # something happened
    # the fields of the homogeneous snapshots as a space run counts them (the node -L as
    # its two halves +-L, granframe.velocity.moments), against the space run's at those steps
    grid = VelocityGrid(**base["grid"])
    expected = FieldMoments(grid, 1.0)(f)
    steps = [int(numpy.argmin(numpy.abs(space.step_time.values - t)))
             for t in space.time.values]
    rho = expected["density"]
    temperature = expected["temperature"]
    pairs = {"f": (f, g), "rho": (homogeneous.mass.values, space.density.values),
             "u": (expected["velocity"], space.velocity.values[steps]),
             "T": (temperature, space.temperature.values[steps]),
             "P": (expected["pressure_tensor"], space.pressure_tensor.values[steps]),
             "q": (expected["heat_flux"], space.heat_flux.values[steps])}
    scales = {"u": 1.0, "q": float((rho * temperature ** 1.5).max())}
    return {name: float(numpy.abs(b - a[:, None]).max()
                        / scales.get(name, numpy.abs(a).max()))
            for name, (a, b) in pairs.items()}


# -- 2. free transport: exact solutions and observed orders ----------------------------------

AMPLITUDE = 0.5           # periodic: f0 = (1 + A sin(2 pi x)) M(v) (sinusoidal_mode)
EVEN, ODD = 0.3, 0.3      # specular: f0 = M(v) (1 + a cos(pi x) + b sin(pi x) tanh(v_1))


def walls_function(x, v1, v2):
    """f0 of the specular test on [0, 1]: the image extension (x, v_1) -> (-x, -v_1) is the
    same smooth 2-periodic formula, so the exact solution is smooth."""
    return (numpy.exp(-(v1 * v1 + v2 * v2) / (2.0 * T0)) / (2.0 * math.pi * T0)
            * (1.0 + EVEN * numpy.cos(math.pi * x) + ODD * numpy.sin(math.pi * x)
               * numpy.tanh(v1)))


def _node(grid, column):
    """g(v_1) at any node value v_1 (-v_1 of a node is a node), from its values ``column``."""
    n, L, h = grid.n_modes, grid.half_width, grid.spacing
    return lambda v1: column[numpy.rint((numpy.asarray(v1) + L) / h).astype(int) % n]


def exact_transport(grid, ends, edges, t):
    """Exact cell averages (cells, *grid.shape) at time t of the free transport of the data
    of :func:`convergence`. The run projects f0 onto the Nyquist-free modes in v; the data
    are sums of terms A(x) phi(v), so the projected data are the sums of A(x) P phi(v), and
    each node v_j carries A at its speed c_j: A(x - c_j t) P phi(v_j) (periodic), or the
    image solution of A(x) P phi(v_1) (specular walls)."""
    c = transport_speeds(grid).reshape(-1)
    v1, v2 = grid.mesh()
    if ends == "periodic":
        shape = grid.project(grid.maxwellian(1.0, None, T0))
        wave = exact.free_transport_sine(edges, t, c, AMPLITUDE, 1, edges[-1])
        return wave[:, :, None] * shape[None]
    gauss = numpy.exp(-(v1 * v1 + v2 * v2) / (2.0 * T0)) / (2.0 * math.pi * T0)
    terms = [(lambda x: 1.0 + EVEN * numpy.cos(math.pi * x), grid.project(gauss)),
             (lambda x: ODD * numpy.sin(math.pi * x), grid.project(gauss * numpy.tanh(v1)))]
    points = grid.points()
    result = numpy.zeros((len(edges) - 1,) + grid.shape)
    for profile, shape in terms:
        for k in range(grid.n_modes):              # one v_2 column at a time
            value = _node(grid, shape[:, k])
            result[:, :, k] += exact.specular_images_cell_averages(
                lambda x, v, p=profile, g=value: p(x) * g(v), edges[-1], edges, t, points, c)
    return result


def convergence(reconstruction, ends, cells, final_time=0.2, courant=0.8):
    """L1 error of the free transport of the data (sum |f - exact| dx dv / sum |exact|
    dx dv) at ``final_time``, and the run's dt.

    dt is ``courant`` times the CFL limit on 20 cells, scaled by (20/cells) (upwind,
    MUSCL: fixed Courant number) or (20/cells)^{5/3} (WENO5: the third-order SSPRK3 time
    error then falls as dx^5)."""
    grid = VelocityGrid(**TRANSPORT_GRID)
    cfl = {"upwind": 1.0, "muscl": 0.5, "weno5": 0.5}[reconstruction]
    dt20 = courant * 2.0 * cfl * (1.0 / 20) / (grid.half_width - grid.spacing)
    power = 5.0 / 3.0 if reconstruction == "weno5" else 1.0
    dt = dividing_step(final_time, dt20 * (20.0 / cells) ** power)
    initial = ({"name": "sinusoidal_mode", "field": "density", "amplitude": AMPLITUDE,
                "temperature": T0}
               if ends == "periodic" else
               {"name": "space_function", "function": walls_function})
    ds = run_dataset(final_time=final_time, time_step=dt, grid=TRANSPORT_GRID, **COLLISIONS,
             initial=initial, output={"snapshot_interval": final_time},
             space={"cells": cells, "reconstruction": reconstruction, "left": ends,
                    "right": ends, "collisions": False})
    edges = numpy.linspace(0.0, 1.0, cells + 1)
    f0, f = ds.f.values[0], ds.f.values[-1]
    start = numpy.abs(f0 - exact_transport(grid, ends, edges, 0.0)).max()
    assert start < 1e-14 * numpy.abs(f0).max(), start
    reference = exact_transport(grid, ends, edges, float(ds.time.values[-1]))
    return numpy.abs(f - reference).sum() / numpy.abs(reference).sum(), dt


def orders(errors):
    """The observed orders log2(E_n / E_2n) between consecutive errors of a refinement by 2."""
    return [math.log2(a / b) for a, b in zip(errors[:-1], errors[1:])]


# -- 3. free-molecular heat transfer between two diffuse walls -------------------------------

#: walls at T1 (x = 0) and T2 (x = 1); initial gas at rest, uniform, at T_GAS
T1, T2, T_GAS = 0.5, 1.0, 0.75
WALLS_GRID = {"dimension": 2, "n_modes": 24, "support_radius": 3.0}


def free_molecular(final_time=30.0, cells=10, reconstruction="upwind", samples=11):
    """A collisionless gas between diffuse walls at T1 and T2 from a uniform Maxwellian at
    rest (T_GAS): the largest relative distance over the cells of rho, u_1 (absolute),
    T, P_11 and q_1 from the grid steady state (:func:`exact.free_molecular_walls_grid`
    of the run's mass and speed-0 nodes) at ``samples`` times, and the grid state's
    relative distance from the continuous one (:func:`exact.free_molecular_walls`)."""
    grid = VelocityGrid(**WALLS_GRID)
    cfl = {"upwind": 1.0, "muscl": 0.5, "weno5": 0.5}[reconstruction]
    dt = dividing_step(final_time, 0.9 * 2.0 * cfl / cells / (grid.half_width - grid.spacing))
    ds = run_dataset(final_time=final_time, time_step=dt, grid=WALLS_GRID, **COLLISIONS,
             initial={"name": "maxwellian", "temperature": T_GAS},
             output={"snapshot_interval": final_time},
             space={"cells": cells, "reconstruction": reconstruction,
                    "left": {"name": "diffuse", "temperature": T1},
                    "right": {"name": "diffuse", "temperature": T2}, "collisions": False})
    mass = float(ds.mass.values[0])                   # the interval has length 1
    steady = exact.free_molecular_walls_grid(grid, T1, T2, mass, rest=ds.f.values[0, 0])
    continuum = exact.free_molecular_walls(2, T1, T2, mass)
    fields = {"rho": ds.density.values, "u1": ds.velocity.values[..., 0],
              "T": ds.temperature.values, "P11": ds.pressure_tensor.values[..., 0, 0],
              "q1": ds.heat_flux.values[..., 0]}
    targets = {"rho": steady["rho"], "u1": steady["u"][0], "T": steady["T"],
               "P11": steady["P11"], "q1": steady["q1"]}
    times = ds.step_time.values
    rows = numpy.linspace(0, len(times) - 1, samples).round().astype(int)
    history = [(float(times[k]), {name: numpy.abs(fields[name][k] - targets[name]).max()
                                  / (1.0 if name == "u1" else abs(targets[name]))
                                  for name in fields}) for k in rows]
    final_f = numpy.abs(ds.f.values[-1] - steady["f"]).max() / steady["f"].max()
    quadrature = {name: (steady[key] - continuum[key]) / continuum[key]
                  for name, key in (("rho", "rho"), ("T", "T"), ("P11", "P11"), ("q1", "q1"))}
    return {"history": history, "f": final_f, "quadrature": quadrature, "dt": dt,
            "steady": steady, "continuum": continuum}


# -- 4. diffuse walls: mass to round-off, relaxation to the wall Maxwellian ------------------

T_WALL = 1.0
RELAXATION_GRID = {"dimension": 2, "n_modes": 16, "support_radius": 3.0}


def relaxation(knudsen=0.1, final_time=6.0, cells=10, grid_table=None, samples=11):
    """An elastic gas of Maxwell molecules (e = 1) between two diffuse walls at T_WALL,
    from a density wave (1 + 0.5 sin 2 pi x) at T = 0.8: the mass drift, the largest wall
    mass record, and the distance from the wall Maxwellian (max over the cells of
    |rho/rho_mean - 1|, |u|, |T/T_w - 1|) at ``samples`` times."""
    table = RELAXATION_GRID if grid_table is None else grid_table
    grid = VelocityGrid(**table)
    dt = dividing_step(final_time, 0.9 / cells / (grid.half_width - grid.spacing))
    ds = run_dataset(final_time=final_time, time_step=dt, grid=table, **COLLISIONS, knudsen=knudsen,
             initial={"name": "sinusoidal_mode", "field": "density", "amplitude": 0.5,
                      "temperature": 0.8},
             output={"snapshot_interval": final_time},
             space={"cells": cells, "left": {"name": "diffuse", "temperature": T_WALL},
                    "right": {"name": "diffuse", "temperature": T_WALL}})
    mass = ds.mass.values
    times = ds.step_time.values
    rows = numpy.linspace(0, len(times) - 1, samples).round().astype(int)
    rho = mass[0]                                     # the mean density (length 1)
    history = [(float(times[k]), {
        "rho": numpy.abs(ds.density.values[k] / rho - 1.0).max(),
        "u": numpy.abs(ds.velocity.values[k]).max(),
        "T": numpy.abs(ds.temperature.values[k] / T_WALL - 1.0).max()}) for k in rows]
    return {"steps": len(times) - 1, "dt": dt,
            "mass": numpy.abs(mass / mass[0] - 1.0).max(),
            "wall_mass": numpy.abs(ds.wall_mass.values).max() / mass[0],
            "wall_energy": float(ds.wall_energy.values.sum()), "history": history}
