"""The components of a run description: a registered name with its parameters.

A :class:`Component` names an implementation of a registry family (a kernel, a law, a
boundary, ...) and holds its parameters in their TOML form (:func:`to_plain`: callables by
reference, tuples as lists), so that a description round-trips through TOML and a store.
:func:`check_component` checks one against its registered factory without building it.
The attrs helpers (:func:`component_field`, :func:`instance_of`, :func:`table_of`) are
those of the description's fields (:mod:`granframe.run.description`,
:mod:`granframe.run.space_description`).
"""

from __future__ import annotations

import math
from typing import Any

import attrs

from granframe import validators as check
from granframe.errors import UnknownParameterError
from granframe.model.initial import callable_reference
from granframe.registry import default_registries


def _is_json_scalar(value) -> bool:
    return value is None or isinstance(value, (str, bool, int, float))


def to_plain(owner: str, key: str, value) -> Any:
    """A parameter in TOML/JSON form: callables by reference, tuples as lists."""
    if isinstance(value, dict):
        return {k: to_plain(owner, f"{key}.{k}", v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)):
        return [to_plain(owner, key, v) for v in value]
    if attrs.has(type(value)):
        return to_plain(owner, key, attrs.asdict(value, recurse=False))
    if callable(value):
        reference = callable_reference(value)
        if reference is None:
            check.reject(owner, key, value, "is a callable that cannot be written to TOML or a "
                         "store: use a module-level function or a 'module:function' string")
        return reference
    if isinstance(value, float) and not math.isfinite(value):
        check.reject(owner, key, value, "must be finite")
    if not _is_json_scalar(value):
        check.reject(owner, key, value, "must be a number, string, boolean, list or table",
                     error=TypeError)
    return value


@attrs.frozen
class Component:
    """A registered implementation: ``name`` in a family, with its parameters."""

    name: str = attrs.field()
    params: dict = attrs.field(factory=dict)

    @name.validator
    def _check_name(self, attribute, value):
        if not isinstance(value, str) or not value:
            check.reject("Component", "name", value, "must be a non-empty string", error=TypeError)

    @params.validator
    def _check_params(self, attribute, value):
        if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
            check.reject("Component", "params", value, "must be a table of named parameters",
                         error=TypeError)

    @classmethod
    def coerce(cls, value) -> "Component":
        """A Component from itself, a name, or a table ``{name = ..., <params>}``."""
        if isinstance(value, Component):
            return value
        if isinstance(value, str):
            return cls(value)
        if isinstance(value, dict):
            params = dict(value)
            if "name" not in params:
                check.reject("Component", "name", None, f"is missing from the table {value!r}")
            return cls(params.pop("name"), params)
        check.reject("Component", "value", value, "must be a name or a table with a 'name' key",
                     error=TypeError)

    def to_dict(self, owner: str) -> dict:
        return {"name": self.name, **to_plain(owner, owner, self.params)}


def coerce_component(value):
    """:meth:`Component.coerce` for an attrs converter: a value it cannot take is returned
    as it is, for the field's validator (:func:`instance_of`) to report against the field."""
    try:
        return Component.coerce(value)
    except (TypeError, ValueError):
        return value


def table_of(cls):
    """attrs converter: a table (a dict) of the parameters of ``cls`` made into one (other
    values are left for the field's validator)."""
    def convert(value):
        return check.from_table(cls, value, "RunDescription") if isinstance(value, dict) else value
    return convert


def instance_of(cls, what, owner="RunDescription"):
    """An attrs validator refusing a value that is not a ``cls`` (``what`` says so in words)."""
    def validate(instance, attribute, value):
        if not isinstance(value, cls):
            check.reject(owner, attribute.name, value, f"must be {what}", error=TypeError)
    return validate


def component_field(**kwargs):
    """An attrs field holding a :class:`Component`, given as one, a name or a table."""
    return attrs.field(converter=coerce_component,
                       validator=instance_of(Component, "a name or a table"), **kwargs)


def check_component(family: str, component: Component, owner: str = "RunDescription",
                    **arguments) -> None:
    """Check ``component`` against its registered factory without calling it.

    The name must be registered in ``family``; the parameters (with ``arguments``, the
    ones the caller passes besides them) must bind to the factory's signature; and for an
    attrs class each parameter goes through its converter and validators (as in
    ``__init__``, but without ``__attrs_post_init__``, where a backend imports its array
    module). Nothing is built: a description naming a backend that this machine lacks
    (``cupy``) is valid here.
    """
    entry = default_registries().get(family, component.name)   # unknown names: clear error
    params = {**arguments, **component.params}
    try:
        entry.check_parameters(component.params, arguments)   # names the closest parameter
    except UnknownParameterError as exc:
        if family == "collision_operators":
            check.reject(owner, "operator", component.params, f"has an unknown option: {exc}",
                         error=TypeError)
        raise
    if isinstance(entry.factory, type) and attrs.has(entry.factory):
        _check_fields(entry.factory, params)


def _check_fields(cls, params: dict) -> None:
    """Run the converters and validators of the attrs class ``cls`` on ``params`` on an
    instance that is never initialised (so that the validators name ``cls``)."""
    stub = object.__new__(cls)
    for field in attrs.fields(cls):
        if not field.init:
            continue
        key = field.alias or field.name
        if key in params:
            value = params[key]
        elif isinstance(field.default, attrs.Factory):
            value = (field.default.factory(stub) if field.default.takes_self
                     else field.default.factory())
        else:
            value = field.default
        if field.converter is not None:
            value = field.converter(value)
        object.__setattr__(stub, field.name, value)
    for field in attrs.fields(cls):
        if field.init and field.validator is not None:
            field.validator(stub, field, getattr(stub, field.name))
