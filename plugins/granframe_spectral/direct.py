"""Direct Fourier-Galerkin method of Filbet, Pareschi and Toscani.

Review (Carrillo, Hu, Ma, Rey), section 2.1; [FPT05] F. Filbet, L. Pareschi,
G. Toscani, J. Comput. Phys. 202 (2005). O(N^{2d}) weights, O(N^{2d}) work:
the slow, obviously-correct reference against which the fast method is checked.
"""

from __future__ import annotations

import math

import numpy
import scipy.special

from granframe import memory
from granframe import validators as check
from granframe.abc import CollisionOperator, check_arguments
from granframe.velocity.quadratures import MAX_GAUSS_POINTS, GaussLegendre, sphere_area

from granframe_spectral._common import (check_operands, energy_factor, isotropic_sphere_average,
                                        radial_rule)

#: Bytes per (k, m) entry: weight (complex), gather index, triple key, gathered f-hat (of
#: one distribution; a stack of D distributions gathers D of them,
#: :data:`BYTES_PER_GATHERED` each).
BYTES_PER_ENTRY = 16 + 8 + 8 + 16
#: Bytes per (k, m) entry and distribution of the gathered f-hat.
BYTES_PER_GATHERED = 16

#: Largest ``angular_degree``: its coefficients take a Gauss rule of 2 degree + 64 points,
#: which must stay within the radial rule's bound; degree 1024 resolves b(cos theta) far
#: beyond what any grid of this method's size (N <= about 100 under the default budget) sees.
MAX_ANGULAR_DEGREE = 1024


def angular_coefficients(kernel, dimension: int, max_degree: int):
    """Coefficients of b(cos theta) in the zonal basis, and the truncation degree.

    3D: b_n = int_{-1}^{1} b(t) P_n(t) dt (Legendre); 2D:
    beta_n = int_0^{2 pi} b(cos psi) cos(n psi) dpsi (Fourier). The series is
    cut after the last coefficient above 1e-13 |b_0|, the round-off level of
    the rules computing them (degree 0 when b is constant).
    """
    if kernel.is_isotropic:
        return numpy.array([2.0 if dimension == 3 else 2.0 * math.pi]), 0
    n = numpy.arange(max_degree + 1)
    if dimension == 3:
        # Gauss-Legendre on [-1, 1]: the rule on [0, 2] shifted by -1
        t, w = GaussLegendre(2 * max_degree + 64).rule(2.0)
        t = t - 1.0
        values = kernel.angular_part(t)
        coeffs = numpy.array([w @ (values * scipy.special.eval_legendre(k, t)) for k in n])
    else:
        psi = 2.0 * math.pi * numpy.arange(4 * max_degree + 64) / (4 * max_degree + 64)
        values = kernel.angular_part(numpy.cos(psi))
        coeffs = numpy.array([values @ numpy.cos(k * psi) for k in n]) * (2 * math.pi / len(psi))
    significant = numpy.nonzero(numpy.abs(coeffs) > 1e-13 * abs(coeffs[0]))[0]
    return coeffs, int(significant.max())


class DirectSpectral(CollisionOperator):
    r"""Direct Fourier-Galerkin collision operator with exact angular integrals.

    Parameters
    ----------
    grid, kernel, restitution, backend
        See :class:`granframe.CollisionOperator`.
    radial_points : int or None
        Gauss-Legendre points for the rho-integral of the weights (default 2N + 16,
        enough to resolve the Bessel oscillations to round-off; at most
        :data:`~granframe.velocity.quadratures.MAX_GAUSS_POINTS`).
    angular_degree : int
        Highest degree of the zonal expansion of b(cos theta) (anisotropic kernels), at
        most :data:`MAX_ANGULAR_DEGREE`.
    memory_budget : int or None
        Bytes the weights may use; a larger problem is refused, before anything is
        allocated, with the memory it needs (:meth:`estimate_memory`). The default is
        ``GRANFRAME_MEMORY_BUDGET`` when that environment variable is set, else 4 GiB
        (:mod:`granframe.memory`). A stack of D distributions gathers D f-hat per
        (k, m) entry at the call; a stack that would exceed the budget is refused then,
        naming ``f``.

    Notes
    -----
    On the Nyquist-free modes I = {k : |k_i| <= N/2 - 1},

    .. math::

        \hat Q_k = \sum_{l+m=k;\ l,m\in I} G(l,m)\hat f_l \hat f_m ,\qquad
        G(l,m) = \int_{B_R} e^{-i\pi m\cdot g/L}\int_{S^{d-1}} B(|g|,\sigma\cdot\hat g)
        \left(e^{i\pi\frac{1+e}{4L}(l+m)\cdot(g-|g|\sigma)}-1\right)d\sigma\,dg .

    Both angular integrals are done exactly by the Funk-Hecke formula. With
    x = a k, a = pi rho (1 + e(rho))/(4L), y = x - pi rho m / L and
    cos(Delta) = x.y/(|x||y|), in 3D

    .. math::

        G = C\int_0^R \rho^{2+\lambda}\Big[8\pi^2\sum_n (2n+1) b_n j_n(|x|) j_n(|y|)
        P_n(\cos\Delta) - 8\pi^2 b_0\, j_0(\pi\rho|m|/L)\Big] d\rho ,

    and in 2D the same with 2 pi beta_n J_n J_n T_n(cos Delta) (n >= 0, the
    n >= 1 terms doubled) and loss 2 pi beta_0 J_0(pi rho |m|/L). G depends on
    k and m only through (|k|^2, |m|^2, k.m), which is evaluated once per
    distinct triple.

    f may hold a stack of distributions f_b, shape (..., *grid.shape): the sum is one
    contraction over the stack (the weights read once for all b), and each f_b gets its
    own E(f_b)^gamma.
    """

    name = "direct_spectral"
    #: Default of ``memory_budget`` when GRANFRAME_MEMORY_BUDGET is not set.
    DEFAULT_MEMORY_BUDGET = 4 * 2 ** 30

    def __init__(self, grid, kernel, restitution, backend, *, radial_points=None,
                 angular_degree=48, memory_budget=None):
        super().__init__(grid, kernel, restitution, backend)
        owner = "direct_spectral"
        d, n = grid.dimension, grid.n_modes
        self.memory_bytes = self.estimate_memory(grid, kernel, restitution, backend,
                                                 radial_points=radial_points,
                                                 angular_degree=angular_degree)
        if memory_budget is None:
            memory_budget = memory.budget(self.DEFAULT_MEMORY_BUDGET)
        if not check.is_real(memory_budget) or memory_budget <= 0:
            check.reject(owner, "memory_budget", memory_budget, "must be a positive number of bytes")
        self.memory_budget = memory_budget
        if self.memory_bytes > memory_budget:
            check.reject(owner, "memory_budget", memory_budget,
                         f"is too small: the direct method needs {memory.gib(self.memory_bytes)} "
                         f"GiB for its {(n - 1) ** d}^2 weights (d = {d}, N = {n}); use "
                         "fast_spectral or a smaller N")
        self.radial_points = 2 * n + 16 if radial_points is None else int(radial_points)
        self.angular_degree = int(angular_degree)
        self._build()

    @classmethod
    def estimate_memory(cls, grid, kernel, restitution, backend, *, radial_points=None,
                        angular_degree=48, memory_budget=None, distributions=1) -> int:
        """Bytes of the weights for stacks of ``distributions`` distributions,
        :data:`BYTES_PER_ENTRY` + (D - 1) :data:`BYTES_PER_GATHERED` per pair of
        Nyquist-free modes (nothing is allocated); invalid options raise the operator's
        own errors. ``memory_budget`` does not change the estimate (it is what it is
        compared with)."""
        owner = "direct_spectral"
        check_arguments(owner, grid, kernel, restitution, backend)
        radial_points = 2 * grid.n_modes + 16 if radial_points is None else radial_points
        if not check.is_integer(radial_points) or not 1 <= radial_points <= MAX_GAUSS_POINTS:
            check.reject(owner, "radial_points", radial_points,
                         f"must be an integer >= 1 and <= {MAX_GAUSS_POINTS}")
        if not check.is_integer(angular_degree) or not 0 <= angular_degree <= MAX_ANGULAR_DEGREE:
            check.reject(owner, "angular_degree", angular_degree,
                         f"must be an integer >= 0 and <= {MAX_ANGULAR_DEGREE}")
        if not check.is_integer(distributions) or distributions < 1:
            check.reject(owner, "distributions", distributions, "must be an integer >= 1")
        return ((BYTES_PER_ENTRY + (int(distributions) - 1) * BYTES_PER_GATHERED)
                * ((grid.n_modes - 1) ** grid.dimension) ** 2)

    def _build(self):
        """The weights G(k - m, m) - loss, the gather index of l = k - m and the FFT layout.

        G depends on (k, m) only through (|k|^2, |m|^2, k.m), which every signed
        permutation of the axes (a symmetry g of the cube: 8 in 2D, 48 in 3D) leaves
        unchanged: G(k, m) = G(gk, gm). The distinct triples are therefore those of the
        rows k in the fundamental domain k_1 >= ... >= k_d >= 0 (1/8 of the rows in 2D,
        1/48 in 3D), and every other row is the row of its representative gk, read at the
        columns gm."""
        grid, xp = self.grid, self.backend.xp
        self._speed_squared = grid.speed_squared(xp)
        d, n = grid.dimension, grid.n_modes
        half = n // 2 - 1
        one = numpy.arange(-half, half + 1)
        modes = numpy.stack(numpy.meshgrid(*([one] * d), indexing="ij"), axis=-1).reshape(-1, d)
        count = len(modes)
        strides = (n - 1) ** numpy.arange(d - 1, -1, -1)
        # l = k - m is a mode when every |k_i - m_i| <= N/2 - 1; the index is linear in
        # the components, so index(k - m) = index(k) - index(m) + index(0)
        valid = numpy.ones((count, count), dtype=bool)
        for axis in range(d):
            component = modes[:, axis].astype(numpy.int16)
            valid &= numpy.abs(component[:, None] - component[None, :]) <= half
        index = (modes + half) @ strides
        l_index = numpy.where(valid, index[:, None] - index[None, :] + half * strides.sum(), 0)
        # each row's symmetry: its signs s and the permutation p sorting |k| downwards,
        # (g m)_i = s_{p_i} m_{p_i}; g k is the row's representative
        signs = numpy.where(modes < 0, -1, 1)
        order = numpy.argsort(-numpy.abs(modes), axis=1, kind="stable")
        representative = numpy.take_along_axis(numpy.abs(modes), order, axis=1)
        rows, row_of = numpy.unique((representative + half) @ strides, return_inverse=True)
        kk = numpy.einsum("ij,ij->i", modes, modes)
        top = int(kk.max())
        km = modes[rows] @ modes.T
        key = (kk[rows][:, None] * (top + 1) + kk[None, :]) * (2 * top + 1) + (km + top)
        unique, inverse = numpy.unique(key, return_inverse=True)
        del key, km
        u_kk = unique // ((top + 1) * (2 * top + 1))
        u_mm = (unique // (2 * top + 1)) % (top + 1)
        u_km = unique % (2 * top + 1) - top
        coeffs, degree = angular_coefficients(self.kernel, d, self.angular_degree)
        rho, scale = self._radial()
        gain = self._gain_weights(u_kk, numpy.sqrt(u_mm), u_km.astype(float),
                                  rho, scale, coeffs, degree)[inverse.reshape(len(rows), count)]
        loss = self._loss_weights(numpy.sqrt(numpy.arange(top + 1)), rho, scale, coeffs[0])
        weights = numpy.empty((count, count))
        symmetry = numpy.concatenate([order, numpy.take_along_axis(signs, order, axis=1)], axis=1)
        groups, group_of = numpy.unique(symmetry, axis=0, return_inverse=True)
        for g, (permutation, sign) in enumerate(zip(groups[:, :d], groups[:, d:])):
            members = numpy.nonzero(group_of.ravel() == g)[0]
            columns = ((modes[:, permutation] * sign + half) @ strides)
            weights[members] = gain[row_of[members]][:, columns]
        weights -= loss[kk][None, :]
        weights *= valid
        self._weights = xp.asarray(weights)
        self._l_index = xp.asarray(l_index)
        # positions of the modes in numpy's FFT layout, and the (-1)^{k_1+...+k_d} factor
        self._fft_index = tuple(xp.asarray(c) for c in (modes % n).T)
        self._sign = xp.asarray((-1.0) ** modes.sum(axis=1))

    def _radial(self):
        rho, w = radial_rule(self.grid, self.radial_points)
        d = self.grid.dimension
        scale = w * rho ** (d - 1) * self.kernel.prefactor(d) * self.kernel.speed_part(rho)
        return rho, scale

    def _gain_weights(self, k_squared, m_norm, k_dot_m, rho, scale, coeffs, degree):
        """The gain weights on the unique (|k|^2, |m|, k.m) keys.

        The factors of x = a|k| depend on |k| alone and are tabulated over the
        |k|^2 <= max(k_squared). For an isotropic kernel and a restitution coefficient e
        that is the same at every rho, a = c b with c = (1 + e)/4 and b = pi rho / L, so
        that |y| = b z with z = |c k - m|: the weight is then
        sum_rho s_rho A(a|k|) A(b z) (A the sphere average), a function of (|k|^2, z)
        alone, evaluated once per distinct z and per distinct |k|^2 and summed over rho
        as a matrix product when the distinct z are few (:meth:`_isotropic_gain`)."""
        d, L = self.grid.dimension, self.grid.half_width
        e = self.restitution(rho)
        if degree == 0 and numpy.all(e == e[0]):
            out = self._isotropic_gain(k_squared, m_norm, k_dot_m, rho, scale, coeffs[0],
                                       (1.0 + e[0]) / 4.0)
            if out is not None:
                return out
        norms = numpy.sqrt(numpy.arange(int(k_squared.max()) + 1))
        out = numpy.zeros(k_squared.shape)
        for r, s, e_r in zip(rho, scale, e):
            a, b = math.pi * r * (1.0 + e_r) / (4.0 * L), math.pi * r / L
            x = (a * norms)[k_squared]
            y = numpy.sqrt(numpy.maximum(x ** 2 - 2 * a * b * k_dot_m + (b * m_norm) ** 2, 0.0))
            if degree == 0:
                series = (coeffs[0] * isotropic_sphere_average(a * norms, d)[k_squared]
                          * isotropic_sphere_average(y, d))
            else:
                with numpy.errstate(invalid="ignore", divide="ignore"):
                    cos = numpy.where((x > 0) & (y > 0), (x ** 2 - a * b * k_dot_m) / (x * y), 1.0)
                cos = numpy.clip(cos, -1.0, 1.0)
                series = numpy.zeros_like(x)
                for order in range(degree + 1):
                    if d == 3:
                        term = ((2 * order + 1) * coeffs[order]
                                * scipy.special.spherical_jn(order, a * norms)[k_squared]
                                * scipy.special.spherical_jn(order, y)
                                * scipy.special.eval_legendre(order, cos))
                    else:
                        term = ((1 if order == 0 else 2) * coeffs[order]
                                * scipy.special.jv(order, a * norms)[k_squared]
                                * scipy.special.jv(order, y)
                                * scipy.special.eval_chebyt(order, cos))
                    series += term
            out += s * series
        # 3D: 8 pi^2 sum (2n+1) b_n ...; 2D: 2 pi sum beta_n ...
        return out * (8.0 * math.pi ** 2 if d == 3 else 2.0 * math.pi)

    def _isotropic_gain(self, k_squared, m_norm, k_dot_m, rho, scale, b_0, c):
        """:meth:`_gain_weights` of an isotropic kernel and a constant e, c = (1 + e)/4:
        b_0 sum_rho s_rho A(c b_rho |k|) A(b_rho z), z^2 = c^2 |k|^2 - 2 c k.m + |m|^2.

        The sum is the product of the (rho, |k|^2) and (rho, z) tables of A, in blocks of z
        of at most 2^22 entries, read at each key's (|k|^2, z). None when the table of all
        (|k|^2, z) would exceed 16 entries per key: z is then nearly distinct per key (e
        such that c^2 k^2 - 2 c k.m + m^2 rarely repeats, e.g. e = 0.9; e = 0.5 gives
        36589 distinct z for 1.9e6 keys at 2D N = 64) and the product saves nothing.
        """
        d, L = self.grid.dimension, self.grid.half_width
        m_squared = numpy.rint(m_norm ** 2)
        z, z_of = numpy.unique(numpy.sqrt(numpy.maximum(
            c * c * k_squared - 2.0 * c * k_dot_m + m_squared, 0.0)), return_inverse=True)
        levels, level_of = numpy.unique(k_squared, return_inverse=True)
        if len(levels) * len(z) > 16 * len(k_squared):
            return None
        b = math.pi * rho / L
        outer = (isotropic_sphere_average(numpy.outer(c * b, numpy.sqrt(levels)), d)
                 * scale[:, None])
        out = numpy.empty(k_squared.shape)
        block = max(1, 2 ** 22 // max(len(levels), len(rho)))
        for start in range(0, len(z), block):
            stop = min(start + block, len(z))
            inner = isotropic_sphere_average(numpy.outer(b, z[start:stop]), d)
            table = outer.T @ inner                      # (|k|^2, z[start:stop])
            members = numpy.nonzero((z_of >= start) & (z_of < stop))[0]
            out[members] = table[level_of[members], z_of[members] - start]
        # 3D: 8 pi^2 b_0 ...; 2D: 2 pi beta_0 ...
        return out * b_0 * (8.0 * math.pi ** 2 if d == 3 else 2.0 * math.pi)

    def _loss_weights(self, m_norm, rho, scale, b_0):
        d, L = self.grid.dimension, self.grid.half_width
        omega = 2.0 * math.pi * b_0 if d == 3 else b_0               # int b(sigma.ghat) dsigma
        out = numpy.zeros(m_norm.shape)
        for r, s in zip(rho, scale):
            out += s * isotropic_sphere_average(math.pi * r / L * m_norm, d)
        return out * omega * sphere_area(d)

    def __call__(self, f):
        r"""Q_I(f_b, f_b) on the grid for each distribution f_b of f, shape
        (..., *grid.shape): the Galerkin sum over l + m = k (class notes),
        Qhat_{b,k} = E(f_b)^gamma sum_m G(k - m, m) fhat_{b,k-m} fhat_{b,m}."""
        stack, batch_shape = check_operands(self.name, self.grid, f, self.backend)
        xp, backend, grid = self.backend.xp, self.backend, self.grid
        count, d = stack.shape[0], grid.dimension
        if count > 1:
            needed = self.estimate_memory(grid, self.kernel, self.restitution, backend,
                                          radial_points=self.radial_points,
                                          angular_degree=self.angular_degree,
                                          distributions=count)
            if needed > self.memory_budget:
                check.reject(self.name, "f", f"a stack of {count} distributions",
                             f"is too large: it needs {memory.gib(needed)} GiB, over the "
                             f"memory_budget of {memory.gib(self.memory_budget)} GiB; "
                             "evaluate smaller stacks")
        axes = tuple(range(1, d + 1))
        total = float(grid.n_modes) ** d
        spectrum = backend.fftn(stack, axes=axes)
        f_hat = spectrum[(slice(None),) + self._fft_index] * self._sign / total   # (B, M)
        q_hat = xp.einsum("km,bkm,bm->bk", self._weights, f_hat[:, self._l_index], f_hat)
        out_spectrum = xp.zeros(stack.shape, dtype=xp.complex128)
        out_spectrum[(slice(None),) + self._fft_index] = q_hat * self._sign * total
        q = xp.real(backend.ifftn(out_spectrum, axes=axes))
        factors = energy_factor(self.kernel, grid.cell_volume, self._speed_squared, stack,
                                backend)
        if factors is not None:
            q = q * factors.reshape((count,) + (1,) * d)
        return q.reshape(batch_shape + grid.shape)
