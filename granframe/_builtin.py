"""granframe's built-in implementations, registered through the public hooks.

This module is a plugin like any third-party one (see docs/plugins.md); the
plugin manager registers it under the name ``builtin``.
"""

import numpy

from granframe import backends, parallel
from granframe.model import initial, kernels, restitution
from granframe.space import boundaries, hierarchy, reconstruction
from granframe.space import initial as space_initial
from granframe.stepping import integrators
from granframe.velocity import quadratures
from granframe.hookspecs import hookimpl


def _forward_peaked(cos_theta):
    """b(cos theta) = 1 + cos(theta)/2: the anisotropic angular part of the kernels' examples."""
    return 1.0 + 0.5 * cos_theta


def _gaussian(*velocity):
    """exp(-|v|^2/2): the callable initial condition's example."""
    return numpy.exp(-0.5 * sum(v * v for v in velocity))


def _space_gaussian(x, *velocity):
    """(1 + sin(2 pi x)/2) exp(-|v|^2/2): the space function initial condition's example."""
    return (1.0 + 0.5 * numpy.sin(2.0 * numpy.pi * x)) * _gaussian(*velocity)


@hookimpl
def granframe_register_collision_kernels(registry):
    registry.add("vhs", kernels.VariableHardSpheres,
                 description="variable hard spheres B = C |g|^lambda b(cos theta) E^gamma",
                 examples=[{}, {"exponent": 0.5, "angular": _forward_peaked,
                                "energy_exponent": 0.5, "constant": 0.2}])
    registry.add("maxwell", kernels.maxwell_molecules,
                 examples=[{}, {"angular": _forward_peaked}])
    registry.add("hard_spheres", kernels.hard_spheres)


@hookimpl
def granframe_register_restitution_laws(registry):
    registry.add("constant", restitution.Constant,
                 examples=[{"value": 0.0}, {"value": 0.5}, {"value": 1.0}])
    registry.add("toscani", restitution.Toscani,
                 examples=[{"strength": 0.5, "exponent": 0.5}, {"strength": 0.0, "exponent": -1.0}])
    registry.add("viscoelastic", restitution.Viscoelastic, examples=[{"strength": 0.2}])
    registry.add("tanh", restitution.Tanh,
                 description="e(r) = (e0-1)/2 tanh((r-centre)/width) + (e0+1)/2 (review, Test 3)",
                 examples=[{"asymptotic_value": 0.2, "centre": 1.5, "width": 0.5}])
    registry.add("threshold", restitution.Threshold,
                 examples=[{"threshold": 1.0, "value": 0.5}])


@hookimpl
def granframe_register_quadratures(registry):
    registry.add("gauss_legendre", quadratures.GaussLegendre,
                 examples=[{"n_points": 1}, {"n_points": 12}])
    registry.add("circle_trapezoid", quadratures.CircleTrapezoid,
                 description="equispaced rule on the circle S^1, exact for degree M - 1",
                 examples=[{"n_points": 16}, {"n_points": 7, "phase": 0.3}])
    registry.add("lebedev", quadratures.Lebedev,
                 description="Lebedev-Laikov rule on S^2 (scipy.integrate.lebedev_rule)",
                 examples=[{"order": 7}, {"order": 11}])
    registry.add("sphere_product", quadratures.SphereProduct,
                 description="Gauss-Legendre x equispaced product rule on S^2, exact for degree 2n - 1",
                 examples=[{"n_polar": 4}])


@hookimpl
def granframe_register_array_backends(registry):
    registry.add("numpy", backends.NumpyBackend,
                 description="NumPy arrays, SciPy pocketfft transforms (multithreaded)")


@hookimpl
def granframe_register_time_integrators(registry):
    registry.add("forward_euler", integrators.ForwardEuler)
    registry.add("ssp_rk2", integrators.SSPRK2)
    registry.add("ssp_rk3", integrators.SSPRK3)
    registry.add("rk4", integrators.RK4)
    registry.add("if_rk4", integrators.IntegratingFactorRK4,
                 description="integrating-factor (Lawson) RK4: the heat bath tau Delta exactly")
    registry.add("dopri54", integrators.DormandPrince54,
                 description="adaptive Dormand-Prince 5(4) embedded pair with error control")
    registry.add("penalised_euler", integrators.PenalisedEuler,
                 description="Filbet-Jin BGK-penalised IMEX Euler, order 1: stable as eps -> 0")
    registry.add("penalised_ars222", integrators.PenalisedARS222,
                 description="BGK-penalised IMEX ARS(2,2,2) with Strang heat bath, order 2: "
                             "stable as eps -> 0")


@hookimpl
def granframe_register_initial_conditions(registry):
    registry.add("maxwellian", initial.Maxwellian)
    registry.add("box", initial.Box,
                 description="flat profile on a cube, cell-averaged (the review's flat data)",
                 examples=[{"half_width": 1.5}, {"half_width": 0.8}])
    registry.add("bkw", initial.BKWProfile, examples=[{"time": 6.0}])
    registry.add("gaussian_mixture", initial.GaussianMixture,
                 examples=[{"components": [{"density": 0.5, "temperature": 0.5},
                                           {"density": 0.5, "temperature": 1.5}]}])
    registry.add("callable", initial.FromCallable,
                 examples=[{"function": _gaussian, "mass": None}])
    registry.add("riemann", space_initial.RiemannProblem,
                 description="Maxwellians of (rho, u, T) left and right of x = interface ell "
                             "(space runs)",
                 examples=[{"left": {"density": 1.0, "temperature": 1.0},
                            "right": {"density": 0.125, "temperature": 0.8}}])
    registry.add("sinusoidal_mode", space_initial.SinusoidalMode,
                 description="uniform Maxwellian with rho, u_1 or T times 1 + A sin(2 pi k x/ell) "
                             "(space runs)",
                 examples=[{"field": "density", "amplitude": 0.2},
                           {"field": "temperature", "amplitude": 0.3, "mode": 2},
                           {"field": "velocity", "amplitude": 0.2, "component": 2}])
    registry.add("quadrants", space_initial.QuadrantProblem,
                 description="four Maxwellian quadrants about (a Lx, b Ly): the 2D Riemann "
                             "problem (rectangles)",
                 examples=[{"upper_right": {"density": 1.0, "temperature": 1.0},
                            "upper_left": {"density": 0.5, "velocity": [-0.5, 0.0],
                                           "temperature": 0.8},
                            "lower_left": {"density": 1.0, "velocity": [-0.5, -0.5],
                                           "temperature": 1.0},
                            "lower_right": {"density": 0.5, "velocity": [0.0, -0.5],
                                            "temperature": 0.8}}])
    registry.add("space_function", space_initial.SpaceFunction,
                 description="f0(x, v) (on a rectangle f0(x, y, v)) from a function, "
                             "cell-averaged (space runs)",
                 examples=[{"function": _space_gaussian}])


@hookimpl
def granframe_register_reconstructions(registry):
    registry.add("upwind", reconstruction.Upwind, description="first order: the cell averages")
    registry.add("muscl", reconstruction.MUSCL,
                 description="second order, piecewise linear with a limited slope (TVD)",
                 examples=[{}, {"limiter": "minmod"}])
    registry.add("weno5", reconstruction.WENO5,
                 description="fifth order WENO (Jiang-Shu) for smooth problems")


@hookimpl
def granframe_register_boundaries(registry):
    registry.add("periodic", boundaries.Periodic)
    registry.add("specular", boundaries.Specular, description="specular reflection v_1 -> -v_1")
    registry.add("diffuse", boundaries.Diffuse,
                 description="diffuse (Maxwell) wall: temperature, tangential velocity, "
                             "accommodation",
                 examples=[{}, {"temperature": 2.0, "velocity": 0.5, "accommodation": 0.7}])
    registry.add("vibrating", boundaries.Vibrating,
                 description="wall vibrating along x in the small-amplitude limit (A -> 0 at "
                             "fixed A omega): speed A omega, temperature, reflection "
                             "(diffuse or specular)",
                 examples=[{"speed": 0.5}, {"speed": 0.3, "temperature": 0.5},
                           {"speed": 0.5, "reflection": "specular"}])
    registry.add("reservoir", boundaries.Reservoir,
                 description="open end: what arrives leaves, a reservoir's Maxwellian "
                             "(density, velocity along the axis, temperature) enters",
                 examples=[{}, {"density": 1.7, "velocity": -0.8, "temperature": 1.5}])


@hookimpl
def granframe_register_communicators(registry):
    registry.add("serial", parallel.SerialCommunicator,
                 description="one process: the collectives return its own values")


@hookimpl
def granframe_register_collision_models(registry):
    registry.add("euler", hierarchy.EulerLevel,
                 description="granular Euler: f set to its cooled local discrete Maxwellian")
    registry.add("bgk", hierarchy.RelaxationLevel,
                 description="granular BGK relaxation at the operator's shear relaxation "
                             "rate, exact in time, with the granular cooling")
    registry.add("esbgk", hierarchy.EllipsoidalLevel,
                 description="granular ES-BGK relaxation with the operator's shear and heat "
                             "relaxation rates (its viscosity and conductivity)")
    registry.add("boltzmann", hierarchy.BoltzmannLevel,
                 description="the run's collision operator and time integrator (full)")
