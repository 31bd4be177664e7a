"""The conformance checks of reconstructions (the face values of the space transport):
the class constants and shapes, the declared order, the symmetries and extreme data.
"""

from __future__ import annotations

import itertools
import math

import numpy

from granframe.testing.conformance.common import require, require_contract


#: Cells of the order check: the L1 order is observed between these two resolutions.
ORDER_CELLS = (40, 80)


def _faces(reconstruction, f):
    """(minus, plus) of ``f`` as NumPy arrays, of shape (len(f) - 2 ghost + 1, ...) each."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    minus, plus = (numpy.asarray(a) for a in reconstruction.faces(f, numpy))
    expected = (f.shape[0] - 2 * g + 1,) + f.shape[1:]
    require(minus.shape == expected and plus.shape == expected,
            f"{name}: faces() of an input of shape {f.shape} (ghost = {g}) returned shapes "
            f"{minus.shape} and {plus.shape}, expected {expected} each")
    return minus, plus


def _sine_averages(cells: int, ghost: int):
    """Averages of sin(2 pi x + 0.4) over the cells of width 1/cells of [0, 1] with ``ghost``
    periodic ghost cells each side, and the exact values at the n + 1 faces."""
    edges = numpy.arange(-ghost, cells + ghost + 1) / cells
    phase = 2.0 * math.pi * edges + 0.4
    averages = (numpy.cos(phase[:-1]) - numpy.cos(phase[1:])) * cells / (2.0 * math.pi)
    return averages, numpy.sin(phase[ghost:cells + ghost + 1])


def _rough_data(rng, cells: int):
    """Positive data with a smooth part, a jump and an extremum, shape (cells, 3, 2)."""
    x = (numpy.arange(cells) + 0.5) / cells
    smooth = 1.0 + 0.5 * numpy.sin(2.0 * math.pi * x) + (x > 0.6)
    return smooth[:, None, None] * rng.uniform(0.5, 1.5, (1, 3, 2))


def check_reconstruction(reconstruction) -> None:
    """The class constants, the faces' shapes, constants, broadcasting over the trailing
    axes, the declared order, the symmetries and extreme data
    (:func:`check_reconstruction_basics`, :func:`check_reconstruction_order`,
    :func:`check_reconstruction_symmetries`, :func:`check_reconstruction_extremes`)."""
    check_reconstruction_basics(reconstruction)
    check_reconstruction_order(reconstruction)
    check_reconstruction_symmetries(reconstruction)
    check_reconstruction_extremes(reconstruction)


def check_reconstruction_basics(reconstruction) -> None:
    """``ghost`` an integer >= 0, ``order`` an integer >= 1, ``cfl`` in (0, 1], all class
    attributes; faces() of an input (n + 2 ghost, ...) of shape (n + 1, ...) each, for no,
    one and two trailing axes; constants 0, 0.7 and 3 reproduced to 4 ulp; a stack of
    columns (trailing axes, a non-contiguous view as the transport passes) reconstructed as
    each column alone, to 1e-14; the input left unchanged."""
    from granframe.abc import Reconstruction

    require(isinstance(reconstruction, Reconstruction),
            f"{reconstruction!r} is not a granframe.abc.Reconstruction")
    require_contract("reconstructions", reconstruction)
    kind, name = type(reconstruction), type(reconstruction).__name__
    for attribute in ("ghost", "order", "cfl"):
        require(attribute in dir(kind) and not isinstance(getattr(kind, attribute), property),
                f"{name}: '{attribute}' must be a class attribute (the core reads it before "
                "building the cells)")
    g, order, cfl = kind.ghost, kind.order, kind.cfl
    require(isinstance(g, int) and not isinstance(g, bool) and g >= 0,
            f"{name}: ghost must be an integer >= 0, got {g!r}")
    require(isinstance(order, int) and not isinstance(order, bool) and order >= 1,
            f"{name}: order must be an integer >= 1, got {order!r}")
    require(isinstance(cfl, (int, float)) and 0.0 < cfl <= 1.0,
            f"{name}: cfl must lie in (0, 1], got {cfl!r}")
    rng = numpy.random.default_rng(2)
    n = 12
    for value in (0.0, 0.7, 3.0):
        for trailing in ((), (3,), (3, 2)):
            f = numpy.full((n + 2 * g,) + trailing, value)
            for side, faces in zip(("minus", "plus"), _faces(reconstruction, f)):
                error = float(numpy.max(numpy.abs(faces - value)))
                require(error <= 4 * numpy.finfo(float).eps * value,
                        f"{name}: the constant {value} is reconstructed as {side} values "
                        f"off by up to {error:.3g}")
    f = numpy.ascontiguousarray(numpy.swapaxes(_rough_data(rng, n + 2 * g), 0, 1))
    copy = f.copy()
    stacked = _faces(reconstruction, numpy.swapaxes(f, 0, 1))   # a view, as the transport's
    require(numpy.array_equal(f, copy), f"{name}: faces() modified its input")
    scale = numpy.max(numpy.abs(f))
    for i, k in itertools.product(range(3), range(2)):
        column = _faces(reconstruction, numpy.ascontiguousarray(f[i, :, k]))
        for side, whole, alone in zip(("minus", "plus"), stacked, column):
            error = float(numpy.max(numpy.abs(whole[:, i, k] - alone))) / scale
            require(error <= 1e-14,
                    f"{name}: the {side} values of column ({i}, {k}) of a stack of shape "
                    f"{f.shape[1:2] + f.shape[:1] + f.shape[2:]} differ from those of the "
                    f"column alone by {error:.3g} of max |f|: faces() must act element-wise "
                    "over the trailing axes")


def check_reconstruction_order(reconstruction) -> None:
    """Consistency at the declared ``order`` p: on the cell averages of sin(2 pi x + 0.4),
    periodic, with n = 40 and 80 cells, the L1 error of the face values (both sides) against
    the point values at the faces falls by at least 2^(p - 0.3) (L1, so that limited schemes,
    which clip at extrema, are measured at their order)."""
    name, g, order = type(reconstruction).__name__, reconstruction.ghost, reconstruction.order
    errors = []
    for cells in ORDER_CELLS:
        averages, exact = _sine_averages(cells, g)
        minus, plus = _faces(reconstruction, averages)
        errors.append(float(numpy.sum(numpy.abs(minus - exact) + numpy.abs(plus - exact)))
                      / (2 * (cells + 1)))
    observed = math.log2(errors[0] / errors[1]) if errors[1] > 0 else math.inf
    require(observed >= order - 0.3,
            f"{name}: declared order {order}, observed {observed:.2f} on the face values of "
            f"a sine (L1 errors {errors[0]:.3g} with {ORDER_CELLS[0]} cells, {errors[1]:.3g} "
            f"with {ORDER_CELLS[1]})")


def check_reconstruction_symmetries(reconstruction) -> None:
    """On positive data with a jump and an extremum: scale invariance (faces of lambda f
    are lambda times those of f, to 1e-13 of lambda max|f|, for lambda = 1e-12 and 1e6:
    distribution values span many decades), translation (the data shifted by one cell
    give the faces shifted by one, to 1e-14 of max|f|) and the mirror symmetry (reversing
    the cells gives the plus values reversed as minus values and the other way round, to
    1e-13 of max|f|)."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    data = _rough_data(numpy.random.default_rng(3), 16 + 2 * g + 1)
    f = data[:-1]
    scale = float(numpy.max(numpy.abs(data)))
    minus, plus = _faces(reconstruction, f)
    for factor in (1e-12, 1e6):
        for side, scaled, faces in zip(("minus", "plus"), _faces(reconstruction, factor * f),
                                       (minus, plus)):
            error = float(numpy.max(numpy.abs(scaled - factor * faces))) / (factor * scale)
            require(error <= 1e-13,
                    f"{name}: the {side} values of {factor:g} f differ from {factor:g} times "
                    f"those of f by {error:.3g} of max|{factor:g} f|: a reconstruction must "
                    "be invariant under f -> lambda f (no absolute thresholds)")
    for side, shifted, faces in zip(("minus", "plus"), _faces(reconstruction, data[1:]),
                                    (minus, plus)):
        error = float(numpy.max(numpy.abs(shifted[:-1] - faces[1:]))) / scale
        require(error <= 1e-14,
                f"{name}: the data shifted by one cell give {side} values that differ from "
                f"the shifted ones by {error:.3g} of max |f|")
    mirrored = _faces(reconstruction, f[::-1])
    for side, other, faces, original in (("minus", "plus", mirrored[0], plus),
                                         ("plus", "minus", mirrored[1], minus)):
        error = float(numpy.max(numpy.abs(faces - original[::-1]))) / scale
        require(error <= 1e-13,
                f"{name}: on the reversed cells the {side} values are not the {other} values "
                f"reversed (off by {error:.3g} of max |f|): the scheme must treat both "
                "directions alike")


def check_reconstruction_extremes(reconstruction) -> None:
    """Finite face values for data spanning 1e-300 .. 1 (a Gaussian tail, a jump from 1 to
    1e-300, zeros, the smallest subnormal)."""
    name, g = type(reconstruction).__name__, reconstruction.ghost
    cells = 40 + 2 * g
    tail = 10.0 ** -numpy.linspace(0.0, 300.0, cells)
    jump = numpy.where(numpy.arange(cells) < cells // 2, 1.0, 1e-300)
    sparse = tail * (numpy.arange(cells) % 3 == 0)
    sparse[1] = 5e-324
    f = numpy.stack([tail, tail[::-1], jump, sparse], axis=1)
    for side, faces in zip(("minus", "plus"), _faces(reconstruction, f)):
        bad = ~numpy.isfinite(faces)
        require(not numpy.any(bad),
                f"{name}: {side} values are not finite on data spanning 1e-300 .. 1 (columns "
                f"{sorted(set(numpy.nonzero(bad)[1].tolist()))} of: a decaying tail, a "
                "growing one, a jump from 1 to 1e-300, a sparse tail with zeros)")
