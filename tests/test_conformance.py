"""The conformance kit over every registered implementation, and what it catches.

The cases are discovered from the process's registries: a new built-in or installed
plugin is tested by being registered, with the parameter sets it declares
(:meth:`granframe.registry.Entry.example_parameters`).
"""

import pathlib
import re

import attrs
import numpy
import pytest

import granframe as gf
from granframe.abc import CollisionOperator
from granframe.backends import NumpyBackend
from granframe.equations.homogeneous import HomogeneousBoltzmann
from granframe.errors import BackendUnavailableError, PluginError
from granframe.model.kernels import VariableHardSpheres
from granframe.model.restitution import RestitutionLaw
from granframe.registry import Entry, Source, default_registries
from granframe.space.boundaries import Diffuse, Specular
from granframe.space.reconstruction import MUSCL, Upwind
from granframe.space.transport import reflect, upwind_speeds
from granframe.stepping.integrators import ForwardEuler
from granframe.testing import conformance as kit
from granframe.velocity.quadratures import CircleTrapezoid

from conftest import FAKE_SITE


def _cases():
    registries = default_registries()
    for family in registries._entries:
        for entry in registries.entries(family):
            examples = entry.example_parameters()
            if examples is None:
                yield pytest.param(family, entry.name, None, id=f"{family}-{entry.name}")
                continue
            for i, params in enumerate(examples):
                yield pytest.param(family, entry.name, params, id=f"{family}-{entry.name}-{i}")


def examples_or_fail(entry: Entry, params):
    """``params``, or a failure naming the implementation that declares no examples."""
    if params is None:
        pytest.fail(f"{entry.family} '{entry.name}' of {entry.source} has required parameters "
                    "and no examples: register it with registry.add(..., examples=[{...}]) or "
                    "give the factory a 'conformance_examples' attribute", pytrace=False)
    return params


def _backend_or_skip(name, params):
    try:
        return default_registries().create("array_backends", name, **params)
    except BackendUnavailableError as exc:
        pytest.skip(f"array backend '{name}' {params} cannot be built here: {exc}")


@pytest.mark.parametrize("family,name,params", list(_cases()))
def test_registered_implementation_conforms(family, name, params):
    registries = default_registries()
    entry = registries.get(family, name)
    params = examples_or_fail(entry, params)
    if family == "collision_operators":
        for check in (kit.check_operator_mass, kit.check_operator_mass_on_generated,
                      kit.check_operator_energy_dissipation,
                      kit.check_operator_against_direct, kit.check_operator_batching,
                      kit.check_operator_refuses_bad_restitution):
            check(entry.factory, params)
        return
    if family == "collision_models":
        kit.check_collision_model(entry.factory, params)
        return
    if family == "array_backends":
        backend = _backend_or_skip(name, params)
        kit.check_backend_transforms(backend)
        kit.check_backend_elementwise(backend)
        for operator in registries.entries("collision_operators"):
            kit.check_backend_parity(backend, operator.factory)
        return
    product = registries.create(family, name, **params)   # the registry's boundary check
    {"restitution_laws": kit.check_restitution_law,
     "collision_kernels": kit.check_collision_kernel,
     "quadratures": kit.check_quadrature,
     "time_integrators": kit.check_integrator_order,
     "initial_conditions": kit.check_initial_condition,
     "reconstructions": kit.check_reconstruction,
     "boundaries": kit.check_boundary,
     "communicators": kit.check_communicator}[family](product)


def test_implementation_without_examples_fails_the_suite():
    def law(value, slope):
        """A factory with required parameters."""

    entry = Entry("restitution_laws", "sloped", law, "", Source("thirdparty"))
    assert entry.example_parameters() is None
    with pytest.raises(pytest.fail.Exception,
                       match=r"restitution_laws 'sloped' of plugin 'thirdparty' has required "
                             r"parameters and no examples"):
        examples_or_fail(entry, entry.example_parameters())


def test_examples_come_from_the_registration_or_a_class_attribute():
    class Declared:
        conformance_examples = [{"value": 0.5}]

        def __init__(self, value):
            self.value = value

    assert Entry("restitution_laws", "declared", Declared, "", Source("p")).example_parameters() \
        == ({"value": 0.5},)
    assert Entry("restitution_laws", "given", Declared, "", Source("p"),
                 ({"value": 0.1},)).example_parameters() == ({"value": 0.1},)


# -- the kit's catches: deliberately broken implementations ---------------------------------

class TooElastic(RestitutionLaw):
    """e = 1.5 at every speed."""

    def _evaluate(self, speed):
        return numpy.full_like(speed, 1.5)


@attrs.frozen
class LyingIsotropy(VariableHardSpheres):
    """An anisotropic b flagged isotropic."""

    @property
    def is_isotropic(self):
        return True


class UnnormalisedInverse(NumpyBackend):
    """irfftn without the 1/n of numpy's convention."""

    def irfftn(self, a, s, axes=None):
        return super().irfftn(a, s, axes) * numpy.prod(s)


class ConjugatedInverse(NumpyBackend):
    """ifftn computed as a forward transform (the conjugate kernel)."""

    def ifftn(self, a, axes=None):
        return super().fftn(a, axes) / numpy.prod([a.shape[i] for i in axes])


class SecondOrderEuler(ForwardEuler):
    """Forward Euler declaring order 2."""

    order = 2


@attrs.frozen
class Overpromising(CircleTrapezoid):
    """The equispaced circle rule claiming one more degree than it has."""

    @property
    def degree(self):
        return self.n_points


def test_kit_catches_a_law_returning_1_5():
    with pytest.raises(AssertionError, match=r"e\(r\) must lie in \[0, 1\], got e\(0\) = 1.5"):
        kit.check_restitution_law(TooElastic())


def test_kit_catches_a_lying_isotropy_flag():
    kernel = LyingIsotropy(angular=lambda c: 1.0 + 0.5 * c)
    with pytest.raises(AssertionError, match="is_isotropic is True but angular_part is not "
                                             "constant"):
        kit.check_collision_kernel(kernel)


def test_kit_catches_an_inverse_fft_without_normalisation():
    with pytest.raises(AssertionError, match=r"UnnormalisedInverse.irfftn differs from "
                                             r"numpy.fft.irfftn"):
        kit.check_backend_transforms(UnnormalisedInverse())


def test_kit_catches_a_conjugated_inverse_fft():
    with pytest.raises(AssertionError, match=r"ConjugatedInverse.ifftn differs from "
                                             r"numpy.fft.ifftn"):
        kit.check_backend_transforms(ConjugatedInverse())


def test_kit_catches_an_overstated_order_and_degree():
    with pytest.raises(AssertionError, match="declared order 2, observed 1.0"):
        kit.check_integrator_order(SecondOrderEuler())
    with pytest.raises(AssertionError, match="declared degree 8, but the monomial"):
        kit.check_quadrature(Overpromising(8))


class SecondOrderUpwind(Upwind):
    """The first-order upwind reconstruction declaring order 2."""

    order = 2


@attrs.frozen
class AbsoluteMUSCL(MUSCL):
    """MUSCL whose slope is cut to 0 below an absolute threshold 1e-8 (not scale invariant)."""

    def faces(self, f, xp):
        minus, plus = super().faces(f, xp)
        keep = xp.abs(f[2:-1] - f[1:-2]) > 1e-8
        return xp.where(keep, minus, f[1:-2]), xp.where(keep, plus, f[2:-1])


class BackwardSlope(Upwind):
    """Piecewise linear with the backward slope f_j - f_{j-1}: second order, but it treats
    the two directions differently."""

    ghost = 2
    order = 2

    def faces(self, f, xp):
        slope = 0.5 * (f[1:-1] - f[:-2])
        return f[1:-2] + slope[:-1], f[2:-1] - slope[1:]


def test_kit_catches_broken_reconstructions():
    with pytest.raises(AssertionError, match=r"declared order 2, observed 1.01 on the face "
                                             r"values of a sine"):
        kit.check_reconstruction_order(SecondOrderUpwind())
    with pytest.raises(AssertionError, match=r"minus values of 1e-12 f differ from 1e-12 times "
                                             r"those of f by .* invariant under f -> lambda f"):
        kit.check_reconstruction_symmetries(AbsoluteMUSCL())
    kit.check_reconstruction_order(BackwardSlope())
    with pytest.raises(AssertionError, match=r"on the reversed cells the minus values are not "
                                             r"the plus values reversed"):
        kit.check_reconstruction_symmetries(BackwardSlope())


@attrs.frozen
class LeakySpecular(Specular):
    """Specular reflection of 99 % of what arrives."""

    def emit(self, incoming, grid, xp, **when):
        return 0.99 * super().emit(incoming, grid, xp, **when)


@attrs.frozen
class SquaringWall(Specular):
    """Sends back f^2 / f-weighted mean: mass-conserving and positive, but not linear."""

    def emit(self, incoming, grid, xp, **when):
        positive, negative = upwind_speeds(grid, xp)
        squared = reflect(-negative * incoming * incoming, grid.dimension, xp)
        scale = (-negative * incoming).sum() / (positive * squared).sum()
        return xp.where(positive > 0, scale * squared, incoming)


@attrs.frozen
class MuteRefusal(Specular):
    """A wall whose check() raises a ValueError naming no parameter."""

    def check(self, grid):
        raise ValueError("no")


def test_kit_catches_broken_walls():
    with pytest.raises(AssertionError, match=r"LeakySpecular: net mass flux through the wall "
                                             r".* 0.01 of the arriving flux \(2D\)"):
        kit.check_wall_mass_flux(LeakySpecular())
    kit.check_wall_mass_flux(SquaringWall())
    kit.check_wall_positivity(SquaringWall())
    with pytest.raises(AssertionError, match=r"SquaringWall: emit\(0.3 x \+ 2.5 y\) differs"):
        kit.check_boundary(SquaringWall())
    kit.check_boundary(SquaringWall(), linear=False)
    with pytest.raises(AssertionError, match=r"MuteRefusal: check\(\) refused the 2D grid .* "
                                             r"with a message naming no parameter: no"):
        kit.check_boundary_basics(MuteRefusal())


def test_specular_emission_is_an_exact_involution():
    """R R = identity on the nodes: reflecting twice gives back the incoming values
    bit for bit, and the wall's energy and tangential momentum fluxes vanish to
    round-off (it conserves them, Diffuse with alpha = 1 does not)."""
    wall = Specular()
    for d, n in ((2, 16), (3, 8)):
        grid = gf.VelocityGrid(d, n, 1.5)
        incoming = numpy.random.default_rng(d).uniform(0.1, 1.0, grid.shape)
        assert numpy.array_equal(wall.emit(wall.emit(incoming, grid, numpy), grid, numpy),
                                 incoming)
        positive, negative = upwind_speeds(grid)
        flux = positive * wall.emit(incoming, grid, numpy) + negative * incoming
        scale = numpy.sum((positive - negative) * incoming * grid.speed_squared())
        assert abs(numpy.sum(flux * grid.speed_squared())) <= 1e-14 * scale
        v2 = grid.mesh()[1]
        assert abs(numpy.sum(flux * v2)) <= 1e-14 * scale
    diffuse = numpy.sum(kit._wall_flux(Diffuse(temperature=2.0), incoming, grid)[0]
                        * grid.speed_squared())
    assert abs(diffuse) > 1e-3 * scale


class Leaky(CollisionOperator):
    """The fast spectral operator plus 1e-6 f: mass is not conserved."""

    name = "leaky"

    def __init__(self, grid, kernel, restitution, backend):
        super().__init__(grid, kernel, restitution, backend)
        self._fast = gf.collision_operator("fast_spectral", grid, kernel, restitution,
                                           backend=backend)

    def __call__(self, f):
        return self._fast(f) + 1e-6 * f


def test_kit_catches_an_operator_losing_mass():
    with pytest.raises(AssertionError, match="mass of Q.f. is .* not round-off"):
        kit.check_operator_mass(Leaky, {})


def test_operators_refuse_bad_restitution_laws():
    grid = gf.VelocityGrid(2, 16, 1.5)
    for name in ("fast_spectral", "direct_spectral"):
        with pytest.raises(ValueError, match=rf"{name}: parameter 'restitution' = .* is "
                                             r"invalid; TooElastic must take values in \[0, 1\]"):
            gf.collision_operator(name, grid, gf.collision_kernel("maxwell"), TooElastic())
        kit.check_operator_refuses_bad_restitution(
            default_registries().get("collision_operators", name).factory, {})


def test_registry_names_the_plugin_whose_product_breaks_its_contract(make_distribution,
                                                                      fresh_registries):
    make_distribution("granframe-broken-laws", "granframe_broken_laws", """
        import numpy
        import granframe
        from granframe.model.kernels import VariableHardSpheres
        from granframe.model.restitution import RestitutionLaw

        class TooElastic(RestitutionLaw):
            def _evaluate(self, speed):
                return numpy.full_like(speed, 1.5)

        class Scalar(RestitutionLaw):
            def _evaluate(self, speed):
                return 0.5

        class Lying(VariableHardSpheres):
            # b = 1 + cos(theta)/2, flagged isotropic

            def __init__(self):
                super().__init__(angular=lambda c: 1.0 + 0.5 * c)

            is_isotropic = True

        @granframe.hookimpl
        def granframe_register_restitution_laws(registry):
            registry.add("too_elastic", TooElastic)
            registry.add("scalar_law", Scalar)

        @granframe.hookimpl
        def granframe_register_collision_kernels(registry):
            registry.add("lying", Lying)
            registry.add("not_a_kernel", lambda: "maxwell")
    """)
    registries = fresh_registries()
    source = r"plugin 'granframe_broken_laws' of granframe-broken-laws 0.1"
    with pytest.raises(PluginError, match=source + r": restitution_laws 'too_elastic' "
                       r"\(granframe_broken_laws.TooElastic\) breaks its contract: e\(r\) must "
                       r"lie in \[0, 1\], got e\(0\) = 1.5"):
        registries.create("restitution_laws", "too_elastic")
    with pytest.raises(PluginError, match=r"'scalar_law' .* must have the input's shape \(10,\), "
                                          r"got shape \(\)"):
        registries.create("restitution_laws", "scalar_law")
    with pytest.raises(PluginError, match=source + r": collision_kernels 'lying' .* "
                                          r"is_isotropic is True but angular_part is not"):
        registries.create("collision_kernels", "lying")
    with pytest.raises(PluginError, match=r"'not_a_kernel' .* must build a "
                                          r"granframe.abc.CollisionKernel, got builtins.str"):
        registries.create("collision_kernels", "not_a_kernel")


# -- a plugin author's use of the kit: the example plugin of docs/plugins.md ----------------

@pytest.fixture
def example_plugin(monkeypatch):
    monkeypatch.syspath_prepend(str(FAKE_SITE))
    import granframe_example_plugin
    return granframe_example_plugin


def test_the_documented_plugin_passes_the_kit(example_plugin):
    class TestExponentialDecay(kit.RestitutionLawTests):
        factory = example_plugin.ExponentialDecay
        examples = [{"minimum": 0.4}, {"minimum": 0.0, "scale": 3.0}]

    class TestSoftenedHardSpheres(kit.CollisionKernelTests):
        factory = example_plugin.SoftenedHardSpheres
        examples = [{}, {"exponent": 2.0, "speed_scale": 0.5}]

    TestExponentialDecay().test_restitution_law()
    TestSoftenedHardSpheres().test_collision_kernel()


def test_a_non_power_law_kernel_runs_in_the_operators(example_plugin):
    kernel = example_plugin.SoftenedHardSpheres(exponent=1.0, speed_scale=2.0)
    grid = gf.VelocityGrid(2, 16, 1.5)
    law = gf.restitution_law("constant", value=0.5)
    for name in ("fast_spectral", "direct_spectral"):
        operator = gf.collision_operator(name, grid, kernel, law)
        kit.check_mass_of(operator, grid.maxwellian(temperature=0.5))
    rates = HomogeneousBoltzmann(operator).stiffness(grid.maxwellian(temperature=0.5))
    assert numpy.isfinite(rates["nonlinear"]) and rates["nonlinear"] > 0.0


# -- the test classes, subclassed the way a plugin author does ------------------------------

class TestFastSpectralThroughTheKit(kit.CollisionOperatorTests):
    factory = default_registries().get("collision_operators", "fast_spectral").factory
    examples = [{}, {"radial_points": 24}, {"quadrature": "review"}]


class TestNumpyBackendThroughTheKit(kit.ArrayBackendTests):
    factory = NumpyBackend
    operators = [default_registries().get("collision_operators", "fast_spectral").factory]


class TestRK4ThroughTheKit(kit.TimeIntegratorTests):
    factory = default_registries().get("time_integrators", "rk4").factory


class TestMUSCLThroughTheKit(kit.ReconstructionTests):
    factory = MUSCL
    examples = [{"limiter": "van_leer"}]


class TestDiffuseThroughTheKit(kit.BoundaryTests):
    factory = Diffuse
    examples = [{"temperature": 1.5, "velocity": [0.3, -0.2], "accommodation": 0.5}]


# -- the boundary plugin of docs/plugins.md -------------------------------------------------

DOCS = pathlib.Path(__file__).parent.parent / "docs" / "plugins.md"


def test_the_documented_boundary_registers_and_passes_the_kit(make_distribution,
                                                              fresh_registries):
    """The Python blocks of "A boundary, and a reconstruction": the wall and its hook as a
    plugin module found by its entry point and built by name, and the kit's class on it;
    the bounce-back share keeps the energy flux zero but not the tangential momentum's."""
    text = DOCS.read_text()
    start = text.index("## A boundary, and a reconstruction\n")
    blocks = re.findall(r"```python\n(.*?)```", text[start:text.index("\n## ", start + 1)],
                        re.S)
    assert len(blocks) == 2
    make_distribution("granframe-bounce", "granframe_bounce", blocks[0])
    wall = fresh_registries().create("boundaries", "bounce_back", share=0.3)
    assert type(wall).__module__ == "granframe_bounce"
    namespace = {"__name__": "docs_plugins_boundary"}
    for block in blocks:
        exec(compile(block, str(DOCS), "exec"), namespace)
    tests = namespace["TestBounceBack"]()
    for name in ("test_basics", "test_mass_flux", "test_positivity", "test_linearity"):
        getattr(tests, name)()
    kit.check_boundary(wall)
    grid = gf.VelocityGrid(3, 8, 1.5)
    incoming = numpy.random.default_rng(0).uniform(0.1, 1.0, grid.shape)
    flux = kit._wall_flux(wall, incoming, grid)[0]
    scale = numpy.sum(numpy.abs(flux) * grid.speed_squared())
    assert abs(numpy.sum(flux * grid.speed_squared())) <= 1e-14 * scale
    assert abs(numpy.sum(flux * grid.mesh()[2])) > 1e-2 * numpy.sum(numpy.abs(flux))
