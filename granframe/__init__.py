"""granframe: Fourier spectral solvers for the inelastic Boltzmann equation.

The public API re-exports the core classes and builds registered
implementations by name::

    import granframe as gf
    grid = gf.VelocityGrid(dimension=2, n_modes=64, support_radius=10.0)
    law = gf.restitution_law("toscani", strength=1.0, exponent=0.5)

See docs/architecture.md for which module owns what.
"""

from granframe._version import __version__
from granframe.backends import ArrayBackend, NumpyBackend
from granframe.errors import AliasingWarning, PluginError, UnknownNameError
from granframe.grid import VelocityGrid
from granframe.hookspecs import hookimpl
from granframe.integrators import TimeIntegrator
from granframe.kernels import VariableHardSpheres
from granframe.operators import CollisionOperator
from granframe.quadratures import CircleTrapezoid, GaussLegendre, Lebedev, Quadrature, SphereProduct
from granframe.registry import FAMILIES, default_registries
from granframe.restitution import RestitutionLaw


def collision_kernel(name: str, **params):
    """Build the collision kernel registered as ``name``."""
    return default_registries().create("collision_kernels", name, **params)


def restitution_law(name: str, **params):
    """Build the restitution law registered as ``name``."""
    return default_registries().create("restitution_laws", name, **params)


def quadrature(name: str, **params):
    """Build the quadrature rule registered as ``name``."""
    return default_registries().create("quadratures", name, **params)


def array_backend(name: str = "numpy", **params):
    """Build the array backend registered as ``name``."""
    return default_registries().create("array_backends", name, **params)


def time_integrator(name: str, **params):
    """Build the time integrator registered as ``name``."""
    return default_registries().create("time_integrators", name, **params)


def initial_condition(name: str, **params):
    """Build the initial condition registered as ``name``."""
    return default_registries().create("initial_conditions", name, **params)


def collision_operator(name: str, grid, kernel, restitution, backend=None, **options):
    """Build the collision operator registered as ``name`` (precomputation happens here)."""
    return default_registries().create(
        "collision_operators", name, grid=grid, kernel=kernel, restitution=restitution,
        backend=array_backend() if backend is None else backend, **options)


__all__ = [
    "__version__", "ArrayBackend", "NumpyBackend", "AliasingWarning", "PluginError",
    "UnknownNameError", "VelocityGrid", "hookimpl", "TimeIntegrator", "VariableHardSpheres",
    "CollisionOperator", "Quadrature", "GaussLegendre", "CircleTrapezoid", "Lebedev",
    "SphereProduct", "FAMILIES", "default_registries", "RestitutionLaw", "collision_kernel",
    "restitution_law", "quadrature", "array_backend", "time_integrator", "initial_condition",
    "collision_operator",
]
