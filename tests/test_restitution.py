import numpy
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import granframe
from granframe.model.restitution import Constant, Tanh, Threshold, Toscani, Viscoelastic

SPEEDS = numpy.concatenate([[0.0], numpy.logspace(-14, 8, 4001)])


@pytest.mark.parametrize("strength", [1e-6, 0.05, 0.3, 1.0, 7.0, 1e4])
def test_viscoelastic_solves_its_implicit_relation_to_machine_precision(strength):
    e = Viscoelastic(strength)(SPEEDS)
    residual = e + strength * SPEEDS ** 0.2 * e ** 0.6 - 1.0
    assert numpy.max(numpy.abs(residual)) <= 1e-13
    assert numpy.all(numpy.diff(e) <= 0.0)  # monotone decreasing in |g|


def test_viscoelastic_small_and_large_speed_limits():
    law = Viscoelastic(0.3)
    assert law(numpy.array([0.0]))[0] == 1.0
    # e = 1 - a r^{1/5} + O(r^{2/5}) near 0; e ~ (a r^{1/5})^{-5/3} for large r.
    r = numpy.array([1e-20])
    assert law(r)[0] == pytest.approx(1.0 - 0.3 * 1e-4, rel=1e-7)
    r = numpy.array([1e30])
    assert law(r)[0] == pytest.approx((0.3 * r[0] ** 0.2) ** (-5 / 3), rel=1e-3)


@pytest.mark.parametrize("law", [Toscani(2.0, 0.5), Toscani(0.1, 2.0), Viscoelastic(0.5),
                                 Threshold(1.5, 0.3)])
def test_elastic_limit_at_vanishing_relative_speed(law):
    e = law(numpy.array([1e-16, 1e-12, 1e-8, 0.0]))
    assert e[-1] == 1.0
    assert numpy.all(numpy.diff(e[:3]) <= 0.0) and e[0] == pytest.approx(1.0, abs=1e-2)


def test_tanh_law_of_the_review():
    law = Tanh(0.2)  # Test 3: e0 = 0.2, centre 4, width 1
    r = numpy.array([0.0, 4.0, 100.0])
    expected = (0.2 - 1) / 2 * numpy.tanh(r - 4) + (0.2 + 1) / 2
    numpy.testing.assert_allclose(law(r), expected, rtol=1e-15)
    assert law(numpy.array([4.0]))[0] == pytest.approx(0.6)
    assert law(numpy.array([0.0]))[0] == pytest.approx(1.0, abs=4e-4)


def test_toscani_and_threshold_values():
    numpy.testing.assert_allclose(Toscani(1.0, 0.5)(numpy.array([0.0, 1.0, 4.0])),
                                  [1.0, 0.5, 1 / 3], rtol=1e-15)
    numpy.testing.assert_array_equal(Threshold(1.0, 0.5)(numpy.array([0.5, 1.0, 2.0])),
                                     [1.0, 0.5, 0.5])


def test_constant_flags():
    assert Constant(0.5).is_constant
    assert Toscani(0.0, 1.0).is_constant and Toscani(1.0, 0.0).is_constant
    assert not Toscani(1.0, 1.0).is_constant
    assert not Viscoelastic(0.1).is_constant
    assert not Tanh(0.2).is_constant and Tanh(1.0).is_constant
    assert not Threshold(1.0, 0.5).is_constant and Threshold(1.0, 1.0).is_constant


def test_negative_or_nan_speeds_are_refused():
    with pytest.raises(ValueError, match="'speed'"):
        Constant(0.5)(numpy.array([1.0, -1.0]))
    with pytest.raises(ValueError, match="'speed'"):
        Viscoelastic(0.5)(numpy.array([numpy.nan]))


laws = st.one_of(
    st.builds(Constant, st.floats(0, 1)),
    st.builds(Toscani, st.floats(0, 1e3), st.floats(-3, 3)),
    st.builds(Viscoelastic, st.floats(1e-6, 1e3)),
    st.builds(Tanh, st.floats(0, 1), st.floats(-10, 10), st.floats(1e-3, 10)),
    st.builds(Threshold, st.floats(1e-3, 1e3), st.floats(0, 1)),
)


@settings(max_examples=300, deadline=None)
@given(law=laws, speeds=st.lists(st.floats(0, 1e6), min_size=1, max_size=20))
def test_every_law_stays_in_unit_interval(law, speeds):
    e = law(numpy.array(speeds))
    assert e.shape == (len(speeds),)
    assert numpy.all((e >= 0.0) & (e <= 1.0))
    if law.is_constant:
        assert numpy.ptp(e) == 0.0


def test_laws_by_name():
    law = granframe.restitution_law("viscoelastic", strength=0.2)
    assert isinstance(law, Viscoelastic)
    with pytest.raises(ValueError, match="'viscous'.*known: constant, tanh, threshold, toscani, viscoelastic"):
        granframe.restitution_law("viscous")
    with pytest.raises(TypeError, match="accepted parameters: strength"):
        granframe.restitution_law("viscoelastic", a=0.2)
