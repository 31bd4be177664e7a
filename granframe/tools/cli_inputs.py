"""What the commands of ``granframe`` read from their arguments: the text of a TOML file,
a study module's runs, and a description with the ``--set KEY=VALUE`` overrides
applied (``run`` and ``limits``).
"""

from __future__ import annotations

import pathlib

import attrs


def read_text(path: pathlib.Path, command: str, parameter: str) -> str:
    """The text of the file ``path``; a file that is not UTF-8 text refused naming it."""
    try:
        return path.read_text()
    except UnicodeDecodeError as exc:
        raise ValueError(f"{command}: parameter '{parameter}' = '{path}' is invalid; it is not "
                         f"UTF-8 text ({exc.reason} at byte {exc.start}): a TOML file is "
                         "expected") from None


def read_toml(path: pathlib.Path, command: str, parameter: str) -> dict:
    """The TOML table of the file ``path`` (:func:`read_text`); invalid TOML refused naming
    the file."""
    import tomllib

    try:
        return tomllib.loads(read_text(path, command, parameter))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{command}: the TOML text of '{path}' is invalid: {exc}") from None


def load_study(source, quick: bool):
    """:func:`~granframe.run.runner.load_study`, a source that is not text and a study
    that exits (``sys.exit`` while it is imported or makes its runs) refused naming it."""
    from granframe.run.runner import load_study

    try:
        return load_study(source, quick=quick)
    except UnicodeDecodeError as exc:
        raise ValueError(f"run: parameter 'source' = '{source}' is invalid; it is not UTF-8 "
                         f"text ({exc.reason} at byte {exc.start}): a .toml description or a "
                         ".py study module is expected") from None
    except SystemExit as exc:
        raise ValueError(f"run: study '{source}' is invalid; it called sys.exit({exc.code!r}) "
                         "while granframe loaded it or made its runs, so it gives no run: a "
                         "study module defines description(quick) or runs(quick) and does "
                         "not exit") from None


def with_settings(description, settings: list[str]):
    """``description`` with each ``KEY=VALUE`` of ``run --set`` applied, in order.

    KEY is a dotted key of the description's table (``grid.n_modes``,
    ``operator.sphere.n_points``, ``kernel.name``); one that the description cannot have
    is refused with the closest that it can. The grid's half width and truncation radius,
    when they are the ones its support radius implies, are derived again from the new
    one. VALUE is read as a TOML value (``64``, ``0.5``, ``true``, ``"rk4"``, ``[1, 2]``,
    ``{name = "lebedev", order = 7}``), or taken as a string when it is not one
    (``kernel.name=hard_spheres``).
    """
    import tomllib

    from granframe.registry import did_you_mean
    from granframe.run.description import RunDescription

    data = description.to_dict()
    derived = attrs.evolve(description.grid, half_width=None, truncation_radius=None)
    for key in ("half_width", "truncation_radius"):   # they follow --set grid.support_radius
        if getattr(derived, key) == getattr(description.grid, key):
            del data["grid"][key]
    for setting in settings:
        key, equals, text = setting.partition("=")
        key = key.strip()
        if not equals or not key:
            raise ValueError(f"run: parameter 'set' = {setting!r} is invalid; must be "
                             "KEY=VALUE, e.g. --set grid.n_modes=64")
        known = _settable_keys(data)
        if key not in known:
            raise ValueError(f"run: parameter 'set' = {setting!r} is invalid; '{key}' is not "
                             f"a key of the description{did_you_mean(key, known)}")
        try:
            value = tomllib.loads(f"value = {text.strip()}")["value"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        *parents, last = key.split(".")
        node = data
        for part in parents:
            child = node.get(part)
            node[part] = node = ({"name": child} if isinstance(child, str)
                                 else child if isinstance(child, dict) else {})
        node[last] = value
    return RunDescription.from_dict(data)


def _settable_keys(data: dict) -> list[str]:
    """The dotted keys a description table ``data`` can have: every key it has, every
    field of RunDescription and of its grid, output, health and space tables, and for each
    component (and each quadrature among the operator's options, and the reconstruction
    and walls of the space table) ``name`` and the parameters of the implementation it
    names."""
    from granframe.backends import resolve_backend
    from granframe.registry import default_registries
    from granframe.run.description import (COMPONENT_FAMILIES, Health, Output,
                                           RunDescription, Space)
    from granframe.velocity.grid import VelocityGrid

    def present(table, prefix=""):
        for key, value in table.items():
            yield prefix + key
            if isinstance(value, dict):
                yield from present(value, f"{prefix}{key}.")

    def parameters(family, table, prefix):
        name = table.get("name") if isinstance(table, dict) else table
        yield f"{prefix}name"
        if not isinstance(name, str):
            return
        try:
            entry = default_registries().get(
                family, resolve_backend(name) if family == "array_backends" else name)
        except ValueError:   # an unknown name: the description names the closest
            return
        yield from (prefix + p.name for p in entry.parameters() or ())

    keys = set(present(data))
    tables = {"grid": VelocityGrid, "output": Output, "health": Health, "space": Space}
    for field in attrs.fields(RunDescription):
        if field.init:
            keys.add(field.alias or field.name)
    for table, cls in tables.items():
        keys.update(f"{table}.{f.alias or f.name}" for f in attrs.fields(cls) if f.init)
    for field, family in COMPONENT_FAMILIES.items():
        keys.update(parameters(family, data.get(field), f"{field}."))
    operator = data.get("operator")
    for option, value in (operator.items() if isinstance(operator, dict) else ()):
        if isinstance(value, dict):
            keys.update(parameters("quadratures", value, f"operator.{option}."))
    space = data.get("space") if isinstance(data.get("space"), dict) else {}
    for field in ("reconstruction", "left", "right"):
        keys.update(parameters("reconstructions" if field == "reconstruction" else "boundaries",
                               space.get(field, "muscl" if field == "reconstruction"
                                         else "periodic"), f"space.{field}."))
    return sorted(keys)
