"""Fused element-wise kernels (numba) for :class:`granframe_fftw.PyFFTWBackend`.

They implement :meth:`granframe.backends.ArrayBackend.separable_product` and
:meth:`~granframe.backends.ArrayBackend.lowrank_accumulate` in one pass over
memory each, where NumPy needs three to four (a temporary per operation).
They release the GIL, so the fast operator's pipelines run them side by
side. Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import numba
import numpy

# fastmath only where it speeds the loops up (fused multiply-add, reassociation): no
# no-NaN/no-Inf assumptions, so a NaN still reaches the runner's health check (measured:
# same speed as fastmath=True, 3D N = 32)
_JIT = {"nogil": True, "fastmath": {"contract", "reassoc"}, "cache": True}


@numba.njit(**_JIT)
def separable_product(out, spectrum, head, tail):
    """out[b, i, j] = spectrum[i, j] head[b, i] tail[b, j]."""
    batch, rows, cols = out.shape
    for b in range(batch):
        for i in range(rows):
            h = head[b, i]
            for j in range(cols):
                out[b, i, j] = spectrum[i, j] * (h * tail[b, j])
    return out


@numba.njit(**_JIT)
def _accumulate_rank2(acc, heads, tails, values):
    """Rank-2 case of :func:`lowrank_accumulate`, the weight formed on the fly."""
    batch, rows, cols = values.shape
    per_group = batch // acc.shape[0]
    for b in range(batch):
        q = b // per_group
        for i in range(rows):
            h0 = heads[b, i, 0]
            h1 = heads[b, i, 1]
            for j in range(cols):
                acc[q, i, j] += (h0 * tails[b, 0, j] + h1 * tails[b, 1, j]) * values[b, i, j]
    return acc


@numba.njit(**_JIT)
def _accumulate_dense(acc, heads, tails, values):
    """Any rank: the weight of each batch entry by one BLAS product, then a fused update."""
    batch, rows, cols = values.shape
    per_group = batch // acc.shape[0]
    for b in range(batch):
        q = b // per_group
        weight = numpy.dot(heads[b], tails[b])
        for i in range(rows):
            for j in range(cols):
                acc[q, i, j] += weight[i, j] * values[b, i, j]
    return acc


def lowrank_accumulate(acc, heads, tails, values):
    """acc[q, i, j] += sum_{b in q} (sum_t heads[b, i, t] tails[b, t, j]) values[b, i, j].

    The rank-2 weights of isotropic kernels (a pair and its antipode) are
    formed on the fly; larger ranks (a sigma rule for anisotropic b) go
    through BLAS.
    """
    if heads.shape[2] == 2:
        return _accumulate_rank2(acc, heads, tails, values)
    return _accumulate_dense(acc, numpy.ascontiguousarray(heads),
                             numpy.ascontiguousarray(tails), values)
