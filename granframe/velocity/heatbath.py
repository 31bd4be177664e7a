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
        symbol = grid.without_nyquist(
            -self.tau * (math.pi / grid.half_width) ** 2 * grid.half_wavenumber_squared())
        self.multiplier = backend.asarray(symbol)
        #: tau max |k|^2 (pi/L)^2 over the evolved modes: the stiffness an explicit scheme sees
        self.spectral_radius = float(-symbol.min()) if symbol.size else 0.0
        # One planned single-threaded transform pair: a threaded FFTW call between two operator
        # evaluations leaves OpenMP workers spinning, which slowed a whole RK4 step of the
        # heated 2D N = 64 problem from 15 to 24 ms.
        self._fft = backend.real_fft(grid.shape, tuple(range(grid.dimension)), threads=1)
        self._inverse_count = 1.0 / float(grid.n_modes) ** grid.dimension
        self._laplacian = self.multiplier * self._inverse_count
        self._factors = {}

    def _apply(self, f, multiplier):
        """IDFT(multiplier DFT(f)) with ``multiplier`` including the 1/N^d of the inverse;
        f of the grid's shape, or a batch (..., *grid.shape) (the cells of a space run)."""
        if f.shape != self.grid.shape:
            axes = tuple(range(-self.grid.dimension, 0))
            spectrum = self.backend.rfftn(f, axes=axes) * (multiplier / self._inverse_count)
            return self.backend.irfftn(spectrum, self.grid.shape, axes=axes)
        fft = self._fft
        fft.real[...] = f
        spectrum = fft.forward()
        fft.spectrum[...] = spectrum * multiplier
        return fft.inverse().copy()  # the result may be the plan's buffer

    def __call__(self, f):
        """tau Delta_v f on the grid."""
        return self._apply(f, self._laplacian)

    def propagate(self, f, dt: float):
        """exp(dt tau Delta_v) f: each mode times exp(-dt tau (pi |k| / L)^2), exactly."""
        if dt == 0.0 or self.tau == 0.0:
            return f
        factor = self._factors.get(dt)
        if factor is None:
            if len(self._factors) > 8:  # a few step fractions per step size; adaptive steps vary
                self._factors.clear()
            factor = self._factors[dt] = (self.backend.xp.exp(dt * self.multiplier)
                                          * self._inverse_count)
        return self._apply(f, factor)
