"""Conformance kit: the checks every implementation of a family must pass.

Each family has check functions, which raise :class:`AssertionError` with a message
saying what is wrong, and a pytest test class running them, which a plugin author
subclasses (the way ``zarr.testing.StoreTests`` is subclassed by a store)::

    from granframe.testing.conformance import RestitutionLawTests

    class TestExponentialDecay(RestitutionLawTests):
        factory = ExponentialDecay
        examples = [{"minimum": 0.4}, {"minimum": 0.0, "scale": 3.0}]

``factory`` builds the implementation from each parameter dict of ``examples`` (for
collision operators the dicts are the options after grid, kernel, restitution and
backend). The grids are small (2D N = 16, 3D N = 8; N = 32 in 2D where an exact rate is
compared), so that a family's suite runs in seconds. The kit needs pytest and Hypothesis
(the ``test`` extra).

The checks live in one module per contract family (:mod:`.components`: restitution laws,
collision kernels, quadratures and initial conditions; :mod:`.integrators`,
:mod:`.operators`, :mod:`.backends`, :mod:`.reconstructions`, :mod:`.boundaries`,
:mod:`.collision_models`, :mod:`.communicators`), the test classes in :mod:`.suites`; this
package gives them all under one name.
"""

from __future__ import annotations

from granframe.testing.conformance.backends import (check_backend_elementwise,
                                                    check_backend_parity,
                                                    check_backend_transforms)
# _wall_flux and _wall_times: tests/test_conformance.py and tests/test_space_walls.py
# check the kit's own wall helpers through this package
from granframe.testing.conformance.boundaries import (WALL_GRIDS, WALL_PHASES, WALL_SIDES,
                                                      WALL_TIMES, _wall_flux, _wall_times,
                                                      check_boundary, check_boundary_basics,
                                                      check_wall_linearity, check_wall_mass_flux,
                                                      check_wall_period, check_wall_positivity)
from granframe.testing.conformance.collision_models import check_collision_model
from granframe.testing.conformance.communicators import check_communicator
from granframe.testing.conformance.components import (check_collision_kernel,
                                                      check_initial_condition, check_quadrature,
                                                      check_restitution_law)
from granframe.testing.conformance.integrators import LinearTestEquation, check_integrator_order
from granframe.testing.conformance.operators import (OPERATOR_CASES, SMALL_GRIDS, check_mass_of,
                                                     check_operator_against_direct,
                                                     check_operator_batching,
                                                     check_operator_energy_dissipation,
                                                     check_operator_mass,
                                                     check_operator_mass_on_generated,
                                                     check_operator_refuses_bad_restitution)
from granframe.testing.conformance.reconstructions import (ORDER_CELLS, check_reconstruction,
                                                           check_reconstruction_basics,
                                                           check_reconstruction_extremes,
                                                           check_reconstruction_order,
                                                           check_reconstruction_symmetries)
from granframe.testing.conformance.suites import (ArrayBackendTests, BoundaryTests,
                                                  CollisionKernelTests, CollisionOperatorTests,
                                                  InitialConditionTests, QuadratureTests,
                                                  ReconstructionTests, RestitutionLawTests,
                                                  TimeIntegratorTests)

__all__ = [
    "ArrayBackendTests", "BoundaryTests", "CollisionKernelTests", "CollisionOperatorTests",
    "InitialConditionTests", "LinearTestEquation", "OPERATOR_CASES", "ORDER_CELLS",
    "QuadratureTests", "ReconstructionTests", "RestitutionLawTests", "SMALL_GRIDS",
    "TimeIntegratorTests", "WALL_GRIDS", "WALL_PHASES", "WALL_SIDES", "WALL_TIMES",
    "check_backend_elementwise", "check_backend_parity", "check_backend_transforms",
    "check_boundary", "check_boundary_basics", "check_collision_kernel",
    "check_collision_model", "check_communicator", "check_initial_condition",
    "check_integrator_order", "check_mass_of", "check_operator_against_direct",
    "check_operator_batching", "check_operator_energy_dissipation", "check_operator_mass",
    "check_operator_mass_on_generated", "check_operator_refuses_bad_restitution",
    "check_quadrature", "check_reconstruction", "check_reconstruction_basics",
    "check_reconstruction_extremes", "check_reconstruction_order",
    "check_reconstruction_symmetries", "check_restitution_law", "check_wall_linearity",
    "check_wall_mass_flux", "check_wall_period", "check_wall_positivity",
]
