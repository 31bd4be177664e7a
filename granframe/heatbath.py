"""The heat-bath term tau Delta_v f of d_t f = Q(f,f)/eps + tau Delta_v f, spectrally."""

from __future__ import annotations

import math

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
        symbol = -self.tau * (math.pi / grid.half_width) ** 2 * grid.half_wavenumber_squared()
        symbol[grid.nyquist_mask()] = 0.0
        self.multiplier = backend.asarray(symbol)
        self._axes = tuple(range(grid.dimension))
        self._factors = {}

    def __call__(self, f):
        """tau Delta_v f on the grid."""
        spectrum = self.backend.rfftn(f, axes=self._axes) * self.multiplier
        return self.backend.irfftn(spectrum, s=self.grid.shape, axes=self._axes)

    def propagate(self, f, dt: float):
        """exp(dt tau Delta_v) f: each mode times exp(-dt tau (pi |k| / L)^2), exactly."""
        if dt == 0.0 or self.tau == 0.0:
            return f
        factor = self._factors.get(dt)
        if factor is None:
            if len(self._factors) > 8:  # a few step fractions per step size; adaptive steps vary
                self._factors.clear()
            factor = self._factors[dt] = self.backend.xp.exp(dt * self.multiplier)
        spectrum = self.backend.rfftn(f, axes=self._axes) * factor
        return self.backend.irfftn(spectrum, s=self.grid.shape, axes=self._axes)
