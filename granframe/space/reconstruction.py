r"""Reconstructions of face values from cell averages along x (axis 0).

Cell j holds the average f_j over [x_{j-1/2}, x_{j+1/2}]; a reconstruction returns at every
face the value seen from the left cell (f^-) and from the right cell (f^+), and the transport
takes the upwind one (:class:`granframe.abc.Reconstruction`). Every operation acts on axis 0
and is element-wise over the trailing (velocity) axes, in the array namespace ``xp``
(numpy or cupy); nothing loops over cells.

Three schemes:

- :class:`Upwind`: piecewise constant, first order (Toro 2009, ch. 5).
- :class:`MUSCL`: piecewise linear with a limited slope, second order away from extrema
  (van Leer 1979; Toro 2009, ch. 13).
- :class:`WENO5`: weighted essentially non-oscillatory, fifth order on smooth data
  (Jiang & Shu 1996; Borges et al. 2008 for the WENO-Z weights).

References: B. van Leer, J. Comput. Phys. 32 (1979) 101-136; A. Harten, J. Comput. Phys. 49
(1983) 357-393; G.-S. Jiang & C.-W. Shu, J. Comput. Phys. 126 (1996) 202-228;
R. Borges, M. Carmona, B. Costa & W. S. Don, J. Comput. Phys. 227 (2008) 3191-3211;
S. Gottlieb, C.-W. Shu & E. Tadmor, SIAM Rev. 43 (2001) 89-112; R. Wang & R. J. Spiteri,
SIAM J. Numer. Anal. 45 (2007) 1871-1901; E. F. Toro, Riemann Solvers and Numerical Methods
for Fluid Dynamics, 3rd ed., 2009.
"""

from __future__ import annotations

import attrs

from granframe import validators as check
from granframe.abc import Reconstruction


@attrs.frozen
class Upwind(Reconstruction):
    r"""Piecewise-constant reconstruction: f^-_{j+1/2} = f_j, f^+_{j-1/2} = f_j.

    With the upwind flux this is the first-order upwind (Godunov) scheme. One forward Euler
    step is monotone for Courant numbers nu = max|c| dt/dx <= 1 (f^{n+1}_j is a convex
    combination of f^n_{j-1}, f^n_j, f^n_{j+1}); the three-stage SSP Runge-Kutta method is a
    convex combination of forward Euler steps (SSP coefficient 1, Gottlieb, Shu & Tadmor
    2001), so the transport sub-step is monotone, TVD and positivity preserving for
    ``cfl = 1``.

    The returned face values are views of ``f`` (no copy).
    """

    ghost = 1
    order = 1
    cfl = 1.0

    def faces(self, f, xp):
        return f[:-1], f[1:]


_LIMITERS = ("minmod", "van_leer", "mc")


@attrs.frozen
class MUSCL(Reconstruction):
    r"""Piecewise-linear reconstruction with a limited slope (MUSCL).

    With a = f_j - f_{j-1} and b = f_{j+1} - f_j, the slope sigma_j (per cell width) is

    - ``"minmod"``:   sigma = minmod(a, b),
    - ``"van_leer"``: sigma = 2ab/(a + b) if ab > 0, else 0 (harmonic mean),
    - ``"mc"``:       sigma = minmod(2a, (a + b)/2, 2b) (monotonised central),

    where minmod is the argument of least modulus if all have one sign and 0 otherwise, and
    f^-_{j+1/2} = f_j + sigma_j/2, f^+_{j-1/2} = f_j - sigma_j/2 [van Leer 1979; Toro 2009,
    ch. 13]. The default ``"mc"`` takes the central slope (a + b)/2 wherever it is within
    a factor 2 of both one-sided ones, i.e. everywhere on well-resolved smooth data away
    from extrema; it has the smallest error of the three there (face values of the
    averages of sin(2 pi x) on 40 cells, L1: mc 3.41e-3, van Leer 3.42e-3, minmod 8.09e-3).

    Courant limit. All three slopes satisfy Harten's conditions
    0 <= sigma_j / a <= 2 and 0 <= sigma_j / b <= 2 (sigma_j = 0 if ab <= 0). For c > 0 one
    forward Euler step of the upwind flux reads
    f^{n+1}_j = f_j - nu C_{j-1/2} (f_j - f_{j-1}) with
    C_{j-1/2} = 1 + (sigma_j/a_j - sigma_{j-1}/b_{j-1})/2 in [0, 2], a_j = b_{j-1}
    = f_j - f_{j-1}; by Harten's lemma (Harten 1983) it is TVD when 0 <= nu C <= 1, i.e. for
    nu <= 1/2 (and symmetrically for c < 0). The three-stage SSP Runge-Kutta method has SSP
    coefficient 1 (Gottlieb, Shu & Tadmor 2001), so ``cfl = 1/2`` for every limiter. The
    face values lie between the neighbouring cell averages (to 2 ulp of rounding; the
    bound 0 exactly), so the sub-step also keeps f >= 0. (minmod, with sigma_j/a in
    [0, 1], allows nu <= 2/3; 1/2 is kept for all.)

    Parameters
    ----------
    limiter : {"minmod", "van_leer", "mc"}
        The slope limiter; "mc" by default.
    """

    limiter: str = attrs.field(default="mc", validator=check.one_of(_LIMITERS))

    ghost = 2
    order = 2
    cfl = 0.5

    def faces(self, f, xp):
        diff = f[1:] - f[:-1]            # diff[i] = f_{i+1} - f_i
        size = xp.abs(diff)
        sign = xp.sign(diff, out=diff)
        same = sign[:-1] + sign[1:]      # 2, -2 if a, b agree in sign, else 0 or +-1
        del diff, sign
        a, b = size[:-1], size[1:]       # |a|, |b| of the cells 1 .. n + 2
        if self.limiter == "minmod":
            slope = xp.minimum(a, b)
        elif self.limiter == "van_leer":
            # 2|a||b|/(|a| + |b|) = 2m/(1 + m/M), m = min, M = max: no underflow of |a||b|
            small = xp.minimum(a, b)
            large = xp.maximum(a, b)
            xp.maximum(large, xp.finfo(f.dtype).tiny, out=large)
            slope = 2.0 * small / (1.0 + small / large)
        else:
            slope = xp.minimum(a, b)
            slope *= 2.0
            xp.minimum(slope, 0.5 * (a + b), out=slope)
        slope *= same
        slope *= 0.25                    # sigma/2 = same/2 * |sigma| / 2
        return f[1:-2] + slope[:-1], f[2:-1] - slope[1:]


_WEIGHTS = ("js", "z")


@attrs.frozen
class WENO5(Reconstruction):
    r"""Fifth-order WENO reconstruction [Jiang & Shu 1996; Borges et al. 2008].

    Face value from cell j at x_{j+1/2}: f^- = sum_k w_k q_k with the third-order candidates

        q_0 = (2 f_{j-2} - 7 f_{j-1} + 11 f_j)/6,  q_1 = (-f_{j-1} + 5 f_j + 2 f_{j+1})/6,
        q_2 = (2 f_j + 5 f_{j+1} - f_{j+2})/6,

    linear weights d = (1/10, 6/10, 3/10) (with which sum d_k q_k is the fifth-order
    value, exact for the averages of polynomials of degree 4), smoothness indicators

        beta_0 = 13/12 (f_{j-2} - 2 f_{j-1} + f_j)^2 + 1/4 (f_{j-2} - 4 f_{j-1} + 3 f_j)^2,
        beta_1 = 13/12 (f_{j-1} - 2 f_j + f_{j+1})^2 + 1/4 (f_{j-1} - f_{j+1})^2,
        beta_2 = 13/12 (f_j - 2 f_{j+1} + f_{j+2})^2 + 1/4 (3 f_j - 4 f_{j+1} + f_{j+2})^2,

    and w_k = alpha_k / sum alpha, with

    - ``"js"``: alpha_k = d_k / (eps + beta_k)^2 (Jiang & Shu 1996),
    - ``"z"``:  alpha_k = d_k (1 + (tau_5/(eps + beta_k))^2), tau_5 = |beta_0 - beta_2|
      (Borges et al. 2008, with the power 2 on the ratio, as in the
      Jiang-Shu weights).

    The value at x_{j-1/2} from cell j (f^+) is the mirror image (f_{j+m} -> f_{j-m}).

    Scale-invariant epsilon. The data are distribution values from 1e-300 to 1, so an
    absolute eps (Jiang & Shu's 1e-6) would switch every stencil to the linear weights where
    f << 1e-3 (no non-oscillatory property at a jump in the tails) and decide by amplitude
    rather than shape. Here eps is relative to the stencil: the indicators are computed
    from f / s_j, s_j = max(|f_{j-2}|, ..., |f_{j+2}|, tiny) (tiny the smallest normal float,
    the floor for an all-zero stencil), i.e. eps_j = eps s_j^2 in the formulas above, with
    eps = 1e-6 for "js" and 1e-40 for "z". One s_j serves all three stencils of cell j, so
    the weights are those of Jiang & Shu's scheme with a locally constant eps: they are
    invariant under f -> lambda f (the same fifth order on smooth data of amplitude 1 and
    1e-12), and dividing before squaring keeps every indicator below 43 without
    underflow, down to subnormal f. A jump inside a stencil gives beta_k / s_j^2 = O(1),
    far above eps, so the weights drop that stencil whatever the amplitude.

    With eps = 1e-6 (``"js"``), a jump smaller than about sqrt(eps) = 1e-3 of the local
    magnitude counts as smooth: a step from 1 to 1.001 gets face values up to 5.5% of the
    step beyond it (5.5e-5 of f); steps of relative size >= 1 stay within 3e-13 of the
    step (``"z"``, with its eps = 1e-40, within round-off in both cases).

    Courant limit. WENO is neither TVD nor positivity preserving. On smooth data it is the
    fifth-order upwind-biased linear scheme; with the upwind flux and the three-stage SSP
    Runge-Kutta method the von Neumann amplification factor R(z) = 1 + z + z^2/2 + z^3/6 of
    that scheme satisfies |R| <= 1 for nu <= 1.43 (Wang & Spiteri 2007; recomputed on 4001
    wavenumbers). Near jumps the weights favour the third-order candidates, of which the
    fully upwind q_0 alone is (weakly) unstable with this time stepping at every nu, and
    the nonlinear scheme degrades well before 1.43: a square wave on 100 cells advected
    over 20 periods with the "js" weights grows its total variation by 1.0e-3, 2.6e-3,
    2.1e-2 at nu = 0.4, 0.5, 0.8, goes below zero by at most 6e-9, and at nu = 1 is smeared
    (L1 error x 3, undershoot 4e-4). ``cfl = 1/2`` is the limit kept, as for
    :class:`MUSCL`.

    Parameters
    ----------
    weights : {"js", "z"}
        Nonlinear weights: WENO-Z ("z", the default: on the data above its face errors
        on smooth data are 6 times smaller than Jiang-Shu's, it keeps a jump to round-off
        and grows a square wave's total variation by 5e-6 at nu = 1/2 against 2.6e-3)
        or Jiang-Shu ("js").
    """

    weights: str = attrs.field(default="z", validator=check.one_of(_WEIGHTS))

    ghost = 3
    order = 5
    cfl = 0.5

    def faces(self, f, xp):
        # Windows m = (f_m, f_{m+1}, f_{m+2}): second difference and centred difference.
        curve = f[:-2] - 2.0 * f[1:-1] + f[2:]
        slope = f[2:] - f[:-2]
        # Cells j = 2 .. n + 3 (k = j - 2) read the windows j - 2, j - 1, j.
        cells = f.shape[0] - 4
        windows = [slice(i, i + cells) for i in range(3)]
        beta = _smoothness(curve, slope, _inverse_scale(f, xp), windows)
        self._nonlinear_weights(beta, xp)
        # q_k - f_j in window quantities: f^- takes (7 curve + 3 slope, curve + 3 slope,
        # -5 curve + 3 slope)/12 on the windows j-2, j-1, j with d = (1, 6, 3)/10; f^+ the
        # mirror image (slope -> -slope, d reversed over the windows).
        sides = (((7.0, 3.0, 0.1), (1.0, 3.0, 0.6), (-5.0, 3.0, 0.3)),
                 ((-5.0, -3.0, 0.3), (1.0, -3.0, 0.6), (7.0, -3.0, 0.1)))
        scratch = xp.empty_like(beta[0])
        term = xp.empty_like(beta[0])
        minus, plus = (_face_value(f, curve, slope, beta, windows, side, scratch, term, xp)
                       for side in sides)
        return minus[:-1], plus[1:]

    def _nonlinear_weights(self, beta, xp) -> None:
        """beta_k -> the unnormalised weight of stencil k, in place: 1/(eps + beta_k)^2
        (Jiang-Shu) or 1 + (tau/(eps + beta_k))^2 (WENO-Z)."""
        if self.weights == "js":
            for b in beta:
                b += 1e-6
                b *= b
                xp.divide(1.0, b, out=b)
            return
        tau = xp.abs(beta[0] - beta[2])
        for b in beta:
            b += 1e-40
            xp.divide(tau, b, out=b)
            b *= b
            b += 1.0


def _inverse_scale(f, xp):
    """1/s_j, s_j = max(|f_{j-2}|, ..., |f_{j+2}|, tiny) for the cells j = 2 .. n + 3."""
    size = xp.abs(f)
    pair = xp.maximum(size[:-1], size[1:])
    inverse = xp.maximum(pair[:-3], pair[2:-1])
    del pair
    xp.maximum(inverse, size[4:], out=inverse)
    del size
    xp.maximum(inverse, xp.finfo(f.dtype).tiny, out=inverse)
    xp.divide(1.0, inverse, out=inverse)
    return inverse


def _smoothness(curve, slope, inverse, windows) -> list:
    """The indicators beta_0 (window j-2, 2 curve + slope), beta_1 (j-1, slope) and beta_2
    (j, 2 curve - slope) of f / s_j: 13/12 c^2 + 1/4 s^2."""
    beta = []
    for window, lean in zip(windows, (1.0, 0.0, -1.0)):
        c = curve[window] * inverse
        s = slope[window] * inverse
        if lean:
            s *= lean
            s += c
            s += c
        c *= c
        c *= 13.0 / 12.0
        s *= s
        s *= 0.25
        c += s
        beta.append(c)
    return beta


def _face_value(f, curve, slope, beta, windows, side, scratch, term, xp):
    """f_j + sum_k alpha_k (q_k - f_j) / sum_k alpha_k on one side of every cell, alpha_k
    = d_k w_k with ``side`` the (curve, slope, d) coefficients of the three stencils."""
    value = xp.zeros_like(beta[0])
    total = xp.zeros_like(beta[0])
    for b, window, (kc, ks, d) in zip(beta, windows, side):
        xp.multiply(curve[window], kc, out=term)
        xp.multiply(slope[window], ks, out=scratch)
        term += scratch                          # 12 (q_k - f_j)
        xp.multiply(b, d, out=scratch)           # alpha_k
        total += scratch
        term *= scratch
        value += term
    value /= total
    value *= 1.0 / 12.0
    value += f[2:-2]
    return value


#: the reconstructions by name
RECONSTRUCTIONS = {"upwind": Upwind, "muscl": MUSCL, "weno5": WENO5}
