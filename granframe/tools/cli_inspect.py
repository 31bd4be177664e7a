"""The commands of ``granframe`` that look at what exists without running anything:
``plugins`` (the registered implementations), ``info`` and ``check`` (what a store
holds, and whether its chunks are intact) and ``plot`` (a run store's figures).
"""

from __future__ import annotations

import json
import sys

from granframe import __version__


def plugins_command(args) -> int:
    """``granframe plugins``: every family's implementations, one family's, or one
    implementation, in words or as JSON."""
    from granframe.registry import FAMILIES, default_registries

    registries = default_registries()
    families = list(FAMILIES)
    if len(args.names) == 1 and args.names[0] in FAMILIES:
        families = args.names
    elif args.names:
        entry = _entry(registries, args.names)
        if args.json:
            json.dump(_entry_document(entry), sys.stdout, indent=2)
            sys.stdout.write("\n")
        else:
            print(_entry_text(entry))
        return 0
    if args.json:
        document = registries.to_json()
        document["families"] = {f: document["families"][f] for f in families}
        json.dump(document, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    for family in families:
        entries = registries.entries(family)
        print(f"{family} ({len(entries)})")
        if not entries:
            print("    (none registered)")
        width = max((len(e.name) for e in entries), default=0)
        for e in entries:
            print(f"    {e.name:<{width}}  {e.description}  [{e.source}]")
    return 0


def _entry(registries, names):
    """The registered implementation that ``plugins NAME`` or ``plugins FAMILY NAME``
    means; an unknown one gets the closest name."""
    from granframe.errors import UnknownNameError
    from granframe.registry import FAMILIES, did_you_mean

    if len(names) > 2:
        raise ValueError(f"plugins: parameter 'names' = {' '.join(names)!r} is invalid; give "
                         "NAME or FAMILY NAME, e.g. granframe plugins collision_kernels vhs")
    if len(names) == 2:
        return registries.get(*names)
    [name] = names
    found = registries.find(name)
    if len(found) > 1:
        raise UnknownNameError(f"plugins: name {name!r} is registered in several families "
                               f"({', '.join(e.family for e in found)}); give FAMILY NAME, "
                               f"e.g. granframe plugins {found[0].family} {name}")
    if not found:
        known = [n for family in FAMILIES for n in registries.names(family)] + list(FAMILIES)
        raise UnknownNameError(f"plugins: name {name!r} is not registered in any family"
                               f"{did_you_mean(name, known)} (granframe plugins lists them)")
    return found[0]


def _entry_document(entry) -> dict:
    """``granframe plugins NAME --json`` (docs/plugins.md)."""
    parameters = entry.parameters()
    return {"schema": "granframe.plugin/1", "granframe_version": __version__,
            "family": entry.family, **entry.to_dict(), "factory": entry.factory_path,
            "summary": entry.summary(),
            "parameters": None if parameters is None else [p.to_dict() for p in parameters]}


def _entry_text(entry) -> str:
    """``granframe plugins NAME``: one implementation in words."""
    from granframe.registry import OPERATOR_ARGUMENTS

    lines = [f"{entry.name} ({entry.family})",
             f"  description  {entry.description}",
             f"  source       {entry.source}",
             f"  factory      {entry.factory_path}"]
    summary = entry.summary()
    if summary and summary != entry.description:
        lines.append(f"  summary      {summary}")
    parameters = entry.parameters()
    after = (f" (after {', '.join(OPERATOR_ARGUMENTS)})"
             if entry.family == "collision_operators" else "")
    if parameters is None:
        lines.append("parameters: not known (the factory has no signature)")
    elif not parameters:
        lines.append(f"parameters{after}: none")
    else:
        lines.append(f"parameters{after}:")
        rows = [(p.name, p.type or "-", "required" if p.required else f"default {p.default!r}")
                for p in parameters]
        widths = [max(len(row[i]) for row in rows) for i in range(2)]
        lines.extend(f"  {n:<{widths[0]}}  {t:<{widths[1]}}  {d}" for n, t, d in rows)
    return "\n".join(lines)


def info_command(args) -> int:
    """``granframe info``: what a run or sweep store holds (``--json``: a run store's
    document, :func:`_info_document`)."""
    if args.json:
        json.dump(_info_document(args.store), sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0
    from granframe.run.storage import describe, store_kind
    from granframe.run.sweep import describe_sweep

    print(describe_sweep(args.store) if store_kind(args.store) == "sweep"
          else describe(args.store))
    return 0


def _info_document(path) -> dict:
    """``granframe info STORE --json``: what ``info`` says of a run store, as JSON
    (docs/runner.md): the store's metadata and progress as stored, and the range of its
    snapshots and moments."""
    from granframe.run.storage import RunStore, StoreDamagedError, store_kind, summarise

    if store_kind(path) == "sweep":
        raise ValueError(f"info: parameter 'store' = '{path}' is invalid; --json describes "
                         f"run stores, and it is a sweep store (granframe info {path} "
                         "describes it)")
    store = RunStore.open(path)   # refuses what is not a run store
    problems = store.verify([n for n in store.array_names() if n != "f"])
    if problems:
        raise StoreDamagedError(f"store '{path}' is damaged: {summarise(problems)} "
                                "(granframe check lists every problem)", problems)
    group, progress = store.group, store.progress
    document = {"schema": "granframe.info/1", "store": str(store.path),
                "metadata": store.metadata, "progress": progress, "snapshots": None,
                "moments": None}
    if progress.get("snapshots"):
        times = group["time"][:int(progress["snapshots"])]
        document["snapshots"] = {"count": len(times), "shape": list(group["f"].shape[1:]),
                                 "first_time": float(times[0]), "last_time": float(times[-1])}
    if progress.get("records"):
        n = int(progress["records"])
        # a space run records totals over the interval (no kurtosis; T is per cell)
        names = (("mass", "kinetic_energy", "min_f") if "space" in store.metadata
                 else ("mass", "temperature", "kurtosis", "min_f"))
        document["moments"] = {
            "records": n, "first_time": float(group["step_time"][0]),
            "last_time": float(group["step_time"][n - 1]), "steps": int(group["step"][n - 1]),
            **{name: {"first": float(group[name][0]), "last": float(group[name][n - 1])}
               for name in names}}
    return document


def check_command(args) -> int:
    """``granframe check``: every committed chunk of a store read; 3 when one is missing or
    damaged."""
    from granframe.run.storage import check

    intact, lines = check(args.store)
    print("\n".join(lines))
    print("intact" if intact else "DAMAGED: the chunks above are missing or fail their "
          "checksum; granframe run --resume --rollback continues from the last intact commit")
    return 0 if intact else 3


def plot_command(args) -> int:
    """``granframe plot``: the figures of a run store written, one path a line
    (:func:`granframe.tools.plotting.plot`)."""
    from granframe.tools.plotting import plot

    for path in plot(args.store, args.out, format=args.format, dpi=args.dpi,
                     animation=args.animate):
        print(path)
    return 0
