"""Quantities the studies extract from runs: relative entropy, decay rates, tail exponents,
the energy budget of a space run with walls."""

from __future__ import annotations

import numpy


def relative_entropy(f, g, cell_volume):
    """H(f|g) = int f ln(f/g) dv over the points where both are positive (rectangle rule)."""
    mask = (f > 0) & (g > 0)
    return float(numpy.sum(f[mask] * numpy.log(f[mask] / g[mask]))) * cell_volume


def fit_line(x, y):
    """Least-squares y = a + b x; returns (b, a, standard error of b)."""
    x, y = numpy.asarray(x, float), numpy.asarray(y, float)
    if len(x) < 3:
        raise ValueError(f"fit: needs at least 3 points, got {len(x)}")
    design = numpy.stack([numpy.ones_like(x), x], axis=1)
    (a, b), residual, _, _ = numpy.linalg.lstsq(design, y, rcond=None)
    dof = len(x) - 2
    sigma2 = float(residual[0]) / dof if dof > 0 and len(residual) else 0.0
    stderr = (sigma2 / float(((x - x.mean()) ** 2).sum())) ** 0.5
    return float(b), float(a), stderr


def exponential_rate(times, values, window):
    """Fit values ~ C exp(-lambda t) over ``window`` = (t_min, t_max); returns (lambda, stderr)."""
    times, values = numpy.asarray(times), numpy.asarray(values)
    use = (times >= window[0]) & (times <= window[1]) & (values > 0)
    slope, _, stderr = fit_line(times[use], numpy.log(values[use]))
    return -slope, stderr


def tail_exponent(speed, f, window):
    r"""Fit f ~ C exp(-c |v|^alpha) over ``window`` = (v_min, v_max) of |v|.

    ln(-ln(f / C)) is linear in ln|v| with slope alpha, but C is unknown; so the fit
    is made on d ln f / d|v| = -c alpha |v|^{alpha-1}: ln(-d ln f/d|v|) against ln|v|
    has slope alpha - 1. Returns (alpha, stderr).
    """
    speed, f = numpy.asarray(speed, float), numpy.asarray(f, float)
    keep = f > 0
    # points at the same |v| (both sides of a slice, equal up to round-off) are merged:
    # their mean ln f
    speed, inverse = numpy.unique(numpy.round(speed[keep], 9), return_inverse=True)
    log_f = numpy.bincount(inverse, numpy.log(f[keep])) / numpy.bincount(inverse)
    middle = 0.5 * (speed[1:] + speed[:-1])
    slope = numpy.diff(log_f) / numpy.diff(speed)
    use = (middle >= window[0]) & (middle <= window[1]) & (slope < 0)
    b, _, stderr = fit_line(numpy.log(middle[use]), numpy.log(-slope[use]))
    return b + 1.0, stderr


def energy_balance(ds, operator, knudsen: float, window: float = 0.2,
                   length: float = 1.0) -> dict:
    r"""The energy budget of a space run with walls at its last step.

    ``ds``: the run's dataset with the steps as its time axis (``f``, ``dt``,
    ``wall_energy``, ``kinetic_energy``); ``operator``: the run's collision operator
    (``operator.grid`` its velocity grid); ``length``: the interval's.

    ``heat``: what both walls put in per unit time, sum_walls wall_energy / dt (the last
    step; ``heat_window``: averaged over the last ``window`` of the steps);
    ``dissipation``: sum_cells dx h^d sum_j Q_j |v_j|^2 / 2 / eps of the final snapshot,
    Q the run's operator; ``dEdt``: the change of the total energy over the last step / dt.
    Every step E^{n+1} - E^n = (wall energy) + (collision step's energy change), so
    ``mismatch`` = (heat + dissipation)/heat equals dEdt/heat (``unsteadiness``) plus
    ``residual`` = (heat + dissipation - dEdt)/heat, the collision step's energy change
    against its rate at the end of the step (splitting and time error, O(dt)).
    """
    f = ds.f.values[-1]
    grid = operator.grid
    dx = length / ds.sizes["x"]
    q = numpy.asarray(operator(f))
    dissipation = float(numpy.sum(q * grid.speed_squared()) * grid.cell_volume
                        * 0.5 * dx / knudsen)
    dt = ds.dt.values[1:]
    heat_rate = ds.wall_energy.values[1:].sum(axis=1) / dt
    count = max(1, int(window * len(heat_rate)))
    energy = ds.kinetic_energy.values
    heat = float(heat_rate[-1])
    dEdt = float((energy[-1] - energy[-2]) / dt[-1])
    return {"heat": heat, "heat_window": float(heat_rate[-count:].mean()),
            "dissipation": dissipation, "dEdt": dEdt,
            "mismatch": (heat + dissipation) / heat, "unsteadiness": dEdt / heat,
            "residual": (heat + dissipation - dEdt) / heat}
