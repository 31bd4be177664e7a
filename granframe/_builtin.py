"""granframe's built-in implementations, registered through the public hooks.

This module is a plugin like any third-party one (see docs/plugins.md); the
plugin manager registers it under the name ``builtin``.
"""

from granframe import backends
from granframe.model import initial, kernels, restitution
from granframe.stepping import integrators
from granframe.velocity import quadratures
from granframe.hookspecs import hookimpl


@hookimpl
def granframe_register_collision_kernels(registry):
    registry.add("vhs", kernels.VariableHardSpheres,
                 description="variable hard spheres B = C |g|^lambda b(cos theta) E^gamma")
    registry.add("maxwell", kernels.maxwell_molecules)
    registry.add("hard_spheres", kernels.hard_spheres)


@hookimpl
def granframe_register_restitution_laws(registry):
    registry.add("constant", restitution.Constant)
    registry.add("toscani", restitution.Toscani)
    registry.add("viscoelastic", restitution.Viscoelastic)
    registry.add("tanh", restitution.Tanh,
                 description="e(r) = (e0-1)/2 tanh((r-centre)/width) + (e0+1)/2 (review, Test 3)")
    registry.add("threshold", restitution.Threshold)


@hookimpl
def granframe_register_quadratures(registry):
    registry.add("gauss_legendre", quadratures.GaussLegendre)
    registry.add("circle_trapezoid", quadratures.CircleTrapezoid,
                 description="equispaced rule on the circle S^1, exact for degree M - 1")
    registry.add("lebedev", quadratures.Lebedev,
                 description="Lebedev-Laikov rule on S^2 (scipy.integrate.lebedev_rule)")
    registry.add("sphere_product", quadratures.SphereProduct,
                 description="Gauss-Legendre x equispaced product rule on S^2, exact for degree 2n - 1")


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
                 description="flat profile on a cube, cell-averaged (the review's flat data)")
    registry.add("bkw", initial.BKWProfile)
    registry.add("gaussian_mixture", initial.GaussianMixture)
    registry.add("callable", initial.FromCallable)
