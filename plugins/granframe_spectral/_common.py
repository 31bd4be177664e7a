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
from granframe.errors import NonFiniteError
from granframe.velocity.quadratures import GaussLegendre


def isotropic_sphere_average(x, dimension: int):
    """(1/|S^{d-1}|) int_{S^{d-1}} exp(i x.sigma) dsigma as a function of |x|.

    J_0(|x|) on the circle, sin|x| / |x| on the sphere.
    """
    if dimension == 2:
        return scipy.special.j0(x)
    return numpy.sinc(numpy.asarray(x) / math.pi)


def energy_factor(kernel, grid, f, xp) -> float:
    """E(f)^gamma with E = int |v|^2/2 f dv; 1 when gamma = 0 (no moment taken)."""
    if kernel.energy_exponent == 0.0:
        return 1.0
    return kernel.energy_factor(grid.kinetic_energy(f, xp))


def check_operands(owner: str, grid, f, backend):
    """Refuse an f that is not a finite real array of the grid's shape on this backend.

    Finiteness costs one reduction, the sum of f (NaN or Inf anywhere makes it
    non-finite), in the backend's namespace, so that every backend refuses alike; a NaN
    or Inf in f would otherwise spread through the transforms to every point of Q.
    """
    xp = backend.xp
    if not isinstance(f, xp.ndarray):
        check.reject(owner, "f", type(f).__name__,
                     f"must be a {xp.__name__} array (backend '{backend.name}')", error=TypeError)
    shape = tuple(f.shape)
    if shape != grid.shape:
        check.reject(owner, "f.shape", shape, f"must equal the grid shape {grid.shape}")
    if f.dtype.kind != "f":
        check.reject(owner, "f.dtype", str(f.dtype), "must be a real floating-point type",
                     error=TypeError)
    if not math.isfinite(float(xp.sum(f))):
        bad = int(xp.sum(~xp.isfinite(f)))
        check.reject(owner, "f", f"{bad} non-finite values" if bad else "values summing to "
                     "infinity", "must be finite everywhere on the grid (NaN or Inf in f, "
                     "e.g. from a blown-up step, would fill Q with NaN)",
                     error=NonFiniteError)


def radial_rule(grid, n_radial: int):
    """Gauss-Legendre nodes rho_i and weights on [0, R]."""
    return GaussLegendre(n_radial).rule(grid.truncation_radius)
