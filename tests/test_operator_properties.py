"""Hypothesis properties of the fast operator over random positive f and every restitution law."""

import functools

import numpy
from hypothesis import given, settings
from hypothesis import strategies as st

import granframe as gf
from granframe.testing import evaluate_on_host

GRID = gf.VelocityGrid(2, 64, 5.0)
LAWS = {
    "constant": {"value": 0.4},
    "toscani": {"strength": 0.5, "exponent": 1.0},
    "viscoelastic": {"strength": 0.3},
    "tanh": {"asymptotic_value": 0.2, "centre": 2.0, "width": 0.5},
    "threshold": {"threshold": 1.5, "value": 0.5},
}


@functools.lru_cache(maxsize=None)
def operator(law_name, elastic=False, backend=None):
    law = gf.restitution_law("constant", value=1.0) if elastic else gf.restitution_law(
        law_name, **LAWS[law_name])
    backend = gf.array_backend("numpy", threads=1) if backend is None else backend
    return gf.collision_operator("fast_spectral", GRID, gf.collision_kernel("hard_spheres"), law,
                                 backend=backend, radial_points=32,
                                 sphere=gf.CircleTrapezoid(32))


@st.composite
def mixtures(draw):
    """Gaussian mixtures that fit the grid: resolved (T >= 0.6) and inside B_S (T <= 1.2)."""
    count = draw(st.integers(1, 3))
    f = numpy.zeros(GRID.shape)
    for _ in range(count):
        u = [draw(st.floats(-0.7, 0.7)) for _ in range(2)]
        f += GRID.maxwellian(density=draw(st.floats(0.1, 2.0)), velocity=u,
                             temperature=draw(st.floats(0.6, 1.2)))
    return f


def relative_moments(f, q):
    """Mass and energy of Q relative to the collision scale rho(f) int (1 + |v|^2) f dv
    (not to Q itself, which vanishes for an elastic Maxwellian)."""
    scale = GRID.mass(f) * (GRID.mass(f) + 2 * GRID.kinetic_energy(f))
    return GRID.mass(q) / scale, GRID.kinetic_energy(q) / scale


@settings(max_examples=40, deadline=None)
@given(f=mixtures(), law=st.sampled_from(sorted(LAWS)))
def test_mass_conserved_and_energy_never_increases(backend, f, law):
    """On every array backend (the ``backend`` fixture of conftest.py)."""
    q = evaluate_on_host(operator(law, backend=backend), f)
    mass, energy = relative_moments(f, q)
    assert abs(mass) <= 1e-13
    assert energy < 0.0


@settings(max_examples=25, deadline=None)
@given(f=mixtures())
def test_elastic_energy_conserved_to_spectral_accuracy(f):
    q = operator("constant", elastic=True)(f)
    _, energy = relative_moments(f, q)
    assert abs(energy) <= 1e-8


@settings(max_examples=25, deadline=None)
@given(u=st.tuples(st.floats(-0.7, 0.7), st.floats(-0.7, 0.7)), temperature=st.floats(0.6, 1.2),
       density=st.floats(0.1, 3.0))
def test_elastic_maxwellian_is_an_equilibrium(u, temperature, density):
    m = GRID.maxwellian(density=density, velocity=list(u), temperature=temperature)
    q = operator("constant", elastic=True)(m)
    loss_scale = density * numpy.abs(m).max()
    assert numpy.abs(q).max() <= 1e-7 * loss_scale
