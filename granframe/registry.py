"""Discovery and registries of implementations.

:func:`get_plugin_manager` follows pluggy's host pattern: add the hook
specifications, then load the plugins of the entry-point group ``granframe``.
granframe's own built-in module is one of them (the entry point ``builtin`` of the
``granframe`` distribution), so it takes exactly the road of a third party's plugin
and no module of granframe imports it. :class:`Registries` calls every hook
implementation once with a :class:`FamilyRegistry` bound to that plugin, so
every registered name knows where it came from.

Plugins listed (comma-separated entry-point names, ``builtin`` for
granframe's own) in the environment variable ``GRANFRAME_DISABLE_PLUGINS``
are not loaded.
"""

from __future__ import annotations

import difflib
import functools
import importlib.metadata
import inspect
import os
import re
from typing import Any, Callable

import attrs
import pluggy

from granframe import contract_checks, hookspecs
from granframe import validators as check
from granframe._version import __version__
from granframe.errors import PluginError, UnknownNameError, UnknownParameterError

ENTRY_POINT_GROUP = "granframe"
DISABLE_ENV = "GRANFRAME_DISABLE_PLUGINS"
BUILTIN_PLUGIN = "builtin"

#: Family name -> hook name. Family names are the keys users see.
FAMILIES = {
    "collision_kernels": "granframe_register_collision_kernels",
    "restitution_laws": "granframe_register_restitution_laws",
    "quadratures": "granframe_register_quadratures",
    "collision_operators": "granframe_register_collision_operators",
    "time_integrators": "granframe_register_time_integrators",
    "initial_conditions": "granframe_register_initial_conditions",
    "array_backends": "granframe_register_array_backends",
    "reconstructions": "granframe_register_reconstructions",
    "boundaries": "granframe_register_boundaries",
    "communicators": "granframe_register_communicators",
    "collision_models": "granframe_register_collision_models",
}

_NAME = re.compile(r"^[a-z][a-z0-9_]*$")

#: Leading parameters of a collision operator's factory that the framework passes itself.
OPERATOR_ARGUMENTS = ("grid", "kernel", "restitution", "backend")

#: What the framework passes to each family's factories besides the users' parameters.
FRAMEWORK_ARGUMENTS = {"collision_operators": OPERATOR_ARGUMENTS,
                       "collision_models": ("context",)}


def closest(word, choices) -> str | None:
    """The choice closest to ``word`` (:func:`difflib.get_close_matches`), None when none
    is close."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1)
    return close[0] if close else None


def did_you_mean(word, choices) -> str:
    """``"; did you mean 'x'?"`` for the choice closest to ``word`` (:func:`closest`), or
    ``""`` when none is close."""
    match = closest(word, choices)
    return "" if match is None else f"; did you mean '{match}'?"


@attrs.frozen
class Parameter:
    """One parameter of a registered factory, as ``granframe plugins NAME`` shows it.

    Attributes
    ----------
    name : str
        The keyword users pass.
    type : str
        Its type as annotated (the attrs field's type, the signature's annotation or the
        ``name : type`` line of the docstring's Parameters section); ``""`` if none is.
    default : object
        The default value; :data:`REQUIRED` when the parameter has none.
    """

    name: str
    type: str
    default: Any

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def to_dict(self) -> dict:
        """JSON-ready: a default that is not a JSON scalar is given as its ``repr``."""
        default = self.default
        if not (default is None or isinstance(default, (str, bool, int, float))):
            default = repr(default)
        return {"name": self.name, "type": self.type, "required": self.required,
                **({} if self.required else {"default": default})}


class _Required:
    """The type of :data:`REQUIRED`."""

    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a :class:`Parameter` that must be given.
REQUIRED = _Required()


@attrs.frozen
class Source:
    """Where an implementation comes from: plugin name, distribution and its version."""

    plugin: str
    distribution: str | None = None
    version: str | None = None

    def __str__(self) -> str:
        if self.distribution is None:
            return f"plugin '{self.plugin}'"
        return f"plugin '{self.plugin}' of {self.distribution} {self.version}"


@attrs.frozen
class Entry:
    """One registered implementation."""

    family: str
    name: str
    factory: Callable = attrs.field(repr=False)
    description: str
    source: Source
    #: Parameter sets the conformance kit builds it with (:meth:`example_parameters`).
    examples: tuple | None = attrs.field(default=None, repr=False)

    def example_parameters(self) -> tuple | None:
        """The parameter sets the conformance kit (:mod:`granframe.testing.conformance`)
        builds this implementation with: the ``examples`` given to
        :meth:`FamilyRegistry.add`, else the factory's attribute ``conformance_examples``,
        else ``({},)`` when every parameter has a default (but those the framework passes,
        :data:`FRAMEWORK_ARGUMENTS`); None when none are known.
        """
        if self.examples is not None:
            return self.examples
        declared = getattr(self.factory, "conformance_examples", None)
        if declared is not None:
            return tuple(dict(p) for p in declared)
        try:
            parameters = list(inspect.signature(self.factory).parameters.values())
        except (TypeError, ValueError):
            return None
        passed = FRAMEWORK_ARGUMENTS.get(self.family, ())
        parameters = [p for p in parameters if p.name not in passed]
        required = [p for p in parameters if p.default is inspect.Parameter.empty
                    and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
        return None if required else ({},)

    @property
    def factory_path(self) -> str:
        """``module.qualname`` of the factory."""
        return _qualname(self.factory)

    def parameters(self) -> list[Parameter] | None:
        """The parameters users pass to the factory, in order: every keyword of its
        signature but ``*args``/``**kwargs``, private (``_``) names and, for collision
        operators and collision models, the arguments the framework passes
        (:data:`FRAMEWORK_ARGUMENTS`);
        None when the factory has no signature."""
        try:
            signature = inspect.signature(self.factory)
        except (TypeError, ValueError):   # builtins without a signature
            return None
        fields = ({f.alias or f.name: f for f in attrs.fields(self.factory)}
                  if isinstance(self.factory, type) and attrs.has(self.factory) else {})
        written = _docstring_types(inspect.getdoc(self.factory))
        found = []
        for p in signature.parameters.values():
            if (p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.name.startswith("_")
                    or p.name in FRAMEWORK_ARGUMENTS.get(self.family, ())):
                continue
            field = fields.get(p.name)
            kind = field.type if field is not None else None
            if kind is None and p.annotation is not p.empty:
                kind = p.annotation
            if kind is None:
                kind = written.get(p.name, "")
            elif not isinstance(kind, str):
                kind = getattr(kind, "__name__", str(kind))
            if field is not None and isinstance(field.default, attrs.Factory):
                default = field.default     # shown as Factory(...): a fresh value per object
            else:
                default = REQUIRED if p.default is p.empty else p.default
            found.append(Parameter(p.name, kind, default))
        return found

    def summary(self) -> str:
        """The docstring's summary: its first paragraph, on one line."""
        text = inspect.getdoc(self.factory) or ""
        return " ".join(text.split("\n\n", 1)[0].split())

    def check_parameters(self, params: dict, arguments=()) -> None:
        """Refuse ``params`` that the factory does not take, naming this implementation.

        An unknown keyword gets the closest accepted one (``unknown parameter 'g_0'; did
        you mean 'g0'?``) before a missing one is reported; ``arguments`` are the names
        the caller passes besides ``params`` (a description checks an operator's options
        with ``grid`` and the rest as None). A factory without a signature, or with
        ``**kwargs``, takes any keyword; its call decides.

        Raises
        ------
        UnknownParameterError
            A ``TypeError``: ``<family> '<name>': unknown parameter ...``, with the
            accepted parameters.
        TypeError
            ``<family> '<name>': missing required parameter ...``, and other calls the
            signature refuses.
        """
        try:
            signature = inspect.signature(self.factory)
        except (TypeError, ValueError):   # builtins without a signature: let the call decide
            return
        who = f"{self.family} '{self.name}'"

        def accepted() -> str:
            return f"accepted parameters: {', '.join(self._names()) or 'none'}"

        named = [p for p in signature.parameters.values()
                 if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
        if not any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values()):
            for key in params:
                if key not in {p.name for p in named}:
                    suggestion = did_you_mean(key, self._names())
                    raise UnknownParameterError(
                        f"{who}: unknown parameter '{key}'{suggestion}"
                        + (f" {accepted().capitalize()}" if suggestion else f"; {accepted()}"))
        given = set(params) | set(arguments)
        for p in named:
            if p.default is p.empty and p.name not in given:
                raise TypeError(f"{who}: missing required parameter '{p.name}'; {accepted()}")
        try:
            signature.bind(**{**dict.fromkeys(arguments), **params})
        except TypeError as exc:   # what the checks above do not cover (positional-only, ...)
            raise TypeError(f"{who}: {exc}; {accepted()}") from None

    def _names(self) -> list[str]:
        return [p.name for p in self.parameters() or ()]

    def create(self, **params) -> Any:
        """Call the factory and check its product against the family's contract
        (:func:`granframe.contract_checks.check_product`).

        A wrong parameter name becomes a clear ``TypeError`` (:meth:`check_parameters`);
        a product that breaks the contract a :class:`PluginError` naming the plugin, the
        implementation and what is wrong.
        """
        self.check_parameters(params)
        product = self.factory(**params)
        try:
            contract_checks.check_product(self.family, product)
        except contract_checks.ContractViolation as exc:
            raise PluginError(f"{self.source}: {self.family} '{self.name}' "
                              f"({self.factory_path}) breaks its contract: {exc}") from None
        return product

    def to_dict(self) -> dict:
        return {"name": self.name, "description": self.description,
                "source": attrs.asdict(self.source)}


def _qualname(factory) -> str:
    return f"{getattr(factory, '__module__', '?')}.{getattr(factory, '__qualname__', repr(factory))}"


def _docstring_types(text: str | None) -> dict[str, str]:
    """``name -> type`` from the ``name : type`` lines of a numpydoc Parameters section."""
    section = re.search(r"^Parameters\n-+\n(.*?)(?:\n\S[^\n]*\n-+\n|\Z)", text or "",
                        re.S | re.M)
    if section is None:
        return {}
    types = {}
    for names, kind in re.findall(r"^(\S[^:\n]*?) : ([^\n]+)$", section.group(1), re.M):
        for name in names.split(","):
            types[name.strip()] = kind.strip()
    return types


def _first_line(text: str | None) -> str:
    for line in (text or "").strip().splitlines():
        if line.strip():
            return line.strip()
    return ""


class FamilyRegistry:
    """What a hook implementation receives:
    ``registry.add(name, factory, description=None, examples=None)``."""

    def __init__(self, registries: Registries, family: str, source: Source):
        self._registries = registries
        self.family = family
        self.source = source

    def add(self, name: str, factory: Callable, *, description: str | None = None,
            examples=None) -> None:
        """Register ``factory`` under ``name`` (snake_case, unique within the family).

        ``description`` defaults to the first line of the factory's docstring.
        ``examples`` is a sequence of parameter dicts the conformance kit builds the
        implementation with (:meth:`Entry.example_parameters`); a factory with required
        parameters and no examples fails the conformance suite.
        """
        if not isinstance(name, str) or not _NAME.match(name):
            raise PluginError(f"{self.source}: {self.family} name {name!r} is invalid; "
                              "names are snake_case: a lowercase letter then [a-z0-9_]")
        if not callable(factory):
            raise PluginError(f"{self.source}: factory for {self.family} '{name}' is not callable")
        if examples is not None:
            if isinstance(examples, dict) or not all(isinstance(p, dict) for p in examples):
                raise PluginError(f"{self.source}: examples for {self.family} '{name}' must "
                                  f"be a sequence of parameter dicts, got {examples!r}")
            examples = tuple(dict(p) for p in examples)
        text = description if description is not None else _first_line(factory.__doc__)
        self._registries._add(Entry(self.family, name, factory, text, self.source, examples))


class Registries:
    """Every family's implementations, collected from one plugin manager."""

    def __init__(self, plugin_manager: pluggy.PluginManager, sources: dict[str, Source]):
        self.plugin_manager = plugin_manager
        self._entries: dict[str, dict[str, Entry]] = {family: {} for family in FAMILIES}
        for family, hook_name in FAMILIES.items():
            # pluggy's call order: last registered first, so the built-ins come first.
            for impl in reversed(getattr(plugin_manager.hook, hook_name).get_hookimpls()):
                source = sources.get(impl.plugin_name, Source(impl.plugin_name))
                arguments = {"registry": FamilyRegistry(self, family, source)}
                impl.function(*(arguments[name] for name in impl.argnames))

    def _add(self, entry: Entry) -> None:
        known = self._entries[entry.family]
        if entry.name in known:
            raise PluginError(f"{entry.family} '{entry.name}' is registered twice: by "
                              f"{known[entry.name].source} and by {entry.source}; disable one "
                              f"with {DISABLE_ENV}=<plugin name>")
        known[entry.name] = entry

    def _family(self, family: str) -> dict[str, Entry]:
        if family not in self._entries:
            raise UnknownNameError(f"parameter 'family' = {family!r} is invalid; "
                                   f"known families: {', '.join(FAMILIES)}"
                                   f"{did_you_mean(family, FAMILIES)}")
        return self._entries[family]

    def names(self, family: str) -> list[str]:
        return sorted(self._family(family))

    def entries(self, family: str) -> list[Entry]:
        return [self._family(family)[n] for n in self.names(family)]

    def get(self, family: str, name: str) -> Entry:
        entries = self._family(family)
        if not isinstance(name, str):
            raise TypeError(f"{family}: name = {name!r} is invalid; must be a string, one of "
                            f"{', '.join(sorted(entries)) or '(none registered)'}")
        if name not in entries:
            raise UnknownNameError(
                f"{family}: name {name!r} is not registered; known: "
                f"{', '.join(sorted(entries)) or '(none registered)'}"
                f"{did_you_mean(name, entries)}")
        return entries[name]

    def find(self, name: str) -> list[Entry]:
        """Every implementation registered as ``name``, in any family (family order)."""
        return [self._entries[family][name] for family in FAMILIES
                if name in self._entries[family]]

    def create(self, family: str, name: str, **params) -> Any:
        """Build implementation ``name`` of ``family`` with ``params``."""
        return self.get(family, name).create(**params)

    def to_json(self) -> dict:
        """The stable JSON document printed by ``granframe plugins --json`` (docs/plugins.md)."""
        return {
            "schema": "granframe.plugins/1",
            "granframe_version": __version__,
            "families": {family: [e.to_dict() for e in self.entries(family)] for family in FAMILIES},
        }


def disabled_plugins() -> set[str]:
    """Plugin names listed in ``GRANFRAME_DISABLE_PLUGINS``."""
    return {n.strip() for n in os.environ.get(DISABLE_ENV, "").split(",") if n.strip()}


def get_plugin_manager() -> tuple[pluggy.PluginManager, dict[str, Source]]:
    """Plugin manager with the entry-point plugins, the built-ins among them, plus their
    sources.

    The built-ins (entry point :data:`BUILTIN_PLUGIN`) are registered last, whatever the
    order of discovery: pluggy calls the last registered first, so the built-ins register
    their names first and a third party's clash is the one reported.
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    blocked = disabled_plugins()
    for name in blocked:
        pm.set_blocked(name)
    sources: dict[str, Source] = {}
    discovered = importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)
    # sorted is stable: the built-ins move to the end, the others keep their order
    for ep in sorted(discovered, key=lambda ep: ep.name == BUILTIN_PLUGIN):
        if pm.is_blocked(ep.name):
            continue
        dist = ep.dist
        source = Source(ep.name, dist.name if dist else None, dist.version if dist else None)
        if ep.name in sources:
            raise PluginError(f"two plugins are named '{ep.name}': {sources[ep.name]} and "
                              f"{source}; uninstall one or disable with {DISABLE_ENV}")
        try:
            plugin = ep.load()
        except check.USER_CODE_FAILURES as exc:  # third-party code, reported with its origin
            raise PluginError(f"cannot load {source} (entry point {ep.value!r}): "
                              f"{check.raised(exc)}; disable it with "
                              f"{DISABLE_ENV}={ep.name}") from exc
        try:
            pm.register(plugin, name=ep.name)
        except pluggy.PluginValidationError as exc:
            raise PluginError(f"{source} does not match granframe's hooks: {exc}") from exc
        sources[ep.name] = source
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        raise PluginError(f"{exc} (a misspelled granframe_ hook?)") from exc
    return pm, sources


@functools.lru_cache(maxsize=1)
def default_registries() -> Registries:
    """The registries of this process (built on first use, then cached)."""
    return Registries(*get_plugin_manager())
