"""Fast Fourier spectral method of Hu & Ma for the inelastic collision operator.

Review (Carrillo, Hu, Ma, Rey), section 2.2; [HM19] J. Hu, Z. Ma, "A fast
spectral method for the inelastic Boltzmann collision operator and application
to heated granular gases", J. Comput. Phys. 385 (2019).
"""

from __future__ import annotations

import concurrent.futures
import math

import attrs
import numpy
import threadpoolctl

from granframe import validators as check
from granframe.abc import PRECISIONS
from granframe import memory
from granframe.abc import CollisionOperator, check_arguments
from granframe.velocity.grid import ANTI_ALIASING_FACTOR
from granframe.velocity.quadratures import (LEBEDEV_ORDERS, MAX_GAUSS_POINTS,
                                            MAX_SURFACE_POINTS, CircleTrapezoid, Lebedev,
                                            SphereProduct, SurfaceQuadrature, antipodal_pairs,
                                            sphere_area)

from granframe_spectral._common import (check_operands, energy_factor, isotropic_sphere_average,
                                        radial_rule)

#: Values of the option ``quadrature``: ``auto`` chooses the rules from the grid
#: (:func:`default_quadratures`), ``review`` takes the review's.
QUADRATURES = ("auto", "review")
#: The review's quadratures (section 2.2 and its Tests 1-3): N_rho = 32 and M = 16 in 2D;
#: N_rho = 30 and the 32-point Gauss product rule (n = 4, degree 7) in 3D. The sigma rules
#: (anisotropic b only; the review's kernels are isotropic) are granframe's former defaults.
REVIEW_RADIAL = {2: 32, 3: 30}
REVIEW_SPHERE = {2: CircleTrapezoid(16), 3: SphereProduct(4)}
REVIEW_SIGMA = {2: CircleTrapezoid(32), 3: SphereProduct(8)}
#: R/L of the default grid (R = 2S, L = (3 + sqrt 2) S / 2): the rules of ``auto`` are
#: calibrated on it and scale with N R/L on other grids.
DEFAULT_REACH = 2.0 / ANTI_ALIASING_FACTOR
#: The rules of ``auto``, (a, b) of a n + b in the effective modes per axis
#: n = N (R/L) / DEFAULT_REACH: N_rho = ceil4(a n + b) Gauss-Legendre points; the ghat rule
#: and the sigma rule have ceil4(a n + b) equispaced points (2D) or the smallest Lebedev order
#: >= a n + b (3D), the sigma rule at least the review's (32 points, degree 15). Measured by
#: studies/default_quadrature.py (docs/accuracy-vs-cost.md, "Default quadratures").
AUTO_RADIAL = {2: (0.5, 8.0), 3: (0.5, 4.0)}
AUTO_SPHERE = {2: (1.0, 8.0), 3: (1.0, 3.0)}
AUTO_SIGMA = {2: (0.5, 8.0), 3: (0.5, 4.0)}


def default_quadratures(grid, quadrature: str = "auto") -> tuple:
    r"""The rules (N_rho, sphere, sigma) that ``fast_spectral`` takes by default on ``grid``.

    Parameters
    ----------
    grid : VelocityGrid
    quadrature : {"auto", "review"}
        ``review``: the review's rules (:data:`REVIEW_RADIAL`, :data:`REVIEW_SPHERE`,
        :data:`REVIEW_SIGMA`), whatever the grid. ``auto``: rules that grow with the grid,
        so that the quadrature error stays below what N resolves. The phases
        pi rho m.ghat / L of the ghat-integrand reach pi R N / (2L), so the rules follow
        the effective modes per axis n = N (R/L) / (2 / 2.207) (n = N on the default grid,
        R = 2S, L = (3 + sqrt 2) S / 2):

        - 2D: N_rho = ceil4(n/2 + 8) Gauss-Legendre points; M = ceil4(n + 8) equispaced
          directions for ghat; ceil4(n/2 + 8), and at least 32, for sigma;
        - 3D: N_rho = ceil4(n/2 + 4); the Lebedev rules of the smallest orders >= n + 3
          for ghat and >= n/2 + 4, and at least 15, for sigma
          (:data:`AUTO_RADIAL`, :data:`AUTO_SPHERE`, :data:`AUTO_SIGMA`),

        with ceil4 the next multiple of 4. Measured by studies/default_quadrature.py on
        data scaled to the coldest the grid resolves (docs/accuracy-vs-cost.md, "Default
        quadratures"): the operator then differs from a reference with far more points by
        less than 1e-7 of max |Q|, or less than a tenth of N's own error on grids too
        coarse to resolve any data to 1e-7.

    Returns
    -------
    tuple
        (radial_points, sphere, sigma).
    """
    d = grid.dimension
    if quadrature == "review":
        return REVIEW_RADIAL[d], REVIEW_SPHERE[d], REVIEW_SIGMA[d]
    modes = grid.n_modes * grid.truncation_radius / grid.half_width / DEFAULT_REACH

    def size(rule):
        slope, offset = rule[d]
        return slope * modes + offset

    radial = min(_ceil_to(size(AUTO_RADIAL), 4), MAX_GAUSS_POINTS)
    if d == 2:
        points = min(_ceil_to(size(AUTO_SPHERE), 4), MAX_SURFACE_POINTS)
        sigma = min(max(_ceil_to(size(AUTO_SIGMA), 4), REVIEW_SIGMA[2].n_points),
                    MAX_SURFACE_POINTS)
        return radial, CircleTrapezoid(points), CircleTrapezoid(sigma)
    return (radial, Lebedev(_lebedev_order(size(AUTO_SPHERE))),
            Lebedev(_lebedev_order(max(size(AUTO_SIGMA), REVIEW_SIGMA[3].degree))))


def _lebedev_order(degree: float) -> int:
    """The smallest Lebedev order >= ``degree`` (the largest there is beyond them)."""
    return next((o for o in LEBEDEV_ORDERS if o >= degree), LEBEDEV_ORDERS[-1])


def _ceil_to(value: float, step: int) -> int:
    """The smallest multiple of ``step`` >= ``value`` (at least ``step``)."""
    return max(step, step * math.ceil(value / step - 1e-9))


class FastSpectral(CollisionOperator):
    r"""Fast spectral collision operator, O(M N_rho N^d log N) per evaluation.

    Parameters
    ----------
    grid, kernel, restitution, backend
        See :class:`granframe.CollisionOperator`.
    radial_points : int
        N_rho, Gauss-Legendre points for rho = |g| on [0, R] (default: from
        ``quadrature``).
    sphere : SurfaceQuadrature
        Rule for ghat on S^{d-1} (default: from ``quadrature``).
    sigma : SurfaceQuadrature
        Rule for the sigma-integral when b(cos theta) is not constant
        (ignored for isotropic kernels, whose sigma-integral is exact; default:
        from ``quadrature``).
    quadrature : {"auto", "review"}
        Where the rules not given come from (:func:`default_quadratures`).
        ``auto`` (default): chosen from the grid so that the operator is converged
        for it: N_rho ~ N/2 and circle or Lebedev rules whose degree grows with N
        (2D N = 64: N_rho = 40, M = 72; 3D N = 32: N_rho = 20, Lebedev 35; the
        measured errors are in docs/accuracy-vs-cost.md, "Default quadratures").
        ``review``: the review's N_rho = 32, M = 16 in 2D and N_rho = 30, the
        32-point product rule of degree 7 in 3D, for reproducing its numbers
        (docs/reproduction.md); it limits 3D to about 1e-2. ``radial_points``,
        ``sphere`` and ``sigma``, when given, take precedence over either.
    batch : int or None
        Pairs (rho, ghat) transformed together for one distribution; ``None`` chooses
        from the grid size and the backend's ``batch_bytes`` (a few MiB on a CPU,
        hundreds on a GPU). A stack of D distributions is cut into chunks of
        C = min(D, max(1, batch // P)) distributions (P pairs per rho), each
        transformed with blocks of max(1, batch // C) pairs: about ``batch`` grids
        per FFT call whatever D (:meth:`stack_transforms`), so the buffers stay the
        size that fits the cache, and a chunk's spectra and accumulators are reused
        over the whole rho of each block.
    memory_budget : int or None
        Bytes the operator may hold: its tables, work buffers and the transients of
        its precomputation. The default is ``GRANFRAME_MEMORY_BUDGET`` when that
        environment variable is set, else 2 GiB (:mod:`granframe.memory`). The batch
        shrinks to fit it; a problem that does not fit with one pair per pipeline is
        refused before anything large is allocated, with the memory it needs
        (:meth:`estimate_memory`). The buffers of a stack of distributions are sized on
        the first call with that stack size (and kept until a call with another size);
        a stack that does not fit the budget is refused then, naming ``f``.
    precision : {"float64", "float32"}
        Arithmetic of the evaluation: transforms, phase tables, weights and
        accumulators. The tables are computed in float64 and rounded once. In
        float32, f is rounded on entry and Q is returned in float32 (a time
        integrator may keep its state in float64). docs/accuracy-vs-cost.md
        gives its measured accuracy floor.

    Notes
    -----
    With g = rho ghat, the gain weight is approximated by the product rule
    [HM19, eq. (lowrank1)]

    .. math::

        \hat Q^+_k = \sum_{\rho,\hat g} w_\rho w_{\hat g} \rho^{d-1} F(k,\rho,\hat g)
        \sum_{l+m=k} \hat f_l \hat f_m e^{-i\pi\rho m\cdot\hat g/L},\quad
        F = \int_{S^{d-1}} B(\rho,\sigma\cdot\hat g)
        e^{i\pi\rho\frac{1+e(\rho)}{4L} k\cdot(\hat g-\sigma)}d\sigma .

    For isotropic B = C rho^lambda, F = C rho^lambda |S^{d-1}| j(a|k|)
    e^{i a k.ghat} with a = pi rho (1+e)/(4L) and j = J_0 (2D), sinc (3D).
    The inner sum is the DFT of f(v) f(v - rho ghat) on the grid. The pair
    (rho, -ghat) reuses that transform: its product is the same function
    shifted by rho ghat, so its DFT is e^{i pi rho k.ghat/L} times the first.
    All phase factors are separable per axis and formed on the fly. The loss
    term f(v) L(f)(v) uses the same (rho, ghat) rule,
    G_loss(m) = sum w_rho w_ghat rho^{d-1} F(0, rho, ghat) e^{-i pi rho m.ghat/L},
    so that Qhat_0 = 0 to round-off.

    f may hold a stack of distributions, shape (..., *grid.shape); each gets its own
    Q (and its own E(f)^gamma), all of them in the same transforms: a pipeline's FFT
    call covers every distribution times a block of pairs, and the phase factors and
    angular weights of a pair are formed once for the whole stack.
    """

    name = "fast_spectral"
    #: the values of ``quadrature``
    quadratures = QUADRATURES
    #: Default of ``memory_budget`` when GRANFRAME_MEMORY_BUDGET is not set.
    DEFAULT_MEMORY_BUDGET = 2 ** 31

    def __init__(self, grid, kernel, restitution, backend, *, radial_points=None, sphere=None,
                 sigma=None, quadrature="auto", batch=None, memory_budget=None,
                 precision="float64"):
        super().__init__(grid, kernel, restitution, backend)
        self._options = (radial_points, sphere, sigma, quadrature, batch, memory_budget,
                         precision)
        plan = _plan(grid, kernel, backend, *self._options)
        self.precision, self.quadrature = precision, quadrature
        self._real_dtype, self._complex_dtype = PRECISIONS[precision]
        self._itemsize = numpy.dtype(self._real_dtype).itemsize
        self.radial_points, self.sphere, self.sigma = plan.radial_points, plan.sphere, plan.sigma
        self.memory_bytes = plan.memory_bytes
        self._build(plan)

    @classmethod
    def estimate_memory(cls, grid, kernel, restitution, backend, *, radial_points=None,
                        sphere=None, sigma=None, quadrature="auto", batch=None,
                        memory_budget=None, precision="float64", distributions=1) -> int:
        """Bytes the operator would hold for these arguments, evaluating stacks of
        ``distributions`` distributions, found without allocating.

        Raises the operator's own errors: invalid options, and a ``memory_budget``
        too small for one pair per pipeline (or for the stack).
        """
        check_arguments(cls.name, grid, kernel, restitution, backend)
        if not check.is_integer(distributions) or distributions < 1:
            check.reject(cls.name, "distributions", distributions, "must be an integer >= 1")
        return _plan(grid, kernel, backend, radial_points, sphere, sigma, quadrature, batch,
                     memory_budget, precision, int(distributions)).memory_bytes

    # -- precomputation -------------------------------------------------------------------
    def _build(self, plan):
        grid, kernel, backend = self.grid, self.kernel, self.backend
        xp = backend.xp
        d, n, L = grid.dimension, grid.n_modes, grid.half_width
        total = float(n) ** d
        rho, w_rho = radial_rule(grid, self.radial_points)
        e_rho = self.restitution(rho)
        a_rho = math.pi * rho * (1.0 + e_rho) / (4.0 * L)
        self._rho = rho
        self._a, self._b = a_rho, math.pi * rho / L - a_rho
        radial = w_rho * rho ** (d - 1) * kernel.prefactor(d) * kernel.speed_part(rho)

        reps = plan.reps
        self.n_pairs = len(reps)
        self._reps, self._coef, self._sig, f0_plus, f0_minus = self._angular_terms(plan)

        # Wavenumbers of the half (rfft) layout: axes 0..d-2 in DFT order, last axis 0..N/2.
        self._k_axes = grid.half_wavenumbers()
        half_shape = self._half_shape = grid.half_shape
        kk = numpy.sqrt(grid.half_wavenumber_squared())
        self._keep = xp.asarray(~grid.nyquist_mask())
        self._speed_squared = grid.speed_squared(xp)

        # Radial weights W_rho(k), one rho at a time into the table (no float64 copy of it).
        weights = numpy.empty((len(rho),) + half_shape, dtype=self._complex_dtype)
        for i, (a, w) in enumerate(zip(a_rho, radial)):
            weights[i] = ((w * sphere_area(d)) * isotropic_sphere_average(a * kk, d)
                          if kernel.is_isotropic else w)
        self._radial_weights = xp.asarray(weights)
        del kk, weights

        self._g_loss = xp.asarray(self._loss_multiplier(rho, radial, plan, f0_plus, f0_minus)
                                  / total, dtype=self._complex_dtype)

        # Work split: contiguous ranges of rho values over pipelines; pairs in batches.
        pipelines = plan.pipelines
        self.batch = plan.batch
        self._tables = _PhaseTables(self, plan.precompute_tables)
        self._bounds = numpy.linspace(0, len(rho), pipelines + 1).round().astype(int)
        self._executor = (concurrent.futures.ThreadPoolExecutor(pipelines - 1, "granframe-fast")
                          if pipelines > 1 else None)
        self._stack = None
        self._size_stack(1)

    def _angular_terms(self, plan):
        """The angular terms of each antipodal pair: the coefficients, the sigma parts of the
        phase vector eta = alpha ghat - a sigma (alpha = a for the term of +ghat, b for the
        reused term of -ghat), and the angular integrals of b at +ghat and -ghat."""
        kernel, d = self.kernel, self.grid.dimension
        reps, w_plus, w_minus = plan.reps, plan.w_plus, plan.w_minus
        if kernel.is_isotropic:
            coef = numpy.stack([w_plus, w_minus], axis=1)                     # (P, 2)
            area = numpy.full(len(reps), sphere_area(d))
            return reps, coef, numpy.zeros((1, d)), area, area
        s_nodes, s_weights = self.sigma.nodes(), self.sigma.weights()
        cos_plus = reps @ s_nodes.T                                            # (P, S)
        b_plus = s_weights * kernel.angular_part(cos_plus)
        b_minus = s_weights * kernel.angular_part(-cos_plus)
        coef = numpy.concatenate([w_plus[:, None] * b_plus, w_minus[:, None] * b_minus], axis=1)
        return reps, coef, s_nodes, b_plus.sum(axis=1), b_minus.sum(axis=1)

    def _loss_multiplier(self, rho, radial, plan, f0_plus, f0_minus):
        """N^d G_loss(m) on the half layout, with the same rho and ghat rule as the gain."""
        L = self.grid.half_width
        reps = plan.reps
        g_loss = numpy.zeros(self._half_shape, dtype=complex)
        for r, w in zip(rho, radial):
            for sign, f0 in ((-1.0, plan.w_plus * f0_plus), (1.0, plan.w_minus * f0_minus)):
                factors = [numpy.exp(sign * 1j * math.pi * r / L * numpy.outer(reps[:, i], k))
                           for i, k in enumerate(self._k_axes)]                 # each (P, N_i)
                g_loss += w * _separable_sum(f0, factors)
        return g_loss

    def _size_stack(self, distributions: int):
        """Transforms and buffers for stacks of ``distributions`` (the last size asked
        for is kept); a stack whose buffers exceed the memory budget is refused."""
        if self._stack == distributions:
            return
        grid, backend, d = self.grid, self.backend, self.grid.dimension
        plan = _plan(grid, self.kernel, backend, *self._options, distributions)
        self.memory_bytes = plan.memory_bytes
        self._pipelines = [_Pipeline(self, (int(self._bounds[p]), int(self._bounds[p + 1])),
                                     distributions) for p in range(plan.pipelines)]
        # The operator's own few transforms are single-threaded when pipelines run: FFTW's
        # OpenMP workers keep spinning after a threaded transform and took a core from the
        # pipelines (3D N = 16: 7.8 ms per evaluation instead of 4.3 ms).
        self._fft = backend.real_fft((distributions,) + grid.shape, tuple(range(1, d + 1)),
                                     threads=1 if plan.pipelines > 1 else backend.concurrency,
                                     precision=self.precision)
        # the evaluation's largest host temporaries: a pipeline's FFT outputs and weighted
        # spectra per call of its transforms, and the stack's own spectra
        grids = self._pipelines[0].chunk * self._pipelines[0].batch
        per_grid = (self._itemsize * grid.n_modes ** d
                    + 4 * self._itemsize * math.prod(self._half_shape))
        _settle_host_allocator(backend.xp, 2 * max(grids, distributions) * per_grid)
        self._stack = distributions

    def stack_transforms(self, distributions: int) -> int:
        """Grids transformed per FFT call of a pipeline for a stack of D = ``distributions``:
        C p with C = min(D, max(1, batch // P)) distributions per chunk (P pairs per rho,
        C evened out over the stack) and p = max(1, batch // C) pairs per block (a
        multiple of P when it is at least P)."""
        return _stack_transforms(self.batch, self.n_pairs, distributions)

    @property
    def transform_pairs(self) -> int:
        """Number of (rho, ghat) pairs that need a forward + inverse transform."""
        return len(self._rho) * self.n_pairs

    # -- evaluation -----------------------------------------------------------------------
    def __call__(self, f):
        r"""Q_I(f_b, f_b) on the grid for each distribution f_b of f (see the class notes
        for the discrete formula); f of shape (..., *grid.shape), Q of f's shape."""
        stack, batch_shape = check_operands(self.name, self.grid, f, self.backend)
        count = stack.shape[0]
        self._size_stack(count)
        fft = self._fft
        fft.real[...] = stack
        spectrum = fft.forward() * self._keep                      # Nyquist-free DFT of f
        fft.spectrum[...] = spectrum
        inverse_count = 1.0 / float(self.grid.n_modes) ** self.grid.dimension
        f_n = fft.inverse() * inverse_count
        if self._executor is None:
            gain = self._pipelines[0].run(spectrum, f_n)
        else:
            # one BLAS thread per pipeline: a threaded BLAS called from both pipelines at
            # once contends for its own pool and made evaluation 2.5x slower (N = 64, 3D).
            # The calling thread runs the first pipeline itself and wakes one worker per
            # other pipeline: a caller that waited instead had both workers woken at once,
            # and the scheduler stacked them on one core whenever no core was idle at the
            # wake-up (the slow mode of docs/benchmarks.md, "Thread placement")
            with _BLAS.limit(limits=1, user_api="blas"):
                others = [self._executor.submit(p.run, spectrum, f_n)
                          for p in self._pipelines[1:]]
                gain = self._pipelines[0].run(spectrum, f_n)
                for part in others:
                    gain += part.result()
        # loss: f_N(v) L(f)(v) with L(f) = IDFT(G_loss * DFT(f))
        fft.spectrum[...] = spectrum * self._g_loss
        fft.real[...] = f_n * fft.inverse()
        total = gain - fft.forward()
        total *= self._keep
        fft.spectrum[...] = total
        factors = energy_factor(self.kernel, self.grid.cell_volume, self._speed_squared, f_n,
                                self.backend)
        if factors is None:
            # a Python float keeps float32 results in float32 (NumPy's scalar promotion)
            q = fft.inverse() * float(inverse_count)
        else:
            scale = (factors * inverse_count).astype(self._real_dtype)
            q = fft.inverse() * scale.reshape((count,) + (1,) * self.grid.dimension)
        return q.reshape(batch_shape + self.grid.shape)

    def close(self):
        """Stop the worker threads (also done when the operator is garbage collected)."""
        executor = getattr(self, "_executor", None)
        if executor is not None:
            executor.shutdown(wait=False)
            self._executor = None

    __del__ = close


@attrs.frozen
class _Plan:
    """The validated options of a fast operator, its work split and its memory."""

    radial_points: int
    sphere: SurfaceQuadrature
    sigma: SurfaceQuadrature
    reps: numpy.ndarray = attrs.field(eq=False)
    w_plus: numpy.ndarray = attrs.field(eq=False)
    w_minus: numpy.ndarray = attrs.field(eq=False)
    pipelines: int
    batch: int
    precompute_tables: bool
    memory_bytes: int


def _checked_options(grid, radial_points, sphere, sigma, quadrature, batch, memory_budget,
                     precision) -> tuple:
    """The operator's options checked, each refused by name, with the defaults of the
    ``quadrature`` preset and of the memory budget filled in: (radial_points, sphere,
    sigma, memory_budget)."""
    owner, d = "fast_spectral", grid.dimension
    if not isinstance(quadrature, str) or quadrature not in QUADRATURES:
        check.reject(owner, "quadrature", quadrature, f"must be one of {list(QUADRATURES)}")
    default_radial, default_sphere, default_sigma = default_quadratures(grid, quadrature)
    radial_points = default_radial if radial_points is None else radial_points
    if not check.is_integer(radial_points) or not 1 <= radial_points <= MAX_GAUSS_POINTS:
        check.reject(owner, "radial_points", radial_points,
                     f"must be an integer >= 1 and <= {MAX_GAUSS_POINTS}")
    sphere = default_sphere if sphere is None else sphere
    sigma = default_sigma if sigma is None else sigma
    for name, rule in (("sphere", sphere), ("sigma", sigma)):
        if not isinstance(rule, SurfaceQuadrature) or rule.dimension != d:
            check.reject(owner, name, rule, f"must be a quadrature on S^{d - 1} "
                         f"({'circle' if d == 2 else 'sphere'} rule)", error=TypeError)
    if batch is not None and (not check.is_integer(batch) or batch < 1):
        check.reject(owner, "batch", batch, "must be None or an integer >= 1")
    if memory_budget is None:
        memory_budget = memory.budget(FastSpectral.DEFAULT_MEMORY_BUDGET)
    if not check.is_integer(memory_budget) or memory_budget <= 0:
        check.reject(owner, "memory_budget", memory_budget, "must be a positive number of bytes")
    if precision not in PRECISIONS:
        check.reject(owner, "precision", precision, f"must be one of {list(PRECISIONS)}")
    return radial_points, sphere, sigma, memory_budget


def _plan(grid, kernel, backend, radial_points, sphere, sigma, quadrature, batch,
          memory_budget, precision, distributions=1) -> _Plan:
    """Validate the options and size everything the operator will allocate for stacks of
    D = ``distributions`` distributions.

    Counted, in bytes (r and c the real and complex item sizes, h the points of the half
    spectrum, N_rho radial points, P pairs): the radial weights, loss multiplier,
    accumulators and the operator's own transform, c h (N_rho + 4 + 2 pipelines), of
    which c h (3 + 2 pipelines) again for each further distribution; per grid of a
    pipeline's transform (:func:`_stack_transforms` of them), a real grid, its spectrum
    and the weighted spectrum of the generic ``lowrank_accumulate``, r N^d + 2 c h; the
    phase tables, precomputed when
    they fit in a quarter of the budget, else one block per pipeline; and the transients
    of the precomputation (|k|, the loss multiplier and its terms), 56 h. The pair batch
    (for D = 1) shrinks until the tables and buffers fit ``memory_budget``; what still
    does not fit is refused here, before anything of the grid's size is allocated (a
    stack, D > 1, that does not fit is refused naming ``f``).
    """
    owner, d = "fast_spectral", grid.dimension
    radial_points, sphere, sigma, memory_budget = _checked_options(
        grid, radial_points, sphere, sigma, quadrature, batch, memory_budget, precision)
    real = numpy.dtype(PRECISIONS[precision][0]).itemsize
    complex_ = 2 * real
    radial_points, budget = int(radial_points), int(memory_budget)
    reps, w_plus, w_minus = antipodal_pairs(sphere.nodes(), sphere.weights())
    n_pairs = len(reps)
    terms = 2 if kernel.is_isotropic else 2 * sigma.n_points
    half_shape = grid.half_shape
    half, total = math.prod(half_shape), grid.n_modes ** d
    pipelines = max(1, min(backend.concurrency, radial_points))
    fixed = complex_ * half * (radial_points + 4 + 2 * pipelines)
    per_distribution = complex_ * half * (3 + 2 * pipelines)
    table_per_pair = complex_ * (half_shape[0] + half // half_shape[0]) * (1 + terms)
    precompute, tables, per_pair = _tables_placed(
        table_per_pair, radial_points * n_pairs, real * total + 2 * complex_ * half, budget)
    if batch is None:
        batch = _default_batch(complex_ * half, n_pairs, _ceil_div(radial_points, pipelines),
                               backend.batch_bytes)
    weights_gib = memory.gib(complex_ * half * radial_points)
    if fixed + tables + pipelines * batch * per_pair > budget:
        batch = (budget - fixed - tables) // (pipelines * per_pair)
        if batch < 1:
            check.reject(owner, "memory_budget", memory_budget,
                         f"is too small: one pair per pipeline needs "
                         f"{memory.gib(fixed + tables + pipelines * per_pair)} GiB (d = {d}, "
                         f"N = {grid.n_modes}); use a smaller N, fewer radial_points (the "
                         f"radial weights take {weights_gib} GiB), or raise memory_budget")
    steady = fixed + tables + pipelines * batch * per_pair
    if not precompute:      # a block holds the pairs of whole rho values
        steady += pipelines * max(0, n_pairs - batch) * table_per_pair
    memory_bytes = steady + 56 * half + _stack_bytes(
        grid, int(batch), n_pairs, distributions, pipelines, per_distribution, per_pair,
        steady + 56 * half, budget)
    if memory_bytes > budget:
        check.reject(owner, "memory_budget", memory_budget,
                     f"is too small: the operator needs {memory.gib(memory_bytes)} GiB (d = {d}, "
                     f"N = {grid.n_modes}); use a smaller N, fewer radial_points (the "
                     f"radial weights take {weights_gib} GiB), or raise memory_budget")
    return _Plan(radial_points, sphere, sigma, reps, w_plus, w_minus, pipelines, int(batch),
                 precompute, int(memory_bytes))


def _tables_placed(table_per_pair: int, pairs: int, per_pair: int, budget: int) -> tuple:
    """Whether the phase tables of all ``pairs`` (rho, pair) are precomputed (when they fit
    in a quarter of the budget), the bytes they take, and the bytes per pair of a batch: a
    pipeline that forms the tables of its block of pairs holds them per pair."""
    tables = table_per_pair * pairs
    if tables <= budget // 4:
        return True, tables, per_pair
    return False, 0, per_pair + table_per_pair


def _stack_bytes(grid, batch: int, n_pairs: int, distributions: int, pipelines: int,
                 per_distribution: int, per_pair: int, single: int, budget: int) -> int:
    """What a stack of D = ``distributions`` distributions needs beyond one (``single``
    bytes): ``per_distribution`` for each further one and the further grids of every
    pipeline's transform (:func:`_stack_transforms`); a stack over ``budget`` is refused
    naming ``f``."""
    if distributions <= 1:
        return 0
    grids = _stack_transforms(batch, n_pairs, distributions)
    extra = (distributions - 1) * per_distribution + pipelines * (grids - batch) * per_pair
    if single + extra > budget:
        check.reject("fast_spectral", "f", f"a stack of {distributions} distributions",
                     f"is too large: it needs {memory.gib(single + extra)} GiB, over the "
                     f"memory_budget of {memory.gib(budget)} GiB (d = {grid.dimension}, "
                     f"N = {grid.n_modes}); evaluate smaller stacks, or raise memory_budget")
    return extra


_BLAS = threadpoolctl.ThreadpoolController()

#: glibc's ceiling on its dynamic mmap threshold (mallopt(3): 4 Mi longs, 32 MiB on 64-bit)
_MMAP_THRESHOLD_MAX = 32 * 2 ** 20


def _settle_host_allocator(xp, nbytes: int) -> None:
    """Allocate and free one host block of ``nbytes`` (at most 32 MiB) at once.

    glibc's malloc maps fresh pages for a request above its mmap threshold and unmaps them
    on free, and trims its heaps when more than twice that threshold lies free at the top;
    freeing a mapped block raises both thresholds to its size (mallopt(3), "dynamic mmap
    threshold"). An evaluation frees and allocates its large temporaries (pocketfft's
    outputs, the generic backend's weighted spectra) at every batch, so with low
    thresholds each call faulted fresh pages in: on the NumPy backend 18461 page faults
    per evaluation at 3D N = 32 with one thread (72 MiB, 50-60 ms of system time), 4256
    at 3D N = 16 with two, where the code before stacks (whose precomputation happened
    to free a large float64 table) had 2212 and none; with the thresholds raised here,
    none in every configuration. Nothing is touched (no page of the block is written);
    other allocators and device arrays are unaffected.
    """
    if xp is numpy and nbytes > 0:
        numpy.empty(min(int(nbytes), _MMAP_THRESHOLD_MAX), dtype=numpy.uint8)


def _default_batch(spectrum_bytes: int, n_pairs: int, rho_per_pipeline: int,
                   batch_bytes: int) -> int:
    """Pairs per batch for about ``batch_bytes`` of spectra (the backend's
    :attr:`~granframe.abc.ArrayBackend.batch_bytes`).

    When the pairs of one rho fit, a batch holds whole rho values and a pipeline's
    ``rho_per_pipeline`` values are split into equal blocks, so that no batch transforms
    padding. Otherwise the pairs of one rho are split into as few batches as the aim allows,
    of equal size (padding below one pair per batch).
    """
    batch = max(1, batch_bytes // spectrum_bytes)
    if batch >= n_pairs:
        rhos = min(batch // n_pairs, rho_per_pipeline)
        return _ceil_div(rho_per_pipeline, _ceil_div(rho_per_pipeline, rhos)) * n_pairs
    return _ceil_div(n_pairs, _ceil_div(n_pairs, batch))


def _stack_layout(batch: int, n_pairs: int, distributions: int) -> tuple[int, int]:
    """(C, p): distributions per chunk and pairs per block of one pipeline FFT call.

    C = min(D, max(1, batch // P)) (P pairs per rho), evened out over the chunks of the
    stack: a block holds at least the P pairs of one rho for each distribution of its
    chunk where ``batch`` allows, so that the chunk's spectra and accumulators stay in
    cache over the block. Stacking more distributions per call cuts only the Python
    overhead per call, and cost more in memory traffic than it saved (3D N = 32, batch 8:
    52.6 ms per distribution for stacks of 64 in chunks of 8, 46.4 ms one at a time).
    p = max(1, batch // C), a multiple of P when it is at least P, so that no grid of a
    call is padding while the pairs of whole rho values are transformed.
    """
    chunk = min(distributions, max(1, batch // n_pairs))
    chunk = _ceil_div(distributions, _ceil_div(distributions, chunk))
    block = max(1, batch // chunk)
    if block >= n_pairs:
        block -= block % n_pairs
    return chunk, block


def _stack_transforms(batch: int, n_pairs: int, distributions: int) -> int:
    """Grids per FFT call for a stack: C p of :func:`_stack_layout`."""
    chunk, block = _stack_layout(batch, n_pairs, distributions)
    return chunk * block


def _ceil_div(a: int, b: int) -> int:
    """ceil(a / b) for positive integers."""
    return -(-a // b)


def _separable_sum(coef, factors):
    """sum_p coef_p prod_i factors_i[p, k_i] on the tensor grid (k_0, ..., k_{d-1})."""
    d = len(factors)
    tail = factors[-1] * coef[:, None]
    for f in reversed(factors[1:-1]):
        tail = (f[:, :, None] * tail[:, None, :]).reshape(len(coef), -1)
    result = factors[0].T @ tail
    return result.reshape(tuple(fa.shape[1] for fa in factors)) if d > 1 else result


class _PhaseTables:
    """Separable phase factors of every (rho, ghat) pair, per rho.

    For rho values ``rhos`` it returns, over all pairs,
    ``shift_head`` (q, P, N0) and ``shift_tail`` (q, P, rest): the factors of
    e^{-i pi rho k.ghat/L} / N^d along axis 0 and over the other axes, and
    ``angular_head`` (q, P, N0, T), ``angular_tail`` (q, P, T, rest): the
    factors of the pair's T angular terms c_t e^{i eta_t.k}. They depend on
    the grid and quadrature only, so they are precomputed when they fit in a
    quarter of the memory budget and otherwise formed once per rho block.
    """

    def __init__(self, op: FastSpectral, precompute: bool):
        xp = op.backend.xp
        self.op, self.xp = op, xp
        self.k = [xp.asarray(k) for k in op._k_axes]
        self.reps = xp.asarray(op._reps)
        self.coef = xp.asarray(op._coef)
        self.sig = xp.asarray(op._sig)
        self.rho, self.a, self.b = (xp.asarray(v) for v in (op._rho, op._a, op._b))
        self._all = self.compute(slice(0, len(op._rho))) if precompute else None

    def __call__(self, rhos: slice):
        if self._all is not None:
            return tuple(t[rhos] for t in self._all)
        return self.compute(rhos)

    def _phases(self, eta, axis):
        """exp(i eta[..., axis] k_axis), shape eta.shape[:-1] + (len(k_axis),)."""
        return self.xp.exp(1j * eta[..., axis, None] * self.k[axis])

    def _tail(self, eta):
        """Separable factor over axes 1..d-1, shape eta.shape[:-1] + (prod(half_shape[1:]),)."""
        d = eta.shape[-1]
        tail = self._phases(eta, d - 1)
        for axis in range(d - 2, 0, -1):
            tail = (self._phases(eta, axis)[..., :, None] * tail[..., None, :]).reshape(
                eta.shape[:-1] + (-1,))
        return tail

    def compute(self, rhos: slice):
        op, xp = self.op, self.xp
        d, L = op.grid.dimension, op.grid.half_width
        inverse_count = 1.0 / float(op.grid.n_modes) ** d
        g = self.reps[None]                                                    # (1, P, d)
        shift = -math.pi / L * self.rho[rhos, None, None] * g                   # (q, P, d)
        shift_head = self._phases(shift, 0) * inverse_count
        shift_tail = self._tail(shift)
        # angular terms: eta = alpha ghat - a sigma, alpha = a (+ghat) or b (reused -ghat)
        a = self.a[rhos, None, None, None]
        b = self.b[rhos, None, None, None]
        g4 = g[:, :, None, :]
        eta = xp.concatenate([a * g4 - a * self.sig, b * g4 - a * self.sig], axis=2)
        angular_head = (self._phases(eta, 0) * self.coef[None, :, :, None]).transpose(0, 1, 3, 2)
        tables = shift_head, shift_tail, angular_head, self._tail(eta)
        return tuple(xp.ascontiguousarray(t, dtype=op._complex_dtype) for t in tables)


class _Pipeline:
    """One worker's transforms and buffers; sums the gain over its rho values.

    For a stack of D distributions f_d and per block of pairs (rho, +-ghat) it forms
    X_d = DFT(f_d) e^{-i pi rho k.ghat/L} (the separable phase as the product of its
    axis-0 factor and the factor over the other axes, formed once for all d,
    :meth:`ArrayBackend.separable_product`), s_d = IDFT(X_d) f_{N,d}, P_d = DFT(s_d), and
    adds E * P_d to the accumulator of its rho and distribution, where
    E = sum_t c_t e^{i eta_t.k} is the sum of the pair's separable angular terms
    (:meth:`ArrayBackend.lowrank_accumulate`). The stack goes in chunks of
    C distributions and the C x p grids of a chunk and a block of p pairs go through one
    FFT call (:func:`_stack_layout`).
    """

    def __init__(self, op: FastSpectral, rho_range, distributions: int):
        backend, grid = op.backend, op.grid
        self.op, self.rho_range, self.distributions = op, rho_range, distributions
        d = grid.dimension
        self.chunk, self.batch = _stack_layout(op.batch, op.n_pairs, distributions)
        self.fft = backend.real_fft((self.chunk * self.batch,) + grid.shape,
                                    tuple(range(1, d + 1)), threads=1, precision=op.precision)
        self._n0, self._rest = op._half_shape[0], int(numpy.prod(op._half_shape[1:]))
        self.radial_weights = op._radial_weights.reshape(-1, self._n0, self._rest)

    def run(self, spectrum, f_n):
        op, backend = self.op, self.op.backend
        xp = backend.xp
        n0, rest, dists = self._n0, self._rest, self.distributions
        gain = xp.zeros((dists, n0, rest), dtype=op._complex_dtype)
        spec2 = spectrum.reshape(dists, n0, rest)
        f_n = f_n[:, None]                                 # (D, 1, *grid.shape)
        grid_shape = op.grid.shape
        n_pairs = op.n_pairs
        # blocks of q rho values x p pairs: all pairs of several rho at once (small grids),
        # or a few pairs of one rho (large grids)
        p = min(self.batch, n_pairs)
        q = max(1, self.batch // n_pairs)
        r_first, r_last = self.rho_range
        for r0 in range(r_first, r_last, q):
            rhos = slice(r0, min(r0 + q, r_last))
            nq = rhos.stop - rhos.start
            shift_head, shift_tail, angular_head, angular_tail = op._tables(rhos)
            acc = xp.zeros((dists, nq, n0, rest), dtype=op._complex_dtype)
            for c0 in range(0, dists, self.chunk):
                chunk = slice(c0, min(c0 + self.chunk, dists))
                nc = chunk.stop - chunk.start
                for start in range(0, n_pairs, p):
                    pairs = slice(start, min(start + p, n_pairs))
                    count = nq * (pairs.stop - pairs.start)
                    used = nc * count           # the first C x count grids of the buffers
                    # s = f(v - rho ghat) f_N(v): shift the spectra, transform, multiply
                    backend.separable_product(
                        self.fft.spectrum[:used].reshape(nc, count, n0, rest), spec2[chunk],
                        shift_head[:, pairs].reshape(count, n0),
                        shift_tail[:, pairs].reshape(count, rest))
                    # s f_N written straight into the forward transform's input: one pass, in
                    # place where the inverse returned that buffer (FFTW), else no extra copy
                    real = self.fft.real
                    xp.multiply(self.fft.inverse()[:used].reshape((nc, count) + grid_shape),
                                f_n[chunk], out=real[:used].reshape((nc, count) + grid_shape))
                    if used < len(real):
                        real[used:] = 0.0
                    p_hat = self.fft.forward()[:used].reshape(nc, count, n0, rest)
                    backend.lowrank_accumulate(acc[chunk],
                                               angular_head[:, pairs].reshape(count, n0, -1),
                                               angular_tail[:, pairs].reshape(count, -1, rest),
                                               p_hat)
            acc *= self.radial_weights[rhos]
            gain += acc[:, 0] if nq == 1 else acc.sum(axis=1)
        return gain.reshape((dists,) + op._half_shape)
