"""The commands of ``granframe`` that plan a run before it is made: ``limits`` (the explicit
time-step limits and the run's cost), ``advise`` (the cheapest configuration for a
scene, or a space run priced with a hierarchy of collision models) and ``bench`` (the
fast operator timed against the FFT floor).
"""

from __future__ import annotations

import json
import pathlib
import sys

from granframe import __version__
from granframe.tools.cli_inputs import load_study, read_toml, with_settings


def bench_command(args) -> int:
    """``granframe bench``: the fast operator (or a space step) timed against the FFT floor,
    as a table or JSON (:mod:`granframe.tools.bench`)."""
    from granframe.tools import bench

    from granframe.backends import AUTO, resolve_backend

    backend = resolve_backend(AUTO if args.backend is None else args.backend)
    if args.space is not None:
        configs = ([bench.parse_space_config(c) for c in args.space] if args.space
                   else list(bench.DEFAULT_SPACE_CONFIGS))
        records = bench.run_space(configs, backend, args.threads, args.repeats)
        heading = (f"space step (Strang: transport, RK4 collisions on all cells, transport), "
                   f"backend {backend}, {args.threads} threads, median of {args.repeats} "
                   "rounds after warm-up")
        table = bench.space_table
    else:
        configs = ([bench.parse_config(c) for c in args.config] if args.config
                   else list(bench.DEFAULT_CONFIGS))
        records = bench.run(configs, backend, args.threads, args.repeats, args.precision,
                            batches=args.batch or (1,), quadratures=args.quadrature or (None,))
        heading = (f"fast_spectral, backend {backend}, {args.threads} threads, "
                   f"{args.precision}, median of {args.repeats} evaluations after warm-up"
                   + (", B distributions per evaluation (time and floor per distribution)"
                      if args.batch else ""))
        table = bench.table
    if args.json:
        json.dump({"schema": "granframe.tools.bench/1", "granframe_version": __version__,
                   "records": records}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(heading)
        print(table(records))
    return 0


def _limit_runs(args) -> tuple[dict, bool]:
    """The runs ``limits`` reports: each description as given (``--set`` applied) but with
    ``health.step_limit = false``, so that one whose step is above the transport's CFL
    limit is built and reported rather than refused; and whether ``granframe run`` would
    check the step limits (the ``health.step_limit`` the description asks for)."""
    from granframe.run.description import RunDescription

    path = pathlib.Path(args.source)
    unchecked = ["health.step_limit=false"]
    if path.suffix == ".toml" and path.is_file() and not args.quick:
        table = read_toml(path, "limits", "source")
        health = table.get("health")
        checked = health.get("step_limit", True) if isinstance(health, dict) else True
        table["health"] = {**(health if isinstance(health, dict) else {}), "step_limit": False}
        runs = {"": RunDescription.from_dict(table)}
    else:
        runs = load_study(args.source, args.quick).runs
        checked = all(d.health.step_limit for d in runs.values())
    for setting in args.set:
        key, _, value = setting.partition("=")
        if key.strip() == "health.step_limit":
            checked = value.strip() != "false"
    return ({name: with_settings(d, args.set + unchecked) for name, d in runs.items()},
            checked)


def _advise_rescaled(description, as_json: bool) -> int:
    """``granframe advise`` on a rescaled run description: priced as it is, one step timed
    (:func:`~granframe.run.problems.run_cost`); a hierarchy of collision models, which a
    rescaled run cannot take (its fluid levels have no self-similar drift), is not priced
    beside it."""
    from granframe.parallel import SerialCommunicator
    from granframe.run.problems import make_problem, run_cost

    cost = run_cost(make_problem(description, communicator=SerialCommunicator()), repeats=3)
    why = ("a rescaled run: priced as it is; a hierarchy of collision models is not priced "
           "beside it, since its fluid levels have no self-similar drift (docs/space.md)")
    if as_json:
        json.dump({"schema": "granframe.run_cost/1", "rescaled": True, "note": why,
                   **cost.to_dict()}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"{why}\n{cost.text()}")
    return 0


def limits_command(args) -> int:
    """``granframe limits``: the time-step limits of each run and its cost, as lines or
    JSON; 3 when a fixed time step is above a limit."""
    from granframe.run.problems import time_step_limit

    runs, checked = _limit_runs(args)
    refused = ("granframe run refuses it" if checked else
               "health.step_limit = false: granframe run does not check it")
    status, document = 0, {}
    for name, d in runs.items():
        limit = time_step_limit(d)
        adaptive = d.build("integrator").adaptive
        above = limit is not None and not adaptive and d.time_step > limit.limit
        transport = None if d.space is None else d.space.transport_limit(d.grid)
        above_cfl = transport is not None and d.time_step > transport * (1 + 1e-12)
        status = 3 if above or above_cfl else status
        document[name] = {
            "integrator": d.integrator.name, "time_step": d.time_step, "adaptive": adaptive,
            "limit": None if limit is None or adaptive else limit.limit,
            "interval": None if limit is None or adaptive else limit.interval,
            "dominant": None if limit is None else str(limit.dominant),
            "rates": {} if limit is None else {str(k): v for k, v in limit.rates.items()},
            "within": None if limit is None or adaptive else not above,
            **({} if transport is None else {"transport_limit": transport,
                                             "within_transport_limit": not above_cfl})}
        cost = None if args.no_cost else _limit_cost(d)
        document[name]["cost"] = None if cost is None or isinstance(cost, str) else (
            cost.to_dict())
        if args.json:
            continue
        head = (f"[{name}] " if name else "") + f"'{d.integrator.name}': "
        if transport is not None:
            axes = "" if d.space.dimension == 1 else ", both axes at once"
            print((f"[{name}] " if name else "") + f"transport ('{d.space.reconstruction.name}',"
                  f" SSP RK3 half steps{axes}): dt <= {transport:.4g}; time_step = "
                  f"{d.time_step:g} is " + (f"ABOVE it ({refused})" if above_cfl else
                                            f"within it ({d.time_step / transport:.3g} of it)"))
        _limit_table(head, d, limit, adaptive, above, refused)
        if cost is not None:
            print((f"[{name}] " if name else "") + (cost if isinstance(cost, str)
                                                    else cost.text()))
    if args.json:
        json.dump({"schema": "granframe.limits/1", "runs": document}, sys.stdout, indent=2)
        sys.stdout.write("\n")
    return status


def _limit_cost(description):
    """The run's :class:`~granframe.run.problems.RunCost` (its problem built and one step
    timed), or why it could not be estimated."""
    from granframe.run.problems import make_problem, run_cost

    try:
        return run_cost(make_problem(description))
    except (ValueError, MemoryError, FloatingPointError) as exc:
        return f"estimated cost: not estimated ({type(exc).__name__}: {exc})"


def _limit_table(head, d, limit, adaptive, above, refused) -> None:
    """The lines of ``granframe limits`` on the collisions' explicit step limit of ``d``."""
    from granframe.registry import default_registries
    from granframe.stepping.stability import PART_NAMES

    if limit is None:
        print(head + "no explicit step limit (the scheme treats none of the equation's "
              "stiff parts explicitly)")
        return
    radii = ", ".join(f"{PART_NAMES.get(part, part)} = {rate:.4g}" for part, rate in
                      sorted(limit.rates.items(), key=lambda x: -x[1]))
    if limit.interval == 0.0:
        registry = default_registries()
        stable = sorted(n for n in registry.names("time_integrators") if getattr(
            registry.get("time_integrators", n).factory, "imaginary_interval", 0.0) > 0.0)
        print(head + f"unstable at any step: {PART_NAMES['drift']} has an imaginary "
              f"spectrum (radii: {radii}) and the scheme is not stable on the imaginary "
              f"axis; use one that is: {', '.join(stable)}")
        return
    if adaptive:
        print(head + f"adaptive: its error control keeps the steps stable (spectral "
              f"radii: {radii})")
        return
    print(head + f"dt <= {limit.limit:.4g}, set by {PART_NAMES.get(limit.dominant)} "
          f"(spectral radii: {radii}; stable for dt * (sum of radii) <= "
          f"{limit.interval:g})")
    if above:
        print(f"  time_step = {d.time_step:g}: ABOVE the limit ({refused})")
    else:
        print(f"  time_step = {d.time_step:g}: within it ({d.time_step / limit.limit:.3g} "
              "of the limit)")


def advise_command(args) -> int:
    """``granframe advise``: a scene (no ``grid``) gets the advice of
    :func:`~granframe.tools.advise.advise`; a run description with a ``[space]`` table (it
    has a ``grid``) is priced as it is, all-kinetic and with a hierarchy of collision models
    (:func:`~granframe.tools.advise.price_hierarchy`)."""
    from granframe.run.description import RunDescription
    from granframe.tools.advise import Scene, advise, price_hierarchy
    from granframe.validators import existing_file

    path = pathlib.Path(args.scene)
    existing_file("advise", "scene", path, "a .toml scene or description")
    data = read_toml(path, "advise", "scene")
    if "grid" in data:
        if args.out:
            raise ValueError(f"advise: parameter '--out' = '{args.out}' is invalid; it writes "
                             f"the description advised for a scene, and '{path}' is a run "
                             "description (it has a grid), priced as it is: add the "
                             "fragment the report shows to it instead")
        description = RunDescription.from_dict(data)
        if description.space is not None and description.space.dimension > 1:
            raise ValueError(f"advise: parameter 'space.cells' = {list(description.space.cells)}"
                             " is invalid; advise prices runs on an interval, not yet on a "
                             "rectangle (its hierarchy and its costs per axis are not "
                             "modelled): granframe limits gives the step limits and the "
                             "estimated cost of a run on a rectangle")
        if description.rescaled:
            return _advise_rescaled(description, args.json)
        price = price_hierarchy(description)
        if args.json:
            json.dump({"schema": "granframe.hierarchy_price/1", **price.to_dict()}, sys.stdout,
                      indent=2)
            sys.stdout.write("\n")
        else:
            print(price.report())
        return 0
    advice = advise(Scene.from_dict(data))
    if args.json:
        json.dump({"schema": "granframe.advice/1", "closed_form": advice.closed_form,
                   "errors": advice.errors, "predicted_seconds": advice.predicted_seconds,
                   "evaluation_seconds": advice.evaluation_seconds,
                   "evaluations": advice.evaluations, "reasons": list(advice.reasons),
                   "description": None if advice.description is None
                   else advice.description.to_dict(),
                   "space": None if advice.space is None else advice.space.to_dict()},
                  sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(advice.report())
    if args.out and advice.description is not None:
        pathlib.Path(args.out).write_text(advice.description.to_toml())
        if not args.json:
            print(f"description: {args.out} (granframe run {args.out} --out STORE)")
    return 0
