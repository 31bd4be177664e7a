"""Fused element-wise kernels (numba) for :class:`granframe_fftw.PyFFTWBackend`.

They implement :meth:`granframe.abc.ArrayBackend.separable_product` and
:meth:`~granframe.abc.ArrayBackend.lowrank_accumulate` in one pass over
memory each, where NumPy needs three to four (a temporary per operation).
They release the GIL, so the fast operator's pipelines run them side by
side. Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import itertools
import math

import numba
import numpy

# fastmath only where it speeds the loops up (fused multiply-add, reassociation): no
# no-NaN/no-Inf assumptions, so a NaN still reaches the runner's health check (measured:
# same speed as fastmath=True, 3D N = 32)
_JIT = {"nogil": True, "fastmath": {"contract", "reassoc"}, "cache": True}


@numba.njit(**_JIT)
def _separable_product_one(out, spectrum, head, tail):
    """out[b, i, j] = spectrum[i, j] (head[b, i] tail[b, j]): one distribution, the factor
    formed inline. The row buffer of :func:`_separable_product` made this case 1.45x
    slower (64 x 64 x 33 spectra: 232 us against 156 us)."""
    batch, rows, cols = out.shape
    for b in range(batch):
        for i in range(rows):
            h = head[b, i]
            for j in range(cols):
                out[b, i, j] = spectrum[i, j] * (h * tail[b, j])
    return out


@numba.njit(**_JIT)
def _separable_product(out, spectrum, head, tail):
    """out[d, b, i, j] = spectrum[d, i, j] head[b, i] tail[b, j]; each factor row
    head[b, i] tail[b, :] formed once for all d (for stacks the buffer pays: 4-25 %
    faster than forming the factor inline for 8 to 64 distributions)."""
    distributions, batch, rows, cols = out.shape
    row = numpy.empty(cols, dtype=out.dtype)
    for b in range(batch):
        for i in range(rows):
            h = head[b, i]
            for j in range(cols):
                row[j] = h * tail[b, j]
            for d in range(distributions):
                for j in range(cols):
                    out[d, b, i, j] = spectrum[d, i, j] * row[j]
    return out


def separable_product(out, spectrum, head, tail):
    """out[d, b, i, j] = spectrum[d, i, j] head[b, i] tail[b, j]; without the d axis
    (spectrum (I, J), out (B, I, J)) the case of one distribution, which (like a d axis of
    length 1) takes the kernel without that axis."""
    if out.ndim == 3:
        return _separable_product_one(out, spectrum, head, tail)
    if out.shape[0] == 1:
        _separable_product_one(out[0], spectrum[0], head, tail)
        return out
    return _separable_product(out, spectrum, head, tail)


@numba.njit(**_JIT)
def _accumulate_rank2_one(acc, heads, tails, values):
    """Rank-2 case of :func:`lowrank_accumulate` for one distribution (acc (Q, I, J),
    values (B, I, J)): the weight formed inline, no row buffer."""
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
def _accumulate_rank2(acc, heads, tails, values):
    """Rank-2 case of :func:`lowrank_accumulate` for a stack, each weight row formed once
    for all d (for stacks the row buffer pays: 4 distributions, 64 x 64 x 33 spectra,
    196 us against 236 us inline; for one distribution it cost 1.3x, hence
    :func:`_accumulate_rank2_one`)."""
    distributions, batch, rows, cols = values.shape
    per_group = batch // acc.shape[1]
    weight = numpy.empty(cols, dtype=acc.dtype)
    for b in range(batch):
        q = b // per_group
        for i in range(rows):
            h0 = heads[b, i, 0]
            h1 = heads[b, i, 1]
            for j in range(cols):
                weight[j] = h0 * tails[b, 0, j] + h1 * tails[b, 1, j]
            for d in range(distributions):
                for j in range(cols):
                    acc[d, q, i, j] += weight[j] * values[d, b, i, j]
    return acc


@numba.njit(**_JIT)
def _accumulate_dense(acc, heads, tails, values):
    """Any rank: the weight of each batch entry by one BLAS product, then a fused update
    of every distribution."""
    distributions, batch, rows, cols = values.shape
    per_group = batch // acc.shape[1]
    for b in range(batch):
        q = b // per_group
        weight = numpy.dot(heads[b], tails[b])
        for d in range(distributions):
            for i in range(rows):
                for j in range(cols):
                    acc[d, q, i, j] += weight[i, j] * values[d, b, i, j]
    return acc


def lowrank_accumulate(acc, heads, tails, values):
    """acc[d, q, i, j] += sum_{b in q} (sum_t heads[b, i, t] tails[b, t, j]) values[d, b, i, j].

    Without the d axis (acc (Q, I, J), values (B, I, J)) the case of one distribution.
    The rank-2 weights of isotropic kernels (a pair and its antipode) are formed on the
    fly; larger ranks (a sigma rule for anisotropic b) go through BLAS. A stack forms
    each rank-2 weight row once for all its distributions; one distribution (no d axis,
    or one of length 1) takes the kernel without that axis and its row buffer, which is
    faster for it.
    """
    stacked_acc = acc[None] if acc.ndim == 3 else acc
    stacked = values[None] if values.ndim == 3 else values
    if heads.shape[2] != 2:
        _accumulate_dense(stacked_acc, numpy.ascontiguousarray(heads),
                          numpy.ascontiguousarray(tails), stacked)
    elif stacked.shape[0] == 1:
        _accumulate_rank2_one(stacked_acc[0], heads, tails, stacked[0])
    else:
        _accumulate_rank2(stacked_acc, heads, tails, stacked)
    return acc


#: the slope limiters of :class:`granframe.space.reconstruction.MUSCL`, by code
MUSCL_LIMITERS = {"minmod": 0, "van_leer": 1, "mc": 2}


@numba.njit(nogil=True, cache=True)
def _least(a, b):
    """numpy.minimum(a, b): the smaller, NaN if either is NaN."""
    if math.isnan(a):
        return a
    if math.isnan(b):
        return b
    return min(a, b)


@numba.njit(nogil=True, cache=True)
def _most(a, b):
    """numpy.maximum(a, b): the larger, NaN if either is NaN."""
    if math.isnan(a):
        return a
    if math.isnan(b):
        return b
    return max(a, b)


@numba.njit(nogil=True, cache=True)
def _sign(x):
    """numpy.sign(x): -1, 0 or 1, NaN for NaN."""
    if x > 0.0:
        return 1.0
    if x < 0.0:
        return -1.0
    return x        # 0 (either sign) or NaN


@numba.njit(nogil=True, cache=True)
def _muscl_faces(f, minus, plus, limiter, tiny):
    """The face values of MUSCL along axis 0 of f (n, k, m) into minus, plus (n - 3, k, m):
    for each cell c = 1 .. n - 2 its half slope sigma_c / 2 from a = f_c - f_{c-1},
    b = f_{c+1} - f_c, with the operations of
    :meth:`granframe.space.reconstruction.MUSCL.faces` in its order (no fastmath: the
    same values to the bit), then f^-_{c-1} = f_c + sigma_c / 2 and
    f^+_{c-2} = f_c - sigma_c / 2. One pass over f."""
    n, k, m = f.shape
    for c in range(1, n - 1):
        for j in range(k):
            for v in range(m):
                centre = f[c, j, v]
                low, high = centre - f[c - 1, j, v], f[c + 1, j, v] - centre
                a, b = abs(low), abs(high)
                same = _sign(low) + _sign(high)
                if limiter == 0:
                    slope = _least(a, b)
                elif limiter == 1:
                    small, large = _least(a, b), _most(a, b)
                    large = _most(large, tiny)
                    slope = 2.0 * small / (1.0 + small / large)
                else:
                    slope = _least(a, b) * 2.0
                    slope = _least(slope, 0.5 * (a + b))
                slope = slope * same
                slope = slope * 0.25
                if c <= n - 3:
                    minus[c - 1, j, v] = centre + slope
                if c >= 2:
                    plus[c - 2, j, v] = centre - slope


#: values of f below which :func:`muscl_faces` runs in the calling thread alone (the
#: handing over to a second thread cost more than it saved: 68 x 32 x 32 values, 0.17 ms
#: alone against 0.28 ms in two threads; 260 x 32 x 32, 0.68 against 0.52 ms)
THREADED_SIZE = 2 ** 18


def muscl_faces(f, limiter: str, executor, workers: int):
    """(f^-, f^+) of MUSCL along axis 0 of ``f`` (n, k, ...), fused (:func:`_muscl_faces`),
    the k columns (or, for fewer columns than ``workers``, the trailing values) shared by
    ``workers`` threads of ``executor`` (None: this thread alone; one thread for fewer than
    :data:`THREADED_SIZE` values)."""
    n, k = f.shape[0], f.shape[1] if f.ndim > 1 else 1
    flat = f.reshape(n, k, -1)
    minus = numpy.empty((n - 3,) + flat.shape[1:], dtype=f.dtype)
    plus = numpy.empty_like(minus)
    code, tiny = MUSCL_LIMITERS[limiter], numpy.finfo(f.dtype).tiny
    if flat.size < THREADED_SIZE:
        workers = 1
    axis = 1 if k >= workers else 2
    size = flat.shape[axis]
    bounds = numpy.linspace(0, size, min(workers, size) + 1).astype(int)
    parts = [tuple(slice(None) if a != axis else slice(lo, hi) for a in range(3))
             for lo, hi in itertools.pairwise(bounds)]
    if executor is None or len(parts) == 1:
        _muscl_faces(flat, minus, plus, code, tiny)
    else:
        done = [executor.submit(_muscl_faces, flat[p], minus[p], plus[p], code, tiny)
                for p in parts[1:]]
        _muscl_faces(flat[parts[0]], minus[parts[0]], plus[parts[0]], code, tiny)
        for part in done:
            part.result()
    shape = (n - 3,) + f.shape[1:]
    return minus.reshape(shape), plus.reshape(shape)
