"""The element-wise operations every array backend supplies (fused or generic) against einsum."""

import numpy
import pytest

import granframe as gf

CPU_BACKENDS = ["numpy", pytest.param("pyfftw", marks=pytest.mark.skipif(
    not __import__("importlib").util.find_spec("pyfftw"), reason="pyfftw not installed"))]


def complex_normal(rng, *shape):
    return rng.standard_normal(shape) + 1j * rng.standard_normal(shape)


@pytest.mark.parametrize("backend", CPU_BACKENDS)
@pytest.mark.parametrize("batch,rows,cols", [(1, 4, 3), (6, 16, 144), (5, 7, 33)])
def test_separable_product(backend, batch, rows, cols):
    rng = numpy.random.default_rng(batch * rows + cols)
    spectrum = complex_normal(rng, rows, cols)
    head, tail = complex_normal(rng, batch, rows), complex_normal(rng, batch, cols)
    out = numpy.full((batch, rows, cols), numpy.nan, dtype=complex)
    result = gf.array_backend(backend).separable_product(out, spectrum, head, tail)
    expected = numpy.einsum("ij,bi,bj->bij", spectrum, head, tail)
    assert result is out
    numpy.testing.assert_allclose(out, expected, rtol=0, atol=1e-14 * numpy.abs(expected).max())


@pytest.mark.parametrize("backend", CPU_BACKENDS)
@pytest.mark.parametrize("rank", [1, 2, 5])
@pytest.mark.parametrize("groups,per_group", [(1, 1), (1, 4), (3, 2)])
def test_lowrank_accumulate(backend, rank, groups, per_group):
    rng = numpy.random.default_rng(100 * rank + 10 * groups + per_group)
    batch, rows, cols = groups * per_group, 9, 17
    heads, tails = complex_normal(rng, batch, rows, rank), complex_normal(rng, batch, rank, cols)
    values = complex_normal(rng, batch, rows, cols)
    start = complex_normal(rng, groups, rows, cols)
    expected = start + numpy.einsum("bit,btj,bij->bij", heads, tails, values).reshape(
        groups, per_group, rows, cols).sum(axis=1)
    acc = start.copy()
    result = gf.array_backend(backend).lowrank_accumulate(acc, heads, tails, values.copy())
    assert result is acc
    numpy.testing.assert_allclose(acc, expected, rtol=0, atol=1e-13 * numpy.abs(expected).max())
