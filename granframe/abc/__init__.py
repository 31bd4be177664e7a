"""The contracts of granframe: what every implementation of a family provides.

One class per family that plugins extend (docs/plugins.md): collision operators, restitution
laws, quadratures, array backends and their transforms, equations, time integrators and
initial conditions, and those of a run and of a space run (problems, communicators,
reconstructions, boundaries, collision models). Implementations live in the topic packages
(:mod:`granframe.model`, :mod:`granframe.velocity`, :mod:`granframe.stepping`,
:mod:`granframe.equations`, :mod:`granframe.space`, :mod:`granframe.run`) and in the
plugins; :mod:`granframe.testing` checks an implementation against its contract.

The package is split by contract family, each module importing only those above it in
this list: :mod:`~granframe.abc.model` (:class:`RestitutionLaw`, :class:`CollisionKernel`,
:class:`InitialCondition`), :mod:`~granframe.abc.velocity` (:class:`Quadrature`,
:class:`SurfaceQuadrature`, :class:`Grid`), :mod:`~granframe.abc.arrays`
(:data:`PRECISIONS`, :class:`ArrayBackend`, :class:`RealFFT`),
:mod:`~granframe.abc.operators` (:class:`CollisionOperator` and the checks of its
arguments), :mod:`~granframe.abc.stepping` (:class:`Part`, :class:`Equation`,
:class:`TimeIntegrator`, :class:`AdaptiveIntegrator`), :mod:`~granframe.abc.space`
(:class:`Reconstruction`, :class:`Boundary`, :class:`CollisionModel`) and
:mod:`~granframe.abc.run` (:class:`Problem`, :class:`Communicator`, :class:`Pending`,
:func:`deferred_checks`). The names below are those of the modules, gathered here: import
them from ``granframe.abc``, which each class and function names as its home
(``__module__``), so that messages (``must build a granframe.abc.CollisionKernel``) and
pickles name the contract where it is imported from.
"""

import types

from granframe.abc.arrays import PRECISIONS, ArrayBackend, RealFFT
from granframe.abc.model import CollisionKernel, InitialCondition, RestitutionLaw
from granframe.abc.operators import CollisionOperator, check_arguments, check_restitution
from granframe.abc.run import (Communicator, Pending, Problem, checked_energy_factors,
                                checks_deferred, deferred_checks)
from granframe.abc.space import (SIDE_NAMES, Boundary, CollisionModel, Reconstruction, Side,
                                  reflect_nodes)
from granframe.abc.stepping import AdaptiveIntegrator, Equation, Part, TimeIntegrator
from granframe.abc.velocity import Grid, Quadrature, SurfaceQuadrature

__all__ = ["PRECISIONS", "AdaptiveIntegrator", "ArrayBackend", "Boundary", "CollisionKernel",
           "CollisionModel", "CollisionOperator", "Communicator", "Equation", "Grid",
           "InitialCondition", "Part", "Pending", "Problem", "Quadrature", "RealFFT",
           "Reconstruction", "RestitutionLaw", "SIDE_NAMES", "Side", "SurfaceQuadrature",
           "TimeIntegrator", "check_arguments", "check_restitution", "checked_energy_factors", "checks_deferred",
           "deferred_checks", "reflect_nodes"]

for _name in __all__:
    if isinstance(globals()[_name], (type, types.FunctionType)):
        globals()[_name].__module__ = __name__
del _name
