"""Cell averages: of profiles that are smooth between known break points, and of fine
fields onto coarser cells through their conserved quantities."""

from __future__ import annotations

import numpy

from granframe import validators as check


def gauss_cell_averages(edges, function, breaks, points: int):
    r"""Averages over the cells [e_i, e_{i+1}] of a function smooth between ``breaks``.

    Each cell is split at the breaks inside it and each piece [a, b] gets the
    ``points``-point Gauss-Legendre rule (Abramowitz & Stegun, Handbook of Mathematical
    Functions, 25.4.29),

    .. math:: \frac{1}{e_{i+1} - e_i}\sum_{\text{pieces}} \frac{b - a}{2}
              \sum_k w_k\, F\Bigl(\frac{a + b}{2} + \frac{b - a}{2}\,\xi_k\Bigr),

    exact for polynomials of degree 2 points - 1 on every piece.

    Parameters
    ----------
    edges : array_like
        Strictly increasing cell edges, 1-D (not checked here: the callers check them,
        :func:`granframe.validators.cell_edges`).
    function : callable
        F(x): maps a 1-D array of n positions to an array of shape (n, ...).
    breaks : array_like
        Positions where F may have a kink or a jump (any shape; those outside the cells
        are ignored).
    points : int
        Gauss-Legendre points per piece.

    Returns
    -------
    numpy.ndarray
        Shape ``(len(edges) - 1, ...)``.
    """
    edges = numpy.asarray(edges, dtype=float)
    breaks = numpy.asarray(breaks, dtype=float).ravel()
    inner = breaks[(breaks > edges[0]) & (breaks < edges[-1])]
    nodes = numpy.unique(numpy.concatenate([edges, inner]))
    left, right = nodes[:-1], nodes[1:]
    abscissae, weights = numpy.polynomial.legendre.leggauss(points)
    half = 0.5 * (right - left)
    x = (0.5 * (left + right))[:, None] + half[:, None] * abscissae[None, :]
    values = numpy.asarray(function(x.ravel()), dtype=float)
    values = values.reshape(x.shape + values.shape[1:])
    scale = (half[:, None] * weights[None, :]).reshape(x.shape + (1,) * (values.ndim - 2))
    pieces = numpy.sum(values * scale, axis=1)
    starts = numpy.searchsorted(left, edges[:-1])
    widths = numpy.diff(edges).reshape((-1,) + (1,) * (pieces.ndim - 1))
    return numpy.add.reduceat(pieces, starts, axis=0) / widths


def conserved_block_average(fields: dict, cells: int, dimension: int) -> dict:
    r"""Fields on R x R cells averaged onto ``cells`` x ``cells`` (R a multiple of it)
    through the conserved quantities: rho, rho u and E = rho |u|^2/2 + d rho T/2 are averaged
    over each block of (R/cells)^2 cells, then u = <rho u>/<rho> and
    T = (<E> - <rho> |u|^2/2) / (d <rho>/2), d the velocity ``dimension``.

    Parameters
    ----------
    fields : dict
        ``rho``, ``u1``, ``u2``, ``T``, each (R, R).
    cells : int
        The coarse cells per axis, dividing R.
    dimension : int
        d of the velocities (T is per velocity dimension).

    Returns
    -------
    dict
        ``rho``, ``u1``, ``u2``, ``T``, each (cells, cells).
    """
    size = fields["rho"].shape[0]
    if cells < 1 or size % cells:
        check.reject("conserved_block_average", "cells", cells,
                     f"must divide the fields' {size} cells per axis")
    k = size // cells

    def mean(a):
        return numpy.asarray(a).reshape(cells, k, cells, k).mean(axis=(1, 3))

    rho = numpy.asarray(fields["rho"])
    half = 0.5 * dimension
    r = mean(rho)
    u1, u2 = mean(rho * fields["u1"]) / r, mean(rho * fields["u2"]) / r
    energy = mean(rho * (fields["u1"] ** 2 + fields["u2"] ** 2) / 2 + half * rho * fields["T"])
    return {"rho": r, "u1": u1, "u2": u2, "T": (energy - r * (u1 ** 2 + u2 ** 2) / 2) / (half * r)}
