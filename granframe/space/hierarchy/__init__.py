r"""A hierarchy of collision models chosen cell by cell (docs/space.md, "The hierarchy").

In a space run every cell pays for the collision step. Where f is close to its local
Maxwellian a cheaper model gives the same answer: this module keeps the transport
kinetic in every cell (the same upwind fluxes of f everywhere, so mass, momentum and
energy cross the interfaces between levels exactly as between any two cells) and lets
the collision step of each cell be one of the registered
:class:`~granframe.abc.CollisionModel` levels, from the cheapest to the full operator,
following F. Filbet & T. Rey, SIAM J. Sci. Comput. 37 (2015) A1218-A1247
(arXiv:1402.6304) and G. Caparello, L. Pareschi & T. Rey (arXiv:2505.03360, 2025):

- ``euler``: f set to the discrete Maxwellian of its mass, momentum and cooled energy
  (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`): between two transport
  half steps this is the kinetic flux-vector scheme of the granular Euler equations;
- ``bgk``: the granular BGK model d_t f = nu_s (M[f] - f)/eps, stepped by the run's own
  time integrator and then cooled, with nu_s the rate at which the run's own operator
  relaxes a shear stress (:func:`relaxation_rate`), so that the level has the
  shear viscosity of the full operator in the first Sonine approximation;
- ``esbgk``: the ellipsoidal statistical BGK model, stepped and cooled as ``bgk``, with the
  operator's shear and heat-flux relaxation rates: its viscosity and its conductivity;
- ``boltzmann``: the run's integrator on the run's collision operator.

The fluid levels cool their equilibrium at the granular cooling rate of the run's kernel
and restitution law (:class:`CoolingRate`), the ``euler`` level also heats it at 2 tau per
unit time under a heat bath (the relaxation levels get the heat bath from the run's
integrator); mass and momentum are kept to round-off, the energy to the cooling the
formula gives. Where that formula has no closed form (a heat bath, a restitution law that
depends on the impact speed) it is integrated by substeps whose number follows the fastest
rate over the cells of the last record (:class:`StepRates`), numbers already on the host.

Which level a cell takes is decided every ``interval`` steps from two indicators per cell
(:class:`HybridCollisions`, :func:`choose_levels`):

- from fluid to kinetic, the Navier-Stokes realizability indicator of Levermore,
  Morokoff & Nadiga (Phys. Fluids 10 (1998) 3214), as Filbet & Rey use it: the stress and
  heat flux of the Navier-Stokes closure computed from the gradients of rho, u, T, relative
  to the pressure, kappa = max(|sigma|_F / p, |q| / (p sqrt T)). The Chapman-Enskog f is
  M (1 + phi) with phi of the size of these ratios at thermal speeds; it stops being
  a positive distribution (the closure loses its meaning) when they approach one.
- from kinetic to fluid, the distance of f from its local equilibrium in the relative
  L1 norm, delta = sum |f - M[f]| h^d / rho: dimensionless, at most 2, and a bound for
  the error of every bounded observable when f is replaced by M[f]; it measures the
  non-equilibrium in every moment at once, including those no indicator of rho, u, T sees
  (a Knudsen layer's velocity distribution at a wall).

A cell at level l rises to level k > l when an indicator exceeds the threshold of k; it
falls below k only when both are under ``hysteresis`` times that threshold, and every
cell lifts its neighbours to its level as far as ``buffer`` cells or ``free_paths`` mean
free paths eps sqrt(2T)/nu_s on each side, whichever is larger, so that a wave, or the
particles that fly ahead of it, never reach a cell still at a lower level, and cells do not
flicker. The fluid levels hold f at a Maxwellian or relax it to a Gaussian, so their
distance after the step says nothing of what they leave out: for an inelastic gas or
under a heat bath their cells take at least the distance delta_inf of the uniform state
the full level tends to (:func:`equilibrium_distance`).

The package is split by concern: :mod:`~granframe.space.hierarchy.rates` (the cooling
rate and the relaxation rates), :mod:`~granframe.space.hierarchy.relaxation` (the BGK and
ES-BGK equations and the discrete Gaussians), :mod:`~granframe.space.hierarchy.levels`
(the four levels), :mod:`~granframe.space.hierarchy.indicators` (kappa, delta, the reach
and delta_inf), :mod:`~granframe.space.hierarchy.choice` (the choice of the levels) and
:mod:`~granframe.space.hierarchy.hybrid` (the collision step and the context of the
levels' factories).
"""

from granframe.space.hierarchy.choice import choose_levels, spread_levels
from granframe.space.hierarchy.hybrid import HierarchyContext, HybridCollisions
from granframe.space.hierarchy.indicators import (CellGrid, CellIndicators,
                                                  equilibrium_distance, realizability)
from granframe.space.hierarchy.levels import (BoltzmannLevel, EllipsoidalLevel, EulerLevel,
                                              FluidParts, RelaxationLevel)
from granframe.space.hierarchy.rates import (CoolingRate, StepRates, relaxation_rate,
                                             scaled_rates)
from granframe.space.hierarchy.relaxation import (EllipsoidalEquation, RelaxationEquation,
                                                  discrete_gaussians)

__all__ = ["BoltzmannLevel", "CellGrid", "CellIndicators", "CoolingRate", "EllipsoidalEquation",
           "EllipsoidalLevel", "EulerLevel", "FluidParts", "HierarchyContext",
           "HybridCollisions", "RelaxationEquation", "RelaxationLevel", "StepRates",
           "choose_levels", "discrete_gaussians", "equilibrium_distance", "realizability",
           "relaxation_rate", "scaled_rates", "spread_levels"]
