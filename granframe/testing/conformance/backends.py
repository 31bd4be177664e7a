"""The conformance checks of array backends: the FFTs against NumPy's, the element-wise
kernels against :func:`numpy.einsum`, and an operator's results against those on the
NumPy backend.
"""

from __future__ import annotations

import numpy

from granframe.abc import ArrayBackend
from granframe.testing.conformance.common import require
from granframe.testing.conformance.operators import (OPERATOR_CASES, SMALL_GRIDS, build_operator,
                                                     default_arguments, on_host)


def check_backend_transforms(backend) -> None:
    """fftn/ifftn/rfftn/irfftn against :mod:`numpy.fft` to 1e-12, and :meth:`real_fft`
    (unnormalised, in float64 and float32) against numpy's rfftn and irfftn times the
    number of points."""
    require(isinstance(backend, ArrayBackend), f"{backend!r} is not a granframe.ArrayBackend")
    name = type(backend).__name__
    rng = numpy.random.default_rng(0)
    for shape, axes in (((16, 16), (0, 1)), ((8, 8, 8), (0, 1, 2)), ((3, 8, 8), (1, 2))):
        x = rng.standard_normal(shape)
        z = x + 1j * rng.standard_normal(shape)
        spectrum = numpy.fft.rfftn(x, axes=axes)
        sizes = tuple(shape[a] for a in axes)
        pairs = {"fftn": (backend.fftn(backend.asarray(z), axes=axes), numpy.fft.fftn(z, axes=axes)),
                 "ifftn": (backend.ifftn(backend.asarray(z), axes=axes),
                           numpy.fft.ifftn(z, axes=axes)),
                 "rfftn": (backend.rfftn(backend.asarray(x), axes=axes), spectrum),
                 "irfftn": (backend.irfftn(backend.asarray(spectrum), s=sizes, axes=axes), x)}
        for what, (got, expected) in pairs.items():
            got = backend.to_numpy(got)
            require(got.shape == expected.shape and numpy.allclose(got, expected, rtol=0,
                                                                   atol=1e-12 * abs(expected).max()),
                    f"{name}.{what} differs from numpy.fft.{what} over axes {axes} of {shape}")
        for precision, tolerance in (("float64", 1e-12), ("float32", 1e-5)):
            plan = backend.real_fft(shape, axes, precision=precision)
            plan.real[...] = backend.asarray(x)
            forward = backend.to_numpy(plan.forward())
            require(numpy.allclose(forward, spectrum, rtol=0, atol=tolerance * abs(spectrum).max()),
                    f"{name}.real_fft({precision}).forward differs from numpy.fft.rfftn")
            plan.spectrum[...] = backend.asarray(spectrum)
            inverse = backend.to_numpy(plan.inverse())
            expected = x * numpy.prod(sizes)
            require(inverse.shape == x.shape and numpy.allclose(
               inverse, expected, rtol=0, atol=tolerance * abs(expected).max()),
               f"{name}.real_fft({precision}).inverse differs from numpy.fft.irfftn times "
               f"the number of points (RealFFT.inverse is unnormalised)")
            require(inverse.dtype == numpy.dtype(precision),
                    f"{name}.real_fft({precision}).inverse returned dtype {inverse.dtype}")


def check_backend_elementwise(backend) -> None:
    """``separable_product`` and ``lowrank_accumulate`` against :func:`numpy.einsum` to
    1e-12, with and without the leading axis of distributions."""
    name = type(backend).__name__
    rng = numpy.random.default_rng(1)

    def c(*shape):
        return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)

    xp, host = backend.asarray, backend.to_numpy
    batch, groups, rows, cols, rank = 6, 3, 8, 5, 2
    head, tail = c(batch, rows), c(batch, cols)
    heads, tails = c(batch, rows, rank), c(batch, rank, cols)
    for lead in ((), (2,)):
        spectrum = c(*lead, rows, cols)
        out = xp(numpy.zeros(lead + (batch, rows, cols), dtype=complex))
        got = host(backend.separable_product(out, xp(spectrum), xp(head), xp(tail)))
        expected = numpy.einsum("...ij,bi,bj->...bij", spectrum, head, tail)
        require(numpy.allclose(got, expected, rtol=1e-12, atol=1e-12),
                f"{name}.separable_product differs from einsum (leading shape {lead})")
        acc0, values = c(*lead, groups, rows, cols), c(*lead, batch, rows, cols)
        weights = numpy.einsum("bit,btj->bij", heads, tails) * values
        expected = acc0 + weights.reshape(lead + (groups, -1, rows, cols)).sum(axis=-3)
        got = host(backend.lowrank_accumulate(xp(acc0.copy()), xp(heads), xp(tails),
                                              xp(values.copy())))
        require(numpy.allclose(got, expected, rtol=1e-12, atol=1e-12),
                f"{name}.lowrank_accumulate differs from einsum (leading shape {lead})")


def check_backend_parity(backend, factory, options=None) -> None:
    """Q(f) of the operator ``factory`` on ``backend`` equals that on the NumPy backend
    to 1e-12 of max |Q| on the small grids."""
    name = type(backend).__name__
    for d, n, support, temperature in SMALL_GRIDS:
        for kernel, params, law in OPERATOR_CASES:
            grid, kernel_, law_, numpy_backend = default_arguments(d, n, support, kernel,
                                                                   params, law)
            f = grid.maxwellian(velocity=[0.1] * d, temperature=temperature)
            reference = on_host(build_operator(factory, options or {}, grid, kernel_, law_,
                                               numpy_backend), f)
            got = on_host(build_operator(factory, options or {}, grid, kernel_, law_, backend), f)
            error = numpy.max(numpy.abs(got - reference)) / numpy.max(numpy.abs(reference))
            require(error <= 1e-12, f"{name}: Q(f) differs from the NumPy backend's by "
                                    f"{error:.3g} of max |Q| ({d}D, {kernel})")
