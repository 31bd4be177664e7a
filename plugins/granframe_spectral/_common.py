"""Pieces shared by the direct and fast spectral operators.

Conventions (review, section 2): f_N(v) = sum_k fhat_k exp(i pi k.v / L) on
[-L, L]^d. Both operators work on the Nyquist-free modes |k_i| <= N/2 - 1 so
that every grid function they produce is real and the k = 0 mode never
receives aliased contributions (exact mass conservation).
"""

from __future__ import annotations

import math

import numpy
import scipy.special

from granframe import validators as check
from granframe.abc import checked_energy_factors, checks_deferred
from granframe.errors import NonFiniteError
from granframe.velocity.quadratures import GaussLegendre


def isotropic_sphere_average(x, dimension: int):
    """(1/|S^{d-1}|) int_{S^{d-1}} exp(i x.sigma) dsigma as a function of |x|.

    J_0(|x|) on the circle, sin|x| / |x| on the sphere.
    """
    if dimension == 2:
        return scipy.special.j0(x)
    return numpy.sinc(numpy.asarray(x) / math.pi)


def energy_factor(kernel, cell_volume: float, squared, f, backend):
    r"""E(f_b)^gamma for each distribution f_b of a stack ``f`` of shape (B, *grid.shape).

    .. math:: E(f_b) = \tfrac12 \Delta v \sum_j |v_j|^2 f_b(v_j)

    with Delta v the cell volume and ``squared`` the backend array |v_j|^2 (the grid's
    :meth:`~granframe.velocity.grid.VelocityGrid.speed_squared`, made once by the
    operator). Returns None when gamma = 0 (no moment taken, every factor 1), else a
    backend array of B factors computed on the backend
    (:func:`granframe.abc.checked_energy_factors`: no copy to the host within a run's step).
    """
    if kernel.energy_exponent == 0.0:
        return None
    axes = tuple(range(1, f.ndim))
    xp = backend.xp
    energy = 0.5 * xp.sum(squared * f, axis=axes) * cell_volume
    return checked_energy_factors(kernel, energy, backend)


def check_operands(owner: str, grid, f, backend):
    """Refuse an f that is not a finite real array of shape (..., *grid.shape) on this
    backend; return it as a stack of shape (B, *grid.shape) with the batch shape.

    A plain ``grid.shape`` f is the stack of one distribution, batch shape (). Finiteness
    costs one reduction, the sum of f (NaN or Inf anywhere makes it non-finite), and its
    copy to the host. On a backend whose arrays live on a device
    (:attr:`~granframe.abc.ArrayBackend.on_device`) that copy would stop the device at every
    call, several times per time step, so within a run's step
    (:func:`granframe.abc.deferred_checks`) it is not made there: a NaN or Inf in f spreads
    through the transforms to every point of Q, and the runner's health check of the
    step's record (one transfer per step) reports it.
    """
    xp = backend.xp
    if not isinstance(f, xp.ndarray):
        check.reject(owner, "f", type(f).__name__,
                     f"must be a {xp.__name__} array (backend '{backend.name}')", error=TypeError)
    shape, d = tuple(f.shape), grid.dimension
    if len(shape) < d or shape[len(shape) - d:] != grid.shape or 0 in shape:
        check.reject(owner, "f.shape", shape, f"must be the grid shape {grid.shape}, or batch "
                     f"axes then the grid shape, (..., {', '.join(map(str, grid.shape))}), "
                     "with no empty axis")
    if f.dtype.kind != "f":
        check.reject(owner, "f.dtype", str(f.dtype), "must be a real floating-point type",
                     error=TypeError)
    if not checks_deferred(backend) and not math.isfinite(float(xp.sum(f))):
        bad = int(xp.sum(~xp.isfinite(f)))
        check.reject(owner, "f", f"{bad} non-finite values" if bad else "values summing to "
                     "infinity", "must be finite everywhere on the grid (NaN or Inf in f, "
                     "e.g. from a blown-up step, would fill Q with NaN)",
                     error=NonFiniteError)
    batch_shape = shape[:len(shape) - d]
    return f.reshape((math.prod(batch_shape),) + grid.shape), batch_shape


def radial_rule(grid, n_radial: int):
    """Gauss-Legendre nodes rho_i and weights on [0, R]."""
    return GaussLegendre(n_radial).rule(grid.truncation_radius)
