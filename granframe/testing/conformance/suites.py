"""The pytest test classes of the conformance kit, one per family, which a plugin author
subclasses with a ``factory`` and its ``examples``; each runs the family's checks.
"""

from __future__ import annotations

from granframe.testing.conformance.backends import (check_backend_elementwise,
                                                    check_backend_parity,
                                                    check_backend_transforms)
from granframe.testing.conformance.boundaries import (check_boundary_basics, check_wall_linearity,
                                                      check_wall_mass_flux, check_wall_period,
                                                      check_wall_positivity)
from granframe.testing.conformance.components import (check_collision_kernel,
                                                      check_initial_condition, check_quadrature,
                                                      check_restitution_law)
from granframe.testing.conformance.integrators import check_integrator_order
from granframe.testing.conformance.operators import (check_operator_against_direct,
                                                     check_operator_batching,
                                                     check_operator_energy_dissipation,
                                                     check_operator_mass,
                                                     check_operator_mass_on_generated,
                                                     check_operator_refuses_bad_restitution)
from granframe.testing.conformance.reconstructions import (check_reconstruction_basics,
                                                           check_reconstruction_extremes,
                                                           check_reconstruction_order,
                                                           check_reconstruction_symmetries)


class _FamilyTests:
    """Base of the test classes: ``factory`` and ``examples`` (a list of parameter dicts)."""

    factory = None
    examples: tuple = ({},)

    def _factory(self):
        factory = self.factory
        factory = getattr(factory, "__func__", factory)    # a function set as an attribute
        if factory is None:
            raise AssertionError(f"{type(self).__name__} must set 'factory'")
        return factory

    def implementations(self):
        """The implementation built from each example."""
        return [self._factory()(**params) for params in self.examples]


class RestitutionLawTests(_FamilyTests):
    """Conformance tests of a restitution law (:func:`check_restitution_law`)."""

    def test_restitution_law(self):
        for law in self.implementations():
            check_restitution_law(law)


class CollisionKernelTests(_FamilyTests):
    """Conformance tests of a collision kernel (:func:`check_collision_kernel`)."""

    def test_collision_kernel(self):
        for kernel in self.implementations():
            check_collision_kernel(kernel)


class QuadratureTests(_FamilyTests):
    """Conformance tests of a quadrature rule (:func:`check_quadrature`)."""

    def test_quadrature(self):
        for rule in self.implementations():
            check_quadrature(rule)


class InitialConditionTests(_FamilyTests):
    """Conformance tests of an initial condition (:func:`check_initial_condition`)."""

    def test_initial_condition(self):
        for condition in self.implementations():
            check_initial_condition(condition)


class TimeIntegratorTests(_FamilyTests):
    """Conformance tests of a time integrator (:func:`check_integrator_order`)."""

    def test_order(self):
        for integrator in self.implementations():
            check_integrator_order(integrator)


class CollisionOperatorTests(_FamilyTests):
    """Conformance tests of a collision operator; ``examples`` hold its options."""

    def test_mass(self):
        for options in self.examples:
            check_operator_mass(self._factory(), options)

    def test_mass_of_generated_distributions(self):
        for options in self.examples:
            check_operator_mass_on_generated(self._factory(), options)

    def test_energy_dissipation(self):
        for options in self.examples:
            check_operator_energy_dissipation(self._factory(), options)

    def test_against_direct(self):
        for options in self.examples:
            check_operator_against_direct(self._factory(), options)

    def test_batching(self):
        for options in self.examples:
            check_operator_batching(self._factory(), options)

    def test_refuses_bad_restitution(self):
        for options in self.examples:
            check_operator_refuses_bad_restitution(self._factory(), options)


class ArrayBackendTests(_FamilyTests):
    """Conformance tests of an array backend; ``operators`` lists the operator factories
    whose results must match the NumPy backend's (by default the registered ones)."""

    operators = None

    def _operators(self):
        from granframe.registry import default_registries

        if self.operators is not None:
            return list(self.operators)
        return [e.factory for e in default_registries().entries("collision_operators")]

    def test_transforms(self):
        for backend in self.implementations():
            check_backend_transforms(backend)

    def test_elementwise(self):
        for backend in self.implementations():
            check_backend_elementwise(backend)

    def test_operator_parity(self):
        for backend in self.implementations():
            for factory in self._operators():
                check_backend_parity(backend, factory)


class ReconstructionTests(_FamilyTests):
    """Conformance tests of a reconstruction (:func:`check_reconstruction` in parts)."""

    def test_basics(self):
        for reconstruction in self.implementations():
            check_reconstruction_basics(reconstruction)

    def test_order(self):
        for reconstruction in self.implementations():
            check_reconstruction_order(reconstruction)

    def test_symmetries(self):
        for reconstruction in self.implementations():
            check_reconstruction_symmetries(reconstruction)

    def test_extremes(self):
        for reconstruction in self.implementations():
            check_reconstruction_extremes(reconstruction)


class BoundaryTests(_FamilyTests):
    """Conformance tests of a boundary (:func:`check_boundary` in parts); a wall whose
    emission is not linear in what arrives sets ``linear = False``."""

    linear = True

    def test_basics(self):
        for boundary in self.implementations():
            check_boundary_basics(boundary)

    def test_mass_flux(self):
        for boundary in self.implementations():
            if not (type(boundary).periodic or getattr(type(boundary), "open", False)):
                check_wall_mass_flux(boundary)

    def test_positivity(self):
        for boundary in self.implementations():
            if not type(boundary).periodic:
                check_wall_positivity(boundary)

    def test_period(self):
        for boundary in self.implementations():
            if not type(boundary).periodic:
                check_wall_period(boundary)

    def test_linearity(self):
        for boundary in self.implementations():
            if self.linear and not (type(boundary).periodic
                                    or getattr(type(boundary), "open", False)):
                check_wall_linearity(boundary)
