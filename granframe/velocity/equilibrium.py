r"""Discrete Maxwellians: the equilibria of the velocity grid with given grid moments.

For the moments of a distribution f on the nodes v_j of a velocity grid (cell volume
h^d),

.. math:: \rho = h^d \sum_j f_j,\qquad J = h^d \sum_j v_j f_j,\qquad
          S = h^d \sum_j |v_j|^2 f_j,

the discrete Maxwellian is the grid function

.. math:: \mathcal M_j = \exp\bigl(a + b\cdot v_j + c\,|v_j|^2\bigr)

whose grid moments are exactly (rho, J, S). Its parameters are the minimiser of the
strictly convex function h^d sum_j exp(a + b.v_j + c|v_j|^2) - (a rho + b.J + c S) (the
discrete entropy's dual), found by Newton's method from the continuum Maxwellian of the
same rho, u = J/rho and T = (S - |J|^2/rho)/(d rho). The exponent is a sum over the axes,
so M is a product of one-dimensional factors g_i(v) = exp(b_i v + c v^2) and every moment
the iteration needs (up to |v|^4) is a product of their one-dimensional moments: an
iteration costs O(d N) per distribution, not O(N^d). M is positive by construction.

This is the equilibrium of discrete-velocity models [Mieussens, Math. Models Methods
Appl. Sci. 10 (2000) 1121-1149, section 3]; its exact moments make the BGK penalisation
r (M[f] - f) of the asymptotic-preserving schemes conserve mass, momentum and energy to
round-off on the grid, which the continuum Maxwellian sampled on the grid does only to the
grid's quadrature error [Filbet & Jin, J. Comput. Phys. 229 (2010) 7625-7648].
"""

from __future__ import annotations

import numpy

#: Newton iterations from the continuum Maxwellian: the residual falls quadratically, to
#: round-off in 3 to 5 on resolved grids, and the damped start of far-off data takes a few
#: more; the count is fixed, so that no value crosses from the device to the host
ITERATIONS = 12
#: added to the diagonal-scaled Hessian (unit diagonal): keeps a distribution that has
#: collapsed onto one node solvable without changing a converged step
_REGULAR = 1e-14
#: the step lengths of the line search: 1, 1/2, ..., 2^-9 (21 lengths converged on no more
#: of 180 Maxwellians, T = 0.005 to 60 on three grids, and cost twice the time)
_SEARCH = 10
#: the largest relative residual of the moments accepted as converged
RESIDUAL_TOLERANCE = 1e-10


def _axis_moments(points, b, c, xp):
    r"""The normalised one-dimensional factors p_i(v) = g_i(v) / sum_v g_i, g_i(v) =
    exp(b_i v + c v^2), and their moments <v^k>_i = sum_v v^k p_i(v), k = 1..4, for every
    distribution and axis (the largest exponent is taken out first, so nothing
    overflows). ``b`` (n, d), ``c`` (n,); returns (n, d, N) and (n, d, 4)."""
    exponent = b[:, :, None] * points + c[:, None, None] * (points * points)
    factor = xp.exp(exponent - exponent.max(axis=2, keepdims=True))
    factor = factor / factor.sum(axis=2, keepdims=True)
    mean = xp.stack([(factor * points ** k).sum(axis=2) for k in range(1, 5)], axis=2)
    return factor, mean


def _objective(points, beta, target, xp):
    r"""The convex objective sum_i log sum_v exp(b_i v + c v^2) - (b, c) . (J, S)/rho of
    every distribution and candidate: ``beta`` (n, k, d+1), ``target`` (n, d+1) -> (n, k).
    Its gradient is <phi> - target, zero at the discrete Maxwellian."""
    d = beta.shape[2] - 1
    exponent = beta[:, :, :d, None] * points + beta[:, :, d, None, None] * (points * points)
    top = exponent.max(axis=3)
    log_total = xp.log(xp.exp(exponent - top[..., None]).sum(axis=3)) + top
    return log_total.sum(axis=2) - (beta * target[:, None, :]).sum(axis=2)


def _moments(mean, xp):
    r"""<phi> (n, d+1) and Cov(phi) (n, d+1, d+1) of the product measure whose axes have the
    moments ``mean`` (n, d, 4) of v, v^2, v^3, v^4, for phi = (v_1, ..., v_d, |v|^2):

    .. math:: \langle v_i v_j\rangle = \langle v_i\rangle\langle v_j\rangle\ (i \ne j),
              \quad \langle v_i |v|^2\rangle = \langle v_i^3\rangle + \langle v_i\rangle
              \sum_{k \ne i}\langle v_k^2\rangle,\quad
              \langle |v|^4\rangle = \sum_i \langle v_i^4\rangle
              + \sum_{i \ne k}\langle v_i^2\rangle\langle v_k^2\rangle.
    """
    d = mean.shape[1]
    m1, m2, m3, m4 = (mean[:, :, k] for k in range(4))
    square = m2.sum(axis=1)
    phi = xp.concatenate([m1, square[:, None]], axis=1)
    rows = []
    for p in range(d + 1):
        row = []
        for q in range(d + 1):
            if p < d and q < d:
                row.append(m2[:, p] - m1[:, p] * m1[:, p] if p == q else m1[:, p] * 0.0)
            elif p < d or q < d:
                i = min(p, q)
                row.append(m3[:, i] + m1[:, i] * (square - m2[:, i]) - m1[:, i] * square)
            else:
                row.append((m4 - m2 * m2).sum(axis=1))
        rows.append(xp.stack(row, axis=1))
    return phi, xp.stack(rows, axis=1)


def discrete_maxwellians(grid, density, momentum, second, xp=numpy, points=None):
    r"""The discrete Maxwellians (see the module notes) with grid mass ``density`` (n,),
    momentum ``momentum`` (n, d) and second moment ``second`` = h^d sum |v|^2 f (n,).

    The mass is exact at every iterate (a is eliminated: e^a = rho / (h^d prod_i sum_v
    g_i)); Newton's method runs on (b, c), whose gradient and Hessian are rho <phi> - (J, S)
    and rho Cov(phi), in the variables w = v / L (L the grid's half width) and with the
    Hessian scaled by its diagonal.

    Parameters
    ----------
    grid : VelocityGrid
    density, momentum, second : arrays in ``xp``
        The grid moments of each distribution (the momentum with the node -L at -L, the
        grid's own convention, in which the collision operator conserves it).
    xp : module
        The array namespace; nothing crosses to the host.
    points : array, optional
        The grid's one-dimensional nodes already in ``xp``.

    Returns
    -------
    maxwellians : array (n, *grid.shape)
        Positive, with exactly the grid mass ``density``, and the momentum and second
        moment to round-off where ``converged``.
    converged : boolean array (n,)
        The moments are realisable (rho > 0, T > 0, all finite) and the Newton residual is
        at most :data:`RESIDUAL_TOLERANCE` relative to rho and S; elsewhere M is not an
        equilibrium of f and must not be used as one.
    """
    d = grid.dimension
    points = xp.asarray(grid.points()) if points is None else points
    scale = float(grid.half_width)
    w = points / scale                                         # the nodes in [-1, 1)
    with numpy.errstate(divide="ignore", invalid="ignore", over="ignore"):
        valid, rho, target, beta = _start(density, momentum / scale,
                                          second / (scale * scale), d, xp)
        identity = xp.eye(d + 1)[None]
        lengths = 0.5 ** xp.arange(float(_SEARCH))
        for _ in range(ITERATIONS):
            beta = _newton_step(w, beta, target, identity, lengths, xp)
        factors, mean = _axis_moments(w, beta[:, :d], beta[:, d], xp)
        phi, _ = _moments(mean, xp)
        residual = xp.abs(phi - target).max(axis=1) / target[:, -1]
    converged = valid & (residual <= RESIDUAL_TOLERANCE)
    return _product(factors, rho / grid.cell_volume, d), converged


def _start(density, j, s, d: int, xp):
    """Where the moments (mass ``density``, momentum ``j`` and second moment ``s`` in the
    variables w = v / L) are realisable (``valid``), the mass (1 elsewhere), the Newton
    target (u, |u|^2 + d T) and the first iterate (u / T, -1 / (2T)): the continuous
    Maxwellian's; elsewhere a standard target (u = 0, T = 0.05 L^2) that keeps the iteration
    finite."""
    temperature = (s - (j * j).sum(axis=1) / density) / (d * density)
    valid = (xp.isfinite(density) & (density > 0) & xp.isfinite(temperature)
             & (temperature > 0) & xp.all(xp.isfinite(j), axis=1))
    rho = xp.where(valid, density, 1.0)
    u = xp.where(valid[:, None], j / rho[:, None], 0.0)
    t = xp.where(valid, temperature, 0.05)
    target = xp.concatenate([u, ((u * u).sum(axis=1) + d * t)[:, None]], axis=1)
    beta = xp.concatenate([u / t[:, None], (-0.5 / t)[:, None]], axis=1)
    return valid, rho, target, beta


def _newton_step(w, beta, target, identity, lengths, xp):
    """One Newton step on (b, c) with the Hessian scaled by its diagonal, and a line search
    over ``lengths`` (all candidate lengths at once) on the convex objective."""
    d = beta.shape[1] - 1
    _, mean = _axis_moments(w, beta[:, :d], beta[:, d], xp)
    phi, covariance = _moments(mean, xp)
    scaling = xp.sqrt(xp.diagonal(covariance, axis1=1, axis2=2)) + 1e-150
    scaled = covariance / (scaling[:, :, None] * scaling[:, None, :])
    scaled = xp.where(xp.isfinite(scaled), scaled, 0.0) + _REGULAR * identity
    gradient = (phi - target) / scaling
    step = xp.linalg.solve(scaled, gradient[:, :, None])[:, :, 0]
    candidates = beta[:, None, :] - lengths[:, None] * (step / scaling)[:, None, :]
    objective = _objective(w, candidates, target, xp)
    objective = xp.where(xp.isfinite(objective), objective, xp.inf)
    lowest = objective.min(axis=1)
    # the full step unless a shorter one is lower beyond round-off (near the minimum the
    # objective's differences are below its round-off)
    full = objective[:, 0] <= lowest + 1e-13 * (1.0 + xp.abs(lowest))
    best = xp.where(full, 0, xp.argmin(objective, axis=1))
    beta = xp.take_along_axis(candidates, best[:, None, None], axis=1)[:, 0]
    return xp.where(xp.isfinite(beta), beta, 0.0)


def _product(factors, amplitude, d: int):
    """amplitude_n prod_i factors_{n,i}(v_i): the separable Maxwellians (n, *grid.shape)."""
    n = factors.shape[0]
    result = None
    for i in range(d):
        shape = [n] + [1] * d
        shape[1 + i] = -1
        factor = factors[:, i].reshape(shape)
        result = factor if result is None else result * factor
    return result * amplitude.reshape((n,) + (1,) * d)
