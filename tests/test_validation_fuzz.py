"""Fuzz every configuration constructor: only clear ValueError/TypeError may escape.

Whatever a user passes, a constructor either succeeds or raises ValueError or
TypeError whose message names one of the parameters it was given.
"""

import math
import warnings

import numpy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import granframe
from granframe import backends
from granframe.errors import AliasingWarning
from granframe.model import kernels, restitution
from granframe.velocity import grid, quadratures

#: constructor -> a valid set of arguments; the fuzzer replaces some of them.
CONSTRUCTORS = {
    grid.VelocityGrid: dict(dimension=2, n_modes=16, support_radius=1.0, half_width=3.0,
                            truncation_radius=2.0, allow_aliasing=False),
    kernels.VariableHardSpheres: dict(exponent=0.5, angular=None, energy_exponent=0.0,
                                      constant=1.0),
    restitution.Constant: dict(value=0.5),
    restitution.Toscani: dict(strength=1.0, exponent=0.5),
    restitution.Viscoelastic: dict(strength=0.2),
    restitution.Tanh: dict(asymptotic_value=0.2, centre=4.0, width=1.0),
    restitution.Threshold: dict(threshold=1.0, value=0.5),
    quadratures.GaussLegendre: dict(n_points=8),
    quadratures.CircleTrapezoid: dict(n_points=16, phase=0.0),
    quadratures.Lebedev: dict(order=7),
    quadratures.SphereProduct: dict(n_polar=4),
    backends.NumpyBackend: dict(threads=1),
}

values = st.one_of(
    st.none(), st.booleans(),
    st.integers(-10, 300), st.integers(min_value=-(10 ** 400), max_value=10 ** 400),
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-5.0, 5.0), st.floats(0.0, 1.0),
    st.sampled_from([2, 3, 4, 7, 8, 64, 0.5, 1.0, -0.0, 1e308, 5e-324, 3 + 0j, "2", "", b"x",
                     [], [1.0], (), {}, object(), math.pi, numpy.float32(0.5), numpy.int64(16),
                     numpy.nan, numpy.array(2.0), numpy.array([1.0, 2.0]),
                     abs, lambda c: 1.0 + 0.0 * c, lambda c: -c, lambda: 1.0]),
    st.text(max_size=5), st.complex_numbers(max_magnitude=1e3),
)


@st.composite
def calls(draw):
    """A constructor, its valid arguments with one to three replaced, dropped or added."""
    cls = draw(st.sampled_from(list(CONSTRUCTORS)))
    kwargs = dict(CONSTRUCTORS[cls])
    names = list(kwargs) + ["not_a_parameter"]
    for name in draw(st.lists(st.sampled_from(names), min_size=1, max_size=3, unique=True)):
        if draw(st.integers(0, 9)) == 0:
            kwargs.pop(name, None)
        else:
            kwargs[name] = draw(values)
    return cls, kwargs


def _use(obj):
    """An object that was accepted must be usable and consistent."""
    if isinstance(obj, grid.VelocityGrid):
        assert obj.half_width > 0 and obj.truncation_radius > 0 and obj.spacing > 0
        assert obj.allow_aliasing or obj.half_width >= obj.safe_half_width * (1 - 1e-12)
    elif isinstance(obj, kernels.VariableHardSpheres):
        assert 0.0 <= obj.exponent <= 1.0
        value = obj(numpy.array([0.5, 2.0]), numpy.array([-1.0, 1.0]), dimension=3)
        assert numpy.all(numpy.isfinite(value) & (value > 0))
    elif isinstance(obj, restitution.RestitutionLaw):
        e = obj(numpy.array([0.0, 0.5, 4.0, 1e6]))
        assert numpy.all((e >= 0.0) & (e <= 1.0)), e
    elif isinstance(obj, quadratures.GaussLegendre):
        if obj.n_points <= 512:
            rho, w = obj.rule(2.0)
            assert w.sum() == numpy.float64(2.0) or abs(w.sum() - 2.0) < 1e-12
    elif isinstance(obj, quadratures.SurfaceQuadrature):
        if obj.n_points <= 6000:
            area = quadratures.sphere_area(obj.dimension)
            assert abs(obj.weights().sum() - area) < 1e-12 * area
    elif isinstance(obj, backends.NumpyBackend):
        assert obj.workers >= 1


def _attempt(constructor, kwargs, owner_names):
    try:
        with warnings.catch_warnings():
            # allow_aliasing=True asks for the aliasing warning: an answer, not an error
            warnings.simplefilter("ignore", AliasingWarning)
            obj = constructor(**kwargs)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        assert any(f"'{name}'" in message for name in owner_names), message
        return
    assert kwargs.keys() <= set(owner_names)
    _use(obj)


@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(calls())
def test_constructors_raise_only_clear_value_or_type_errors(call):
    cls, kwargs = call
    _attempt(cls, kwargs, list(CONSTRUCTORS[cls]) + ["not_a_parameter"])


@settings(max_examples=500, deadline=None)
@given(family=st.sampled_from(sorted(granframe.FAMILIES) + ["laws", ""]),
       name=st.one_of(st.sampled_from(["constant", "toscani", "lebedev", "vhs", "numpy", "tanh",
                                       "gauss_legendre", "nope"]), st.text(max_size=6), values),
       kwargs=st.dictionaries(st.sampled_from(["value", "order", "n_points", "exponent",
                                               "strength", "threads", "bogus"]), values,
                              max_size=3))
def test_lookup_by_name_raises_only_clear_errors(family, name, kwargs):
    registries = granframe.default_registries()
    try:
        registries.create(family, name, **kwargs)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        mentioned = [repr(family), repr(name), "family", "name", *(f"'{k}'" for k in kwargs)]
        assert any(m in message for m in mentioned), message
