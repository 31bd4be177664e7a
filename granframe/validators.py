"""Validators shared by the attrs configuration classes.

Every message has the same shape -- ``<owner>: parameter '<name>' = <value!r>
is invalid; <what is allowed>`` -- so a user always learns which parameter,
which value and what would have been accepted.
"""

from __future__ import annotations

import difflib
import math
import numbers
import pathlib
from typing import Any, Callable

import attrs
import numpy


def _plain(value):
    """``value`` with NumPy scalars as Python numbers (in lists and tuples too), so that a
    message shows 0.5, not np.float64(0.5)."""
    if isinstance(value, numpy.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(v) for v in value)
    return value


def reject(owner: str, name: str, value: Any, allowed: str, *, error=ValueError):
    """Raise ``error`` with granframe's standard message (NumPy scalars shown as numbers)."""
    shown = repr(_plain(value))
    if len(shown) > 80:
        shown = shown[:77] + "..."
    raise error(f"{owner}: parameter '{name}' = {shown} is invalid; {allowed}")


#: what user code (an initial condition, a kernel's angular part, a module it names) may
#: raise that granframe reports as that code's failure: any error, and a ``sys.exit``
#: inside it (KeyboardInterrupt still stops the run)
USER_CODE_FAILURES = (Exception, SystemExit)


def raised(exc: BaseException) -> str:
    """What user code raised, for a message: ``TypeError: ...``, or for a ``sys.exit``
    inside it ``SystemExit (it called sys.exit(0))``."""
    if isinstance(exc, SystemExit):
        return f"SystemExit (it called sys.exit({exc.code!r}))"
    return f"{type(exc).__name__}: {exc}"


def existing_file(owner: str, name: str, path, expected: str) -> None:
    """Refuse a ``path`` that is not a file: missing ("no such file"), or a directory
    (a zarr store such as a run's, or another), saying what the command takes
    (``expected``)."""
    path = pathlib.Path(path)
    if path.is_file():
        return
    if not path.exists():
        reject(owner, name, str(path), "no such file")
    if (path / "zarr.json").is_file():
        reject(owner, name, str(path), f"is a zarr store (a run's or a sweep's), not a file; "
               f"{owner} takes {expected}; `granframe info` says what a store holds, and a "
               "run store is continued by `granframe run DESCRIPTION --out STORE --resume`")
    reject(owner, name, str(path), f"is a directory, not a file; {owner} takes {expected}")


def distinct(value: float, limit: float, digits: int = 3) -> tuple[str, str]:
    """``value`` and ``limit`` with ``digits`` significant digits, or as many more as make
    them differ (17 tell any two floats apart), for messages comparing a value with its
    limit: a share of 0.01004 above a tolerance of 0.01 reads "0.01004 > 0.01"."""
    for n in range(digits, 18):
        shown = f"{value:.{n}g}", f"{limit:.{n}g}"
        if shown[0] != shown[1]:
            break
    return shown


def _owner(instance) -> str:
    return type(instance).__name__


def is_real(value) -> bool:
    """True for finite-or-not real scalars, excluding ``bool``."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def is_integer(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def cell_edges(owner: str, edges):
    """``edges`` as a float array: 1-D, at least 2 finite, strictly increasing cell edges
    (the cells [e_i, e_{i+1}] of a cell-average function); refused by name otherwise."""
    e = numpy.asarray(edges, dtype=float)
    if e.ndim != 1 or e.size < 2 or not numpy.isfinite(e).all() or not numpy.all(numpy.diff(e) > 0):
        reject(owner, "edges", edges, "must be a 1-D array of at least 2 finite, "
               "strictly increasing cell edges")
    return e


def time_point(owner: str, t):
    """``t`` as a float: a finite real number >= 0 (the time of an exact solution)."""
    if not is_real(t) or not (0.0 <= float(t) < math.inf):
        reject(owner, "t", t, "must be a finite real number >= 0")
    return float(t)


def rule_points(owner: str, points):
    """``points`` as an int: the number of Gauss-Legendre points of a quadrature, in
    [1, 100]."""
    if not is_integer(points) or not 1 <= points <= 100:
        reject(owner, "points", points, "must be an integer in [1, 100]")
    return int(points)


def real(lower: float = -math.inf, upper: float = math.inf, *,
         lower_open: bool = False, upper_open: bool = False) -> Callable:
    """attrs validator: a finite real number in the given interval."""
    lo = "(" if lower_open else "["
    hi = ")" if upper_open else "]"
    interval = f"{lo}{lower:g}, {upper:g}{hi}"

    def validate(instance, attribute: attrs.Attribute, value):
        owner = _owner(instance)
        if not is_real(value):
            reject(owner, attribute.name, value,
                   f"must be a real number in {interval}", error=TypeError)
        try:
            v = float(value)
        except OverflowError:
            v = math.inf
        if not math.isfinite(v):
            reject(owner, attribute.name, value, f"must be finite, in {interval}")
        if v < lower or v > upper or (lower_open and v == lower) or (upper_open and v == upper):
            reject(owner, attribute.name, value, f"must lie in {interval}")

    return validate


def integer(lower: int | None = None, upper: int | None = None, *,
            even: bool = False, choices: tuple[int, ...] | None = None) -> Callable:
    """attrs validator: an integer (not bool) with optional bounds, parity or choices."""

    def describe() -> str:
        if choices is not None:
            return f"must be one of {list(choices)}"
        parts = ["an even integer" if even else "an integer"]
        if lower is not None:
            parts.append(f">= {lower}")
        if upper is not None:
            parts.append(f"and <= {upper}" if lower is not None else f"<= {upper}")
        return "must be " + " ".join(parts)

    def validate(instance, attribute: attrs.Attribute, value):
        owner = _owner(instance)
        if not is_integer(value):
            reject(owner, attribute.name, value, describe(), error=TypeError)
        v = int(value)
        bad = ((lower is not None and v < lower) or (upper is not None and v > upper)
               or (even and v % 2) or (choices is not None and v not in choices))
        if bad:
            reject(owner, attribute.name, value, describe())

    return validate


def one_of(choices) -> Callable:
    """attrs validator: one of the names ``choices``."""

    def validate(instance, attribute: attrs.Attribute, value):
        if not (isinstance(value, str) and value in choices):
            reject(_owner(instance), attribute.name, value, f"must be one of {list(choices)}")

    return validate


def to_float(value):
    """attrs converter: real numbers become ``float``; anything else passes to the validator."""
    if not is_real(value):
        return value
    try:
        return float(value)
    except OverflowError:  # an integer too large for a float: the validator reports it
        return value


def to_int(value):
    """attrs converter: integers (including NumPy's) become ``int``."""
    return int(value) if is_integer(value) else value


def optional_positive(instance, attribute: attrs.Attribute, value):
    """attrs validator: ``None`` or a finite real number > 0."""
    if value is not None:
        real(0.0, math.inf, lower_open=True)(instance, attribute, value)


def boolean(instance, attribute: attrs.Attribute, value):
    """attrs validator: exactly ``True`` or ``False``."""
    if not isinstance(value, bool):
        reject(_owner(instance), attribute.name, value, "must be True or False", error=TypeError)


def did_you_mean(word, choices) -> str:
    """``"; did you mean 'x'?"`` for the choice closest to ``word``
    (:func:`difflib.get_close_matches`), or ``""`` when none is close."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1)
    return f"; did you mean '{close[0]}'?" if close else ""


def from_table(cls, table: dict, owner: str):
    """``cls(**table)`` for an attrs class, an unknown key reported with the keys it knows
    (the parameters of ``__init__``; private state is not one) and the closest of them, a
    missing required one by name."""
    known = {a.alias or a.name for a in attrs.fields(cls) if a.init}
    unknown = sorted(set(table) - known)
    if unknown:
        reject(owner, unknown[0], table[unknown[0]],
               f"is not a parameter of {cls.__name__}; known: {', '.join(sorted(known))}"
               f"{did_you_mean(unknown[0], known)}", error=TypeError)
    missing = [a.alias or a.name for a in attrs.fields(cls)
               if a.init and a.default is attrs.NOTHING and (a.alias or a.name) not in table]
    if missing:
        reject(owner, missing[0], None, f"is required by {cls.__name__} (it has no default)",
               error=TypeError)
    return cls(**table)
