"""The conformance check of collision models, the levels of a space run's hierarchy: one
step on four cells keeps each cell's mass and momentum, and its energy or the cooling
of a Maxwellian.
"""

from __future__ import annotations

import math

import numpy

from granframe import contract_checks
from granframe.testing.conformance.common import require
from granframe.testing.conformance.operators import default_arguments


def _model_cells(grid):
    """Four cells: two Maxwellians of different mass, velocity and temperature, and two
    positive non-equilibrium distributions (products of Gaussians of unequal temperatures
    along v_1 and the other axes, one of them shifted)."""
    mesh = [numpy.broadcast_to(m, grid.shape) for m in grid.mesh()]

    def gaussian(rho, shift, t1, t2):
        exponent = (mesh[0] - shift) ** 2 / (2 * t1) + sum(m * m for m in mesh[1:]) / (2 * t2)
        norm = (2 * math.pi) ** (grid.dimension / 2) * math.sqrt(t1 * t2 ** (grid.dimension - 1))
        return rho * numpy.exp(-exponent) / norm

    return numpy.stack([gaussian(1.0, 0.0, 1.0, 1.0), gaussian(0.3, 0.4, 0.7, 0.7),
                        gaussian(0.8, 0.0, 1.4, 0.7), gaussian(0.5, -0.3, 0.6, 1.1)])


def check_collision_model(factory, options) -> None:
    """A level of the hierarchy (:class:`~granframe.abc.CollisionModel`) on four cells of a 2D
    Maxwell-molecule gas (N = 24, the fast operator with the conservative correction, as a
    run with a hierarchy has it, penalised ARS(2,2,2), eps = 0.1, one
    step of 0.02): of f's shape and finite; every cell's mass and momentum (the grid's own,
    node -L at -L) kept to 1e-12; elastic, its energy kept to 1e-12; with e = 0.8, no cell
    gains energy and the Maxwellian cells lose what the cooling rate of a Maxwellian gives,
    rho d (T' - T) of :class:`~granframe.space.hierarchy.CoolingRate`, within 5%."""
    from granframe.equations.conservative import ConservativeCorrection
    from granframe.registry import default_registries
    from granframe.equations.homogeneous import HomogeneousBoltzmann
    from granframe.space.hierarchy import CoolingRate, HierarchyContext

    registries = default_registries()
    for restitution in (1.0, 0.8):
        grid, kernel, law, backend = default_arguments(
            2, 24, 6.0, law=("constant", {"value": restitution}))
        operator = ConservativeCorrection(registries.create(
            "collision_operators", "fast_spectral", grid=grid, kernel=kernel, restitution=law,
            backend=backend), "maxwellian")
        equation = HomogeneousBoltzmann(operator, 0.0, 0.1)
        integrator = registries.create("time_integrators", "penalised_ars222")
        model = factory(HierarchyContext(equation, integrator, 1.0), **options)
        name = f"{type(model).__name__} (e = {restitution:g})"
        require(isinstance(model, contract_checks.CONTRACTS["collision_models"]),
                f"{factory!r} built {model!r}, not a granframe.abc.CollisionModel")
        f = _model_cells(grid)
        out = numpy.asarray(backend.to_numpy(model.advance(backend.asarray(f.copy()), 0.0,
                                                           0.02)))
        require(out.shape == f.shape and numpy.all(numpy.isfinite(out)),
                f"{name}: advance must return finite values of shape {f.shape}")
        for before, after, cell in zip(f, out, range(len(f))):
            mass = grid.mass(before)
            require(abs(grid.mass(after) / mass - 1) <= 1e-12,
                    f"{name}: cell {cell} mass changed by "
                    f"{grid.mass(after) / mass - 1:.3g}")
            scale = mass * math.sqrt(grid.temperature(before))
            moved = numpy.abs(grid.momentum(after) - grid.momentum(before)).max() / scale
            require(moved <= 1e-12, f"{name}: cell {cell} momentum changed by {moved:.3g} "
                                    "of rho sqrt(T)")
            energy, later = grid.kinetic_energy(before), grid.kinetic_energy(after)
            if restitution == 1.0:
                require(abs(later / energy - 1) <= 1e-12,
                        f"{name}: elastic, cell {cell} energy changed by "
                        f"{later / energy - 1:.3g}")
            else:
                require(later <= energy * (1 + 1e-12),
                        f"{name}: cell {cell} gained energy ({later / energy - 1:.3g})")
        if restitution < 1.0:
            cooling = CoolingRate(kernel, law, grid)
            for cell in (0, 1):
                rho, t = grid.mass(f[cell]), grid.temperature(f[cell])
                energy0 = grid.kinetic_energy(f[cell])
                expected = 0.5 * grid.dimension * rho * (
                    cooling.cooled(rho, t, energy0, 0.02, 0.1, 0.0) - t)
                change = grid.kinetic_energy(out[cell]) - energy0
                require(abs(change / expected - 1) <= 0.05,
                        f"{name}: Maxwellian cell {cell} lost {-change:.4g} of energy, the "
                        f"cooling rate gives {-expected:.4g}")
