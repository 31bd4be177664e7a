r"""A wall vibrating along its normal in the limit of small amplitude: the collisionless
layer it sweeps, and the boundary condition that layer makes (docs/space.md, "Vibrating
walls").

The wall is at X(t) = A sin(omega t) (the gas at x > X) and moves with U = V cos(omega t),
V = A omega. In the limit A -> 0 at fixed V (A small against the mean free path and the
cell, the period 2 pi / omega short against the time the gas near the wall takes to
change) the layer 0 < x - X < 2A holds no collisions and a vanishing share of the gas;
what crosses its top is a steady flux, so a particle enters it at a phase uniform over
the period. In the variables phase theta = omega t, height x / A and speed v / V the
wall is the curve sin(theta) and a particle a straight line; nothing depends on A. So the
limit is a boundary condition that does not depend on time: an arriving particle of
normal speed a V leaves, after one or several hits, with a speed b V drawn from a kernel
that depends on a, on V and on what a hit does (diffuse or specular).

Two functions of the phase describe the layer (both in units where the wall's height and
speed are sin and cos):

- the *escape slope* :func:`escape_slope`, S(theta) = sup_{u>0} (sin(theta + u) - sin
  theta) / u: a particle that leaves the wall at phase theta with lab slope c is caught by
  the wall again iff c < S(theta) (the line from (theta, sin theta) then meets the curve
  again before it rises above the wall's highest point), first at the phase where the
  chord slope (sin(theta + u) - sin theta) / u first reaches c;
- the *visible speed* a_min(theta) = S(pi - theta) (the reflection theta -> pi - theta
  reverses time): a particle arriving with speed a hits the wall first at phase theta
  iff a > a_min(theta); the density of first hits in theta is then
  p_a(theta) = (a + cos theta) / a (the relative speed over the arriving one), zero
  otherwise, and (1 / 2 pi) int p_a = 1 for every a (:func:`first_hit_density`).

A diffuse wall sends a hit particle back from its own frame with the normal speed w of
the flux-weighted Maxwellian at T_w, density h(w) = (w / T_w) exp(-w^2 / (2 T_w)), and a
tangential velocity from the Maxwellian at T_w. The density r(theta) of all hits
(first hits and catches of what the wall itself sent back) solves
r = p_a + Q r, Q the catch kernel (:meth:`Layer.catches`); what escapes has the lab speed
b = V cos theta + w >= V S(theta), so its flux density in b is

.. math:: g(b \mid a) = \frac{1}{2\pi} \int_0^{2\pi} r(\theta)\, h(b - V\cos\theta)\,
          \mathbf 1[b \ge V S(\theta)]\, d\theta.

A specular wall reverses the relative normal velocity, c -> 2 cos theta - c (in units of
V), and keeps the tangential one; a particle bounces until c >= S(theta).

Every phase integral is the midpoint rule on :data:`PHASES` phases, exact for the
trigonometric polynomials the fast particles see.
"""

from __future__ import annotations

import functools
import math

import numpy

#: the phases of the midpoint rule over a period
PHASES = 512

#: the points per period of the chord slopes' search (catch phases, escape slopes)
SEARCH = 2048

#: a particle is followed for this many periods after leaving the wall (a catch comes
#: within 1.5 periods: the wall reaches its highest point once a period)
HORIZON = 1.5

#: the most hits a specular particle is followed for. Most leave after one or two; a
#: particle caught near a tangency can ride the receding wall in a chain of grazing hits,
#: and what is still caught after these (below 1e-7 of the arriving flux at V = 0.1 on
#: 512 phases; more than 1e-6 is refused) leaves with the escape slope
BOUNCES = 64


def phases(count: int = PHASES):
    """The midpoints theta_m = (m + 1/2) 2 pi / count of the periodic midpoint rule."""
    return (numpy.arange(count) + 0.5) * (2.0 * math.pi / count)


def _search_points():
    """u on (0, :data:`HORIZON` periods], :data:`SEARCH` points a period: where the chord
    slopes are searched."""
    return numpy.linspace(0.0, 2.0 * math.pi * HORIZON, int(SEARCH * HORIZON) + 1)[1:]


def _chord_slopes(theta, u):
    """(sin(theta + u) - sin(theta)) / u, theta (..., 1), u (n,), by the difference
    formula 2 cos(theta + u/2) sin(u/2) / u (no cancellation at small u)."""
    return 2.0 * numpy.cos(theta + 0.5 * u) * numpy.sin(0.5 * u) / u


def escape_slope(theta):
    r"""S(theta) = sup_{u > 0} (sin(theta + u) - sin(theta)) / u, the slowest lab slope
    (speed / V) at which a particle leaving the wall at phase theta is never caught again.

    The supremum is cos(theta) (u -> 0) or a tangency cos(theta + u) = S(theta) within
    :data:`HORIZON` periods; it is searched on :data:`SEARCH` points a period and refined
    by Newton's method on the tangency, u cos(theta + u) - (sin(theta + u) - sin(theta))
    = 0, to round-off. S >= 0, and S(theta) = cos(theta) where the tangent at theta stays
    above the wall (the wall then decelerates away from the particle for good).
    """
    theta = numpy.asarray(theta, dtype=float)
    flat = theta.reshape(-1, 1)
    u = _search_points()
    slopes = _chord_slopes(flat, u)
    best = slopes.argmax(axis=1)
    s = u[best]
    th = flat[:, 0]
    for _ in range(40):
        top = th + s
        g = s * numpy.cos(top) - (numpy.sin(top) - numpy.sin(th))
        dg = -s * numpy.sin(top)
        step = numpy.divide(g, dg, out=numpy.zeros_like(g), where=numpy.abs(dg) > 1e-300)
        s = numpy.clip(s - step, u[0] * 1e-3, u[-1])
    refined = _chord_slopes(th, s)
    value = numpy.maximum(numpy.maximum(refined, slopes.max(axis=1)), numpy.cos(th))
    return value.reshape(theta.shape)


def first_hit_density(a, theta):
    r"""p_a(theta) = (a + cos theta) / a where a > a_min(theta) = S(pi - theta), else 0:
    the density over the phase (per d theta / 2 pi) of the first hit of a particle
    arriving at the layer with normal speed a V, a > 0 (shape of a broadcast against
    theta)."""
    a = numpy.asarray(a, dtype=float)
    visible = a > escape_slope(math.pi - numpy.asarray(theta, dtype=float))
    return numpy.where(visible, (a + numpy.cos(theta)) / a, 0.0)


def _first_crossing(theta, c):
    """The smallest u in (0, HORIZON periods] with chord slope (sin(theta + u) - sin theta)
    / u >= c, for c in (cos theta, S(theta)): found on the search points, then bisected
    to round-off (the slope at the point before is below c)."""
    u = _search_points()
    theta, c = numpy.asarray(theta, dtype=float), numpy.asarray(c, dtype=float)
    above = _chord_slopes(theta[:, None], u) >= c[:, None]
    k = numpy.argmax(above, axis=1)
    hi = u[k]
    lo = numpy.where(k > 0, u[numpy.maximum(k - 1, 0)], 0.0)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        ok = _chord_slopes(theta, numpy.maximum(mid, 1e-300)) >= c
        hi, lo = numpy.where(ok, mid, hi), numpy.where(ok, lo, mid)
    return hi


class Layer:
    r"""The collisionless layer of a wall vibrating with speed amplitude V at temperature
    T_w, on :data:`PHASES` phases (module notes). Host NumPy; made once per wall.

    Parameters
    ----------
    speed : float
        V = A omega > 0.
    temperature : float
        T_w > 0 (used by the diffuse wall).
    count : int
        Phases of the midpoint rule.
    """

    def __init__(self, speed: float, temperature: float, count: int = PHASES):
        self.speed, self.temperature, self.count = float(speed), float(temperature), count
        self.theta = phases(count)
        self.slope = escape_slope(self.theta)

    def _caught_probability(self, w):
        """H(w) = 1 - exp(-w^2 V^2 / (2 T_w)): the probability that the diffuse wall sends a
        particle back with a normal speed below w V in its own frame."""
        return -numpy.expm1(-(w * self.speed) ** 2 / (2.0 * self.temperature))

    @functools.cached_property
    def catches(self):
        r"""Q (count, count): Q[m, k] the probability that a particle sent back by the
        diffuse wall at phase theta_k is caught again at a phase in the bin of theta_m.

        A particle leaving at theta_k with lab slope c (= cos theta_k + w) is caught where
        the running maximum R(u) of the chord slope first exceeds c; so the slopes in
        (R(u_{n-1}), R(u_n)] are caught at u_n, with the probability
        H(R(u_n) - cos theta_k) - H(R(u_{n-1}) - cos theta_k), shared linearly between the
        two phases next to theta_k + u_n (mod 2 pi).
        """
        n, step = self.count, 2.0 * math.pi / self.count
        u = _search_points()
        q = numpy.zeros((n, n))
        for k, th in enumerate(self.theta):
            running = numpy.maximum.accumulate(
                numpy.maximum(_chord_slopes(th, u), math.cos(th)))
            levels = self._caught_probability(numpy.concatenate(([0.0], running - math.cos(th))))
            mass = numpy.diff(levels)
            where = numpy.nonzero(mass > 0)[0]
            position = ((th + u[where]) / step - 0.5) % n
            low = numpy.floor(position).astype(int)
            share = position - low
            numpy.add.at(q[:, k], low % n, mass[where] * (1.0 - share))
            numpy.add.at(q[:, k], (low + 1) % n, mass[where] * share)
        return q

    def hits(self, a):
        r"""r (count, len(a)): the density of all hits over the phase for particles arriving
        with speeds a V, r = p_a + Q r (:meth:`catches`), solved directly."""
        p = first_hit_density(numpy.asarray(a, dtype=float)[None, :], self.theta[:, None])
        return numpy.linalg.solve(numpy.eye(self.count) - self.catches, p)

    def diffuse_escape(self, b, a):
        r"""g(b | a) (len(b), len(a)): the flux density, per unit lab speed, of what leaves
        the layer of a diffuse wall with normal speed b (dimensional, >= 0) for particles
        arriving with normal speed a (dimensional, > 0); module notes."""
        V, T = self.speed, self.temperature
        b = numpy.asarray(b, dtype=float)
        w = b[:, None] - V * numpy.cos(self.theta)[None, :]
        h = numpy.where(w > 0, w / T * numpy.exp(-numpy.maximum(w, 0.0) ** 2 / (2.0 * T)), 0.0)
        h = h * (b[:, None] >= V * self.slope[None, :])
        return h @ self.hits(numpy.asarray(a, dtype=float) / V) / self.count

    def specular_escape(self, a):
        r"""(b, weight), each (count, len(a)): the lab speeds (dimensional) with which
        particles arriving with speeds a (dimensional) leave a specular wall after all
        their bounces, one for each phase of a first hit, and the weights p_a(theta_m) /
        count of those phases (summing to 1 up to the midpoint rule's error at the
        visibility edges)."""
        V = self.speed
        a = numpy.asarray(a, dtype=float) / V
        theta = numpy.broadcast_to(self.theta[:, None], (self.count, a.size)).copy()
        weight = first_hit_density(a[None, :], self.theta[:, None]) / self.count
        c = 2.0 * numpy.cos(theta) + a[None, :]
        slope = numpy.broadcast_to(self.slope[:, None], theta.shape).copy()
        caught = (c < slope) & (weight > 0)
        for _ in range(BOUNCES):
            if not caught.any():
                break
            u = _first_crossing(theta[caught], c[caught])
            theta[caught] = (theta[caught] + u) % (2.0 * math.pi)
            c[caught] = 2.0 * numpy.cos(theta[caught]) - c[caught]
            slope[caught] = escape_slope(theta[caught])
            caught &= c < slope
        stuck = float((weight * caught).sum())
        if stuck > 1e-6 * float(weight.sum()):
            raise RuntimeError(f"Layer: {stuck:.3g} of the arriving flux was still caught after "
                               f"{BOUNCES} bounces")
        c = numpy.where(caught, slope, c)
        return c * V, weight
