r"""A conservative correction of any collision operator: exact mass, momentum and energy
dissipation on the grid.

The spectral operators conserve mass to round-off (their k = 0 mode is exact) but
momentum and energy only to the accuracy of their quadratures and truncation. Where a
scheme multiplies Q by a large factor (the penalised schemes take steps dt >> eps, so
each step adds (dt/eps) h^d sum |v|^2 Q), that defect becomes an error of the
temperature. :class:`ConservativeCorrection` wraps an operator and projects its Q onto
the discrete constraints

.. math:: h^d\sum_j Q^c_j = 0,\qquad h^d\sum_j Q^c_j v_j = 0,\qquad
          h^d\sum_j Q^c_j |v_j|^2 = D(f),

with D(f) the energy dissipation of the continuous operator (relative speeds cut at R,
as the operators do) for the grid function f: exactly on the grid for Maxwell molecules with
constant e, to spectral accuracy otherwise (:meth:`ConservativeCorrection.dissipation`);
D = 0 for elastic collisions.

References: I. M. Gamba, S. H. Tharkabhushanam, "Spectral-Lagrangian methods for
collisional models of non-equilibrium statistical states", J. Comput. Phys. 228 (2009)
2012-2036 (the constrained least-squares correction, uniform weight); L. Pareschi,
T. Rey, "Moment preserving Fourier-Galerkin spectral methods and application to the
Boltzmann equation", SIAM J. Numer. Anal. 60 (2022), arXiv:2105.13158 (a moment-constrained
projection that keeps spectral accuracy).
"""

from __future__ import annotations

import math

import numpy
import scipy.special

from granframe import validators as check
from granframe.abc import CollisionOperator, checked_energy_factors
from granframe.velocity.quadratures import MAX_GAUSS_POINTS, GaussLegendre

#: The weights w(v) of the correction Q + w (lambda_0 + lambda.v + lambda_{d+1} |v|^2),
#: the default first.
WEIGHTS = ("maxwellian", "distribution", "uniform")


class ConservativeCorrection(CollisionOperator):
    r"""Q with exact discrete conservation of mass and momentum and the exact energy
    dissipation: a wrapper around any collision operator.

    Parameters
    ----------
    operator : CollisionOperator
        The operator whose Q is corrected; its grid, kernel, restitution law and backend
        are the wrapper's.
    weight : {"maxwellian", "distribution", "uniform"}
        w(v) of the correction. ``"maxwellian"`` (the default): exp(-|v - u|^2 / (2T))
        with the bulk velocity u and temperature T of f, smooth and as localised as f, so
        the correction keeps the operator's spectral accuracy (docs/conservative.md); a
        distribution without positive mass and temperature (a stage of a step that is
        blowing up) gets |f| instead, so that the run's health checks, not the weight,
        report it. ``"distribution"``: |f|.
        ``"uniform"``: w = 1, the constrained least-squares correction of Gamba &
        Tharkabhushanam, a polynomial over the whole box (not periodic: it puts a
        non-smooth |v|^2 into the spectrum of f). docs/conservative.md compares them.

    Notes
    -----
    With phi(v) = (1, v, |v|^2), Q^c minimises sum_j (Q^c_j - Q_j)^2 / w_j under the
    d + 2 constraints h^d sum_j Q^c_j phi(v_j) = (0, 0, D(f)):

    .. math:: Q^c = Q + w\,\lambda\cdot p,\qquad G\lambda = c - \sum_j Q_j p_j,
              \qquad G_{ab} = \sum_j w_j p_{a,j} p_{b,j},

    solved per distribution in the basis p = (1, v/L, |v|^2/L^2) (the span of phi)
    with c = (0, 0, D(f) / (h^d L^2)); G is symmetric positive definite for any w > 0
    on d + 2 points in general position, and is solved after scaling it to a unit
    diagonal. The moments of Q^c then hold to round-off, in the operator's precision.
    D(f) is :meth:`dissipation`. Mass is exact already for the spectral operators; the
    correction is then O(the momentum and energy defects of Q), which converge with
    the operator's quadratures.

    f may hold a stack (..., *grid.shape); each distribution gets its own weight,
    dissipation and correction. Every array operation, the (d+2) x (d+2) solves
    included, is in the backend's ``xp``: a call copies nothing between host and device.
    """

    name = "conservative"

    def __init__(self, operator, weight: str = "maxwellian"):
        if not isinstance(operator, CollisionOperator):
            check.reject(self.name, "operator", operator, "must be a granframe."
                         "CollisionOperator, e.g. collision_operator('fast_spectral', ...)",
                         error=TypeError)
        if isinstance(operator, ConservativeCorrection):
            check.reject(self.name, "operator", operator, "is already conservatively "
                         "corrected; wrap the operator it corrects instead")
        if not isinstance(weight, str) or weight not in WEIGHTS:
            check.reject(self.name, "weight", weight, f"must be one of {', '.join(WEIGHTS)}")
        super().__init__(operator.grid, operator.kernel, operator.restitution, operator.backend)
        self.operator, self.weight = operator, weight
        grid, xp = self.grid, self.backend.xp
        L = grid.half_width
        mesh = grid.mesh(numpy)
        basis = [numpy.ones(grid.shape)] + [numpy.broadcast_to(c / L, grid.shape) for c in mesh]
        basis.append(grid.speed_squared(numpy) / (L * L))
        #: the basis p_a(v_j) as rows, (d + 2, N^d)
        self._basis = xp.asarray(numpy.stack([b.reshape(-1) for b in basis]))
        self._mesh = grid.mesh(xp)
        self._angular = (self.kernel.prefactor(grid.dimension)
                         * self.kernel.angular_integral(grid.dimension, lambda t: 1.0 - t))
        self._table = self._dissipation_table()
        #: the planned transform of the doubled grid and the stack size it was made for
        self._padded, self._padded_count = None, 0

    # -- the energy dissipation ------------------------------------------------------------
    def _loss(self, speed):
        """psi(r) = s(r) r^2 (1 - e(r)^2) at the speeds ``speed`` (NumPy, all <= R)."""
        restitution = self.restitution(speed)
        return self.kernel.speed_part(speed) * speed * speed * (1.0 - restitution ** 2)

    def _dissipation_table(self):
        r"""W_k on the half spectrum of the grid doubled to M = 2N points per axis: the
        weights of |F_k|^2 (F = DFT_M of f padded with zeros) whose sum is D(f) / E^gamma;
        None when e = 1 on [0, R] (D = 0). The lattice sum when psi(r) = c r^2, else its
        spectral quadrature (:meth:`dissipation`)."""
        grid = self.grid
        d, n, h, R = grid.dimension, grid.n_modes, grid.spacing, grid.truncation_radius
        m = 2 * n
        offsets = numpy.fft.fftfreq(m, 1.0 / m)      # z or k = 0..N-1, -N..-1 (DFT order)
        squared = sum(numpy.reshape(offsets, [-1 if a == b else 1 for b in range(d)]) ** 2
                      for a in range(d))
        nodes, weights = GaussLegendre(_radial_points(d, n, h, R)).rule(R)
        values = self._loss(nodes)
        if not numpy.any(values != 0.0):
            return None
        multiplicity = numpy.full(m // 2 + 1, 2.0)
        multiplicity[[0, -1]] = 1.0
        scale = -self._angular / 8.0 * h ** d / float(m) ** d
        quadratic = values / (nodes * nodes)
        if numpy.allclose(quadratic, quadratic[0], rtol=1e-14, atol=0.0):
            speed = h * numpy.sqrt(squared)
            inside = speed <= R
            psi = numpy.zeros_like(speed)
            psi[inside] = self._loss(speed[inside])
            spectrum = h ** d * numpy.fft.rfftn(psi).real    # psi(z) = psi(-z): real
        else:
            spectrum = _radial_transform(squared[..., :n + 1], 2.0 * math.pi / (m * h), d,
                                         nodes, weights * values)
        return self.backend.asarray(scale * spectrum * multiplicity)

    def dissipation(self, f):
        r"""D(f) = h^d sum_j Q(f)_j |v_j|^2 of the continuous operator with relative speeds
        cut at R, for the grid function f (a stack (..., *grid.shape)): a NumPy array of
        the batch shape.

        Notes
        -----
        In the sigma-representation, |v'|^2 + |v'_*|^2 - |v|^2 - |v_*|^2
        = -(1 - e^2)/4 |g|^2 (1 - ghat.sigma) with g = v - v_*, so for
        B = C s(|g|) b(ghat.sigma) E(f)^gamma the weak form gives

        .. math:: D(f) = -\frac{E^\gamma C \beta}{8} \iint f f_* s(|g|) |g|^2
                  (1 - e(|g|)^2)\, 1_{|g|\le R}\, dv\, dv_*,\qquad
                  \beta = \int_{S^{d-1}} b(t)(1 - t)\, d\sigma.

        With ``A(z) = sum_j f_j f_{j+z}`` the autocorrelation of f on the grid (f padded
        with zeros to M = 2N points per axis, so that nothing wraps around) and
        psi(r) = s(r) r^2 (1 - e(r)^2) 1_{r <= R}, D is evaluated in one of two ways:

        - psi(r) = c r^2 (Maxwell molecules, constant e): the double sum over grid pairs,
          exactly,

          .. math:: D(f) = -\frac{E^\gamma C\beta}{8} h^{2d} \sum_z A(z)\,\psi(h|z|)
                    = -\frac{E^\gamma C\beta}{8} \frac{h^{2d}}{M^d} \sum_k |F_k|^2 \Psi_k,

          by Parseval, with F and Psi the DFTs of the padded f and of psi(h|z|) on M^d
          points. It equals :func:`granframe.model.exact.maxwell_energy_dissipation` of the
          grid moments to round-off when f f_* vanishes for |g| > R.
        - otherwise psi is not smooth at g = 0 (|g|^{2+lambda}, or 1 - e^2 ~ |g| for
          Toscani's law), and the lattice sum converges only algebraically in h (2D hard
          spheres, S = 3: 5e-6 relative at N = 40, 3e-7 at N = 64). The autocorrelation
          is then integrated as its trigonometric interpolant
          A(g) = M^{-d} sum_k |F_k|^2 e^{i kappa_k.g}, kappa_k = 2 pi k / (M h), against
          psi exactly in angle:

          .. math:: D(f) = -\frac{E^\gamma C\beta}{8} \frac{h^d}{M^d} \sum_k |F_k|^2
                    \hat\psi(|\kappa_k|),\qquad \hat\psi(\kappa) = |S^{d-1}|
                    \int_0^R \psi(r) r^{d-1} j(\kappa r)\, dr,

          j = J_0 (2D), sin x / x (3D), with Gauss-Legendre on [0, R] (64 + pi sqrt(d) R / h
          points, beyond the oscillations of the largest kappa). This converges
          spectrally: 1e-14 from N = 40 (2D, S = 3, T = 0.5, hard spheres and
          variable-hard-sphere kernels with constant, Toscani and tanh laws).

        Either way it is one real FFT of (2N)^d points per distribution; the weights are
        tabulated once. E(f) = h^d sum |v|^2 f / 2 as in the operators.
        """
        stack, batch_shape = self._stack(f)
        values = self._dissipation(stack, self._raw_moments(stack))
        return numpy.asarray(self.backend.to_numpy(values), dtype=float).reshape(batch_shape)

    def _dissipation(self, stack, moments):
        """D for each distribution of ``stack`` (B, *grid.shape), given its raw moments
        (B, d + 2): a backend array (B,), computed on the backend."""
        xp, grid = self.backend.xp, self.grid
        count = stack.shape[0]
        if self._table is None:
            return xp.zeros(count)
        d, n = grid.dimension, grid.n_modes
        if self._padded_count != count:      # planned once per stack size (FFTW, cuFFT)
            self._padded = self.backend.real_fft((count,) + (2 * n,) * d,
                                                 tuple(range(1, d + 1)))
            self._padded_count = count
        fft = self._padded
        fft.real[...] = 0.0
        fft.real[(slice(None),) + (slice(0, n),) * d] = stack
        spectrum = fft.forward()
        power = spectrum.real ** 2 + spectrum.imag ** 2
        sums = xp.sum((power * self._table).reshape(count, -1), axis=1)
        if not self.kernel.energy_exponent:
            return sums.astype(xp.float64, copy=False)
        energy = 0.5 * grid.cell_volume * moments[:, -1] * grid.half_width ** 2
        return checked_energy_factors(self.kernel, energy, self.backend) * sums

    # -- the correction ------------------------------------------------------------------
    def __call__(self, f):
        r"""Q^c(f) for each distribution of f, shape (..., *grid.shape) (class notes).

        Every step is on the backend: the moments, weights, Gram systems, their solution
        and D(f) make no copy between host and device (a NumPy backend's arrays are the
        host's)."""
        q = self.operator(f)                        # checks f: shape, dtype, finiteness
        stack, batch_shape = self._stack(f)
        xp, grid = self.backend.xp, self.grid
        count = stack.shape[0]
        moments = self._raw_moments(stack)
        weight = self._weights(stack, moments)                          # (B or 1, N^d)
        flat_q = q.reshape(count, -1)
        defect = flat_q @ self._basis.T                                 # (B, d + 2)
        weighted = weight[:, None, :] * self._basis[None]               # (B or 1, d + 2, N^d)
        gram = weighted @ self._basis.T                                 # (B or 1, d+2, d+2)
        target = xp.zeros(defect.shape, dtype=xp.float64)
        target[:, -1] = (self._dissipation(stack, moments)
                         / (grid.cell_volume * grid.half_width ** 2))
        multipliers = _solve_scaled(xp, xp.broadcast_to(gram, (count,) + gram.shape[1:]),
                                    target - defect)
        correction = xp.matmul(multipliers[:, None, :],
                               weighted if weighted.shape[0] == count
                               else weighted[0])[:, 0, :]
        result = flat_q + correction.astype(q.dtype, copy=False)
        return result.reshape(batch_shape + grid.shape)

    def _stack(self, f):
        """f as a stack (B, *grid.shape) and its batch shape (f already checked)."""
        d = self.grid.dimension
        batch_shape = tuple(f.shape[:f.ndim - d])
        return f.reshape((math.prod(batch_shape),) + self.grid.shape), batch_shape

    def _raw_moments(self, stack):
        """sum_j f_j p_a(v_j) for each distribution: a backend (B, d + 2) float64 array."""
        flat = stack.reshape(stack.shape[0], -1).astype(self.backend.xp.float64, copy=False)
        return flat @ self._basis.T

    def _weights(self, stack, moments):
        """w(v_j) for each distribution, (B, N^d); (1, N^d) for the uniform weight.

        The Maxwellian weight of a distribution without positive mass and temperature is
        |f| (chosen per distribution with ``where``, no copy to the host)."""
        xp, grid = self.backend.xp, self.grid
        if self.weight == "uniform":
            return xp.ones((1, self._basis.shape[1]))
        magnitude = xp.abs(stack.reshape(stack.shape[0], -1)).astype(xp.float64, copy=False)
        if self.weight == "distribution":
            return magnitude
        d, L = grid.dimension, grid.half_width
        mass = moments[:, 0]
        with numpy.errstate(all="ignore"):
            velocity = moments[:, 1:d + 1] * L / mass[:, None]
            temperature = ((moments[:, -1] * L * L / mass
                            - xp.sum(velocity * velocity, axis=1)) / d)
        good = xp.isfinite(temperature) & (mass > 0.0) & (temperature > 0.0)
        velocity = xp.where(good[:, None], velocity, 0.0)
        temperature = xp.where(good, temperature, 1.0)
        spread = 1.0 / (2.0 * temperature)
        exponent = 0.0
        for axis, c in enumerate(self._mesh):
            exponent = exponent + (c[None] - velocity[:, axis].reshape((-1,) + (1,) * d)) ** 2
        weights = xp.exp(-exponent * spread.reshape((-1,) + (1,) * d)).reshape(len(mass), -1)
        # a blown-up stage: |f| keeps the constraints well posed
        return xp.where(good[:, None], weights, magnitude)

    def close(self):
        """Close the wrapped operator (its worker threads)."""
        close = getattr(self.operator, "close", None)
        if close is not None:
            close()


def _solve_scaled(xp, gram, rhs):
    """lambda_b solving gram_b lambda_b = rhs_b for each b, in the array namespace ``xp``,
    after scaling gram_b to a unit diagonal (the basis entries differ in size by powers of
    T / L^2)."""
    scale = 1.0 / xp.sqrt(xp.einsum("bii->bi", gram))
    scaled = gram * scale[:, :, None] * scale[:, None, :]
    try:
        return xp.linalg.solve(scaled, (rhs * scale)[..., None])[..., 0] * scale
    except numpy.linalg.LinAlgError:     # CuPy raises NumPy's too
        raise ValueError("ConservativeCorrection: parameter 'f' is invalid; the Gram system "
                         "of its weight is singular in at least one distribution (a cell): "
                         "its Maxwellian weight sits on fewer nodes than the d + 2 "
                         "conserved moments need, f being too narrow for the velocity "
                         "grid's spacing; raise grid.n_modes (or lower grid.support_radius)"
                         ) from None


def _radial_points(dimension: int, n_modes: int, spacing: float, radius: float) -> int:
    """Gauss-Legendre points on [0, R] for the radial transforms of :func:`_radial_transform`:
    64 more than kappa_max R, with kappa_max = pi sqrt(d) / h the largest wavenumber of the
    doubled grid (the integrand oscillates kappa R / pi times)."""
    return min(MAX_GAUSS_POINTS, 64 + int(math.pi * math.sqrt(dimension) * radius / spacing))


def _radial_transform(squared, unit: float, dimension: int, nodes, weights):
    r"""Psi(kappa) = int_{B_R} psi(|g|) e^{-i kappa.g} dg at kappa = unit |k| for the integer
    squared wavenumbers ``squared``: |S^{d-1}| sum_i w_i psi(r_i) r_i^{d-1} j(kappa r_i) with
    j = J_0 (2D), sin x / x (3D); ``weights`` are w_i psi(r_i). Evaluated once per distinct
    |k|^2, in blocks."""
    distinct, inverse = numpy.unique(squared, return_inverse=True)
    radial = weights * nodes ** (dimension - 1)
    out = numpy.empty(len(distinct))
    for start in range(0, len(distinct), 512):
        x = unit * numpy.sqrt(distinct[start:start + 512])[:, None] * nodes
        waves = scipy.special.j0(x) if dimension == 2 else numpy.sinc(x / math.pi)
        out[start:start + 512] = waves @ radial
    return 2.0 * math.pi * (dimension - 1) * out[inverse].reshape(squared.shape)
