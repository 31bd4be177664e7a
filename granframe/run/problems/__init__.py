"""The problems a run steps (:class:`granframe.abc.Problem`): space-homogeneous and in space.

:func:`make_problem` builds the one a description asks for; the runner, ``granframe
limits`` (:func:`time_step_limit`), ``granframe bench`` and resume use it through the
contract only.
"""

from __future__ import annotations

from granframe import validators as check
from granframe.run.description import RunDescription
from granframe.run.problems.homogeneous import HomogeneousProblem, moments
from granframe.run.problems.space import SpaceProblem

__all__ = ["HomogeneousProblem", "SpaceProblem", "make_problem", "moments", "time_step_limit"]


def make_problem(description, outline: bool = False):
    """The problem of ``description``: a :class:`SpaceProblem` when it has a ``space``
    section, else a :class:`HomogeneousProblem`. ``outline``: without the operator's
    precomputation (for :func:`time_step_limit`)."""
    if not isinstance(description, RunDescription):
        check.reject("make_problem", "description", description, "must be a RunDescription",
                     error=TypeError)
    if description.space is not None:
        return SpaceProblem(description, outline)
    return HomogeneousProblem(description, outline)


def time_step_limit(description):
    """The explicit step limit of a run, from its description alone (no operator built).

    The same :class:`~granframe.stepping.stability.StepLimit` that
    :class:`~granframe.run.runner.Simulation` checks
    (:func:`~granframe.stepping.stability.check_time_step`): the problem is built on an
    :class:`~granframe.stepping.stability.OperatorOutline`, so the radii of the heat bath,
    the collisions and the energy dissipation are computed by the same code from f0
    sampled and projected as the runner does; a rescaled run's drift radius takes its
    cooling rate a_0 from the energy dissipation D(f0) in closed form
    (:meth:`~granframe.equations.conservative.ConservativeCorrection.dissipation`) in place
    of one evaluation of Q. With ``conservative`` set, the runner's operator dissipates
    D(f) itself and the two limits agree to round-off; otherwise they differ by the
    operator's error in D: at 2D N = 48, S = 5 with the direct method by 7e-8 for Maxwell
    molecules (T0 = 1) and 5e-6 for hard spheres (two Gaussians of T = 0.6 at
    u = (+-1, 0)), at 2D N = 32 with fast_spectral on 16 x 8 points by 1e-5 (Maxwell,
    T0 = 8, S = 10). None when the equation has no part the scheme treats explicitly. A
    space run's limit is that of the collisions in its stiffest cell
    (:class:`~granframe.space.collisions.CellCollisions`); the transport's CFL limit is
    :meth:`~granframe.run.description.Space.transport_limit`. At 3D N = 32 it takes a few
    tenths of a second, where building the run's operator takes seconds
    (tests/test_frictions.py).

    Examples
    --------
    >>> import granframe
    >>> from granframe.run.description import RunDescription
    >>> d = RunDescription.from_toml(open("heated.toml").read())  # doctest: +SKIP
    >>> limit = granframe.time_step_limit(d)                                # doctest: +SKIP
    >>> limit.limit, limit.dominant, limit.rates                            # doctest: +SKIP
    """
    if not isinstance(description, RunDescription):
        check.reject("time_step_limit", "description", description,
                     "must be a RunDescription", error=TypeError)
    return make_problem(description, outline=True).step_limit()
