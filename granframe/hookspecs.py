"""Hook specifications of granframe's plugin system.

Each family of implementations has one hook. Every hook receives a
``registry`` (a :class:`granframe.registry.FamilyRegistry` bound to the
calling plugin) and returns nothing; the plugin calls
``registry.add(name, factory, description=...)`` once per implementation.
All implementations of a hook are called (there is no "first result wins"),
each exactly once per plugin manager, in pluggy's order (last registered
first). Plugins import the marker as ``from granframe import hookimpl``.
"""

import pluggy

PROJECT = "granframe"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def granframe_register_collision_kernels(registry):
    """Add collision kernels B(|g|, cos theta, E).

    A factory returns a :class:`granframe.abc.CollisionKernel` (e.g.
    :class:`granframe.model.kernels.VariableHardSpheres`).
    """


@hookspec
def granframe_register_restitution_laws(registry):
    """Add restitution laws e(|g|); factories return
    :class:`granframe.model.restitution.RestitutionLaw` instances."""


@hookspec
def granframe_register_quadratures(registry):
    """Add quadrature rules; factories return
    :class:`granframe.quadrature.Quadrature` instances (radial, circle or sphere)."""


@hookspec
def granframe_register_collision_operators(registry):
    """Add collision operators; a factory is called as
    ``factory(grid, kernel, restitution, backend, **options)`` and returns a
    :class:`granframe.abc.CollisionOperator`."""


@hookspec
def granframe_register_time_integrators(registry):
    """Add time integrators; factories return
    :class:`granframe.stepping.integrators.TimeIntegrator` instances."""


@hookspec
def granframe_register_initial_conditions(registry):
    """Add initial conditions; factories return
    :class:`granframe.model.initial.InitialCondition` instances."""


@hookspec
def granframe_register_array_backends(registry):
    """Add array backends; factories return
    :class:`granframe.abc.ArrayBackend` instances."""


@hookspec
def granframe_register_reconstructions(registry):
    """Add reconstructions of cell averages for the transport in x; factories return
    :class:`granframe.abc.Reconstruction` instances."""


@hookspec
def granframe_register_boundaries(registry):
    """Add boundaries of the space interval (walls, periodic links); factories return
    :class:`granframe.abc.Boundary` instances."""


@hookspec
def granframe_register_communicators(registry):
    """Add communicators of processes that run one space problem together; factories
    take no required parameter and return a :class:`granframe.abc.Communicator` of the
    processes this one was launched with (:func:`granframe.parallel.world` creates the one
    named ``mpi`` when a launcher started several)."""


@hookspec
def granframe_register_collision_models(registry):
    """Add levels of a space run's hierarchy of collision models; a factory is called as
    ``factory(context, **params)`` (:class:`granframe.space.hierarchy.HierarchyContext`)
    and returns a :class:`granframe.abc.CollisionModel`."""
