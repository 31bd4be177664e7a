"""granframe: Fourier spectral solvers for the inelastic Boltzmann equation.

The public API re-exports the core classes and builds registered
implementations by name::

    import granframe as gf
    grid = gf.VelocityGrid(dimension=2, n_modes=64, support_radius=10.0)
    law = gf.restitution_law("toscani", strength=1.0, exponent=0.5)

See docs/architecture.md for which module owns what.
"""

import importlib

from granframe._version import __version__

#: public name -> the module that defines it; imported on first use (PEP 562), so that
#: ``granframe`` and its command line start fast and a Ctrl-C during start-up meets the
#: command line's handler rather than an import
_EXPORTS = {
    "ArrayBackend": "granframe.backends", "NumpyBackend": "granframe.backends",
    "AliasingWarning": "granframe.errors", "PluginError": "granframe.errors",
    "UnknownNameError": "granframe.errors", "VelocityGrid": "granframe.velocity.grid",
    "hookimpl": "granframe.hookspecs", "TimeIntegrator": "granframe.stepping.integrators",
    "VariableHardSpheres": "granframe.model.kernels", "CollisionOperator": "granframe.abc",
    "CircleTrapezoid": "granframe.velocity.quadratures", "GaussLegendre": "granframe.velocity.quadratures",
    "Lebedev": "granframe.velocity.quadratures", "Quadrature": "granframe.velocity.quadratures",
    "SphereProduct": "granframe.velocity.quadratures", "FAMILIES": "granframe.registry",
    "default_registries": "granframe.registry", "RestitutionLaw": "granframe.model.restitution",
    "CollisionKernel": "granframe.abc",
    "open_run": "granframe.run.dataset",
    "open_sweep": "granframe.run.sweep",
    "ConservativeCorrection": "granframe.equations.conservative",
    "run_in_memory": "granframe.run.runner", "Simulation": "granframe.run.runner",
    "time_step_limit": "granframe.run.problems",
    "Problem": "granframe.abc", "make_problem": "granframe.run.problems",
}


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'granframe' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))


def _registries():
    from granframe.registry import default_registries

    return default_registries()


def collision_kernel(name: str, **params):
    """Build the collision kernel registered as ``name``."""
    return _registries().create("collision_kernels", name, **params)


def restitution_law(name: str, **params):
    """Build the restitution law registered as ``name``."""
    return _registries().create("restitution_laws", name, **params)


def quadrature(name: str, **params):
    """Build the quadrature rule registered as ``name``."""
    return _registries().create("quadratures", name, **params)


def array_backend(name: str = "numpy", **params):
    """Build the array backend registered as ``name``."""
    return _registries().create("array_backends", name, **params)


def time_integrator(name: str, **params):
    """Build the time integrator registered as ``name``."""
    return _registries().create("time_integrators", name, **params)


def initial_condition(name: str, **params):
    """Build the initial condition registered as ``name``."""
    return _registries().create("initial_conditions", name, **params)


def collision_operator(name: str, grid, kernel, restitution, backend=None, **options):
    """Build the collision operator registered as ``name`` (precomputation happens here)."""
    return _registries().create(
        "collision_operators", name, grid=grid, kernel=kernel, restitution=restitution,
        backend=array_backend() if backend is None else backend, **options)


__all__ = [
    "__version__", "ArrayBackend", "NumpyBackend", "AliasingWarning", "PluginError",
    "UnknownNameError", "VelocityGrid", "hookimpl", "TimeIntegrator", "VariableHardSpheres",
    "CollisionOperator", "Quadrature", "GaussLegendre", "CircleTrapezoid", "Lebedev",
    "SphereProduct", "FAMILIES", "default_registries", "RestitutionLaw", "collision_kernel",
    "restitution_law", "quadrature", "array_backend", "time_integrator", "initial_condition",
    "collision_operator", "CollisionKernel",
    "open_run",
    "open_sweep",
    "ConservativeCorrection",
    "run_in_memory",
    "Simulation",
    "time_step_limit", "Problem", "make_problem",
]
