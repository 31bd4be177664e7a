r"""A collisionless particle simulation of a piston that really oscillates: the independent
reference for the vibrating wall's boundary condition (:mod:`granframe.space.vibration`,
docs/space.md "Vibrating walls").

The piston is at X(t) = A sin(omega t) and moves with U(t) = A omega cos(omega t); the gas
is at x > X(t). Particles arrive from a gas at rest at temperature T: the normal speed of
the flux-weighted half-range Maxwellian (a Rayleigh variable), the tangential components
Gaussian, at the height A (the piston's highest point; above it nothing happens) at a time
uniform over a period. Each is followed in time, on steps of a 256th of a period, with
its position against the piston's checked after every step and the hit found by bisection,
until it rises above A moving away. A hit sends it back from the piston's frame: diffuse,
with the normal speed of the flux-weighted Maxwellian at T_w and Gaussian tangential
components; or specular, v_1 -> 2U - v_1. Nothing here shares code with the spectral
solver or with the layer's phase functions.

The heating is measured with common random numbers: every particle draws its emissions
in advance, and the estimate is the mean over particles of what it leaves with minus what
the same draws would leave with from a piston at rest (its first emission, or its mirror
image), plus the exact mean of the latter; the variance is then that of the vibration's
share only.
"""

from __future__ import annotations

import math

import numpy

#: time steps per period of the collision search
STEPS = 256

#: emissions drawn per particle (a diffuse particle is caught again with probability
#: about V^2 / (4 T_w) per hit)
EMISSIONS = 24


def oscillating_piston(count: int, amplitude: float, frequency: float, *, reflection: str,
                       wall_temperature: float = 1.0, gas_temperature: float = 1.0,
                       dimension: int = 2, seed: int = 0) -> dict:
    """Send ``count`` particles at the piston and return what they leave with.

    Returns a dict: ``incoming`` and ``outgoing`` velocities (count, dimension) (v_1 the
    normal, > 0 away from the piston), ``resting`` the velocities the same draws leave a
    piston at rest with, ``hits`` per particle, and ``heating`` / ``heating_error``: the
    mean energy per arriving particle that the vibration adds to what a resting piston
    sends back, and its standard error.
    """
    if reflection not in ("diffuse", "specular"):
        raise ValueError(f"oscillating_piston: parameter 'reflection' = {reflection!r} is "
                         "invalid; must be 'diffuse' or 'specular'")
    rng = numpy.random.default_rng(seed)
    A, omega = float(amplitude), float(frequency)
    period = 2.0 * math.pi / omega
    sigma, sigma_w = math.sqrt(gas_temperature), math.sqrt(wall_temperature)
    incoming = rng.normal(0.0, sigma, (count, dimension))
    incoming[:, 0] = -sigma * numpy.sqrt(-2.0 * numpy.log1p(-rng.random(count)))
    emission = rng.normal(0.0, sigma_w, (count, EMISSIONS, dimension))
    emission[:, :, 0] = sigma_w * numpy.sqrt(-2.0 * numpy.log1p(-rng.random((count, EMISSIONS))))

    t = rng.random(count) * period                       # arrival at height A
    x = numpy.full(count, A)
    v = incoming.copy()
    hits = numpy.zeros(count, dtype=int)
    active = numpy.ones(count, dtype=bool)
    dt = period / STEPS

    def wall(time):
        return A * numpy.sin(omega * time)

    while active.any():
        i = numpy.nonzero(active)[0]
        t0, x0, v0 = t[i], x[i], v[i, 0]
        t1 = t0 + dt
        gap = x0 + v0 * dt - wall(t1)
        hit = gap <= 0.0
        escaped = ~hit & (x0 + v0 * dt >= A) & (v0 > 0.0)
        moving = ~hit & ~escaped
        t[i[moving]], x[i[moving]] = t1[moving], x0[moving] + v0[moving] * dt
        active[i[escaped]] = False
        j = i[hit]
        if j.size:
            lo, hi = t[j].copy(), t1[hit]
            xs, vs, start = x[j], v[j, 0], t[j].copy()
            for _ in range(50):
                mid = 0.5 * (lo + hi)
                below = xs + vs * (mid - start) - wall(mid) <= 0.0
                hi, lo = numpy.where(below, mid, hi), numpy.where(below, lo, mid)
            tc = hi
            u = A * omega * numpy.cos(omega * tc)
            if reflection == "diffuse":
                k = numpy.minimum(hits[j], EMISSIONS - 1)
                v[j] = emission[j, k]
                v[j, 0] += u
            else:
                v[j, 0] = 2.0 * u - v[j, 0]
            t[j], x[j] = tc, wall(tc)
            hits[j] += 1
    if numpy.any(hits > EMISSIONS) and reflection == "diffuse":
        raise RuntimeError("oscillating_piston: a particle was caught more often than it drew "
                           "emissions")
    if reflection == "diffuse":
        resting = emission[:, 0].copy()
        resting_energy = 0.5 * (dimension + 1) * wall_temperature
    else:
        resting = incoming * numpy.r_[-1.0, numpy.ones(dimension - 1)]
        resting_energy = 0.5 * (dimension + 1) * gas_temperature
    share = 0.5 * ((v * v).sum(axis=1) - (resting * resting).sum(axis=1))
    return {"incoming": incoming, "outgoing": v, "resting": resting, "hits": hits,
            "heating": float(share.mean()),
            "heating_error": float(share.std(ddof=1) / math.sqrt(count)),
            "resting_energy": resting_energy}
