"""The heat-bath term tau Delta_v f of d_t f = Q(f,f)/eps + tau Delta_v f, spectrally."""

from __future__ import annotations

import math

import numpy

from granframe import validators as check


class HeatBath:
    """tau Delta_v f by the Fourier multiplier -tau (pi |k| / L)^2.

    Parameters
    ----------
    grid : VelocityGrid
    tau : float
        Heat-bath strength tau >= 0 (review, eq. (homo_heat)).
    backend : ArrayBackend

    Notes
    -----
    On f_N = sum_k fhat_k exp(i pi k.v/L), Delta_v f_N = -sum_k (pi|k|/L)^2 fhat_k
    exp(i pi k.v/L); the Nyquist modes, which are not real-representable, are dropped.
    ``multiplier`` exposes the symbol for exponential integrators.
    """

    def __init__(self, grid, tau: float, backend):
        if not check.is_real(tau) or not (0.0 <= float(tau) < math.inf):
            check.reject("HeatBath", "tau", tau, "must be a finite real number >= 0")
        self.grid, self.tau, self.backend = grid, float(tau), backend
        d, n = grid.dimension, grid.n_modes
        k_axes = [numpy.fft.fftfreq(n, 1.0 / n)] * (d - 1) + [numpy.arange(n // 2 + 1.0)]
        k2 = sum(numpy.reshape(k, [-1 if i == j else 1 for j in range(d)]) ** 2
                 for i, k in enumerate(k_axes))
        symbol = -self.tau * (math.pi / grid.half_width) ** 2 * k2
        for axis in range(d):
            index = [slice(None)] * d
            index[axis] = n // 2
            symbol[tuple(index)] = 0.0
        self.multiplier = backend.asarray(symbol)
        self._axes = tuple(range(d))

    def __call__(self, f):
        """tau Delta_v f on the grid."""
        spectrum = self.backend.rfftn(f, axes=self._axes) * self.multiplier
        return self.backend.irfftn(spectrum, s=self.grid.shape, axes=self._axes)
