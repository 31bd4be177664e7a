r"""Error bars from refinement: a family of runs refined together, the observed order, a
Richardson estimate and the grid convergence index of chosen quantities.

A :class:`Refinement` is a base run description, the parameters refined together (the
velocity grid's modes, the cells, the time step; one or several, coarse to fine, each by
the same ratio at every level) and the quantities to report. :func:`run_refinement`
runs the family as a sweep (:mod:`granframe.run.sweep`: one store per member, on Dask
workers, resumed when run again) and :func:`grid_convergence` analyses each quantity
over the three finest members by the procedure of Celik, Ghia, Roache, Freitas, Coleman
& Raad (J. Fluids Eng. 130 (2008) 078001), which puts Roache's grid convergence index
(J. Fluids Eng. 116 (1994) 405; ASME V&V 20-2009) into practice: with h_1 < h_2 < h_3
the members' resolutions (h the node spacing, the cell width or the time step), phi_k
their values, r_21 = h_2 / h_1, r_32 = h_3 / h_2, e_21 = phi_2 - phi_1,
e_32 = phi_3 - phi_2, s = sign(e_32 / e_21),

.. math:: p = \frac{\bigl|\ln|e_{32}/e_{21}| + q(p)\bigr|}{\ln r_{21}},\qquad
          q(p) = \ln\frac{r_{21}^p - s}{r_{32}^p - s},

          \phi_{ext} = \frac{r_{21}^p \phi_1 - \phi_2}{r_{21}^p - 1},\qquad
          \mathrm{GCI}_{fine} = \frac{F_s\, |e_{21} / \phi_1|}{r_{21}^p - 1},\quad F_s = 1.25,

p solved by fixed-point iteration (q = 0 for a constant ratio). With two members the
order is not observed: p is the scheme's formal order, given, and F_s = 3. The error bar of
the finest value is GCI_fine |phi_1|. s < 0 (oscillatory convergence), |e_32| <= |e_21|
(divergent: the members are not in the asymptotic range) and differences at round-off are
reported as such; the index is then not an error bar.

The quantities are read from each member's store (:func:`granframe.open_run`, every
step) by :func:`quantity`: ``NAME[.v1[.v2]][@t=T][,x=X|x=mean][,wall=left|right]``, e.g.
``temperature@t=1,x=0.5`` (linear interpolation between cell centres),
``density@t=1,x=mean``, ``heat_flux.v1@t=2,x=0.25``, ``wall_energy@wall=left`` (the total
through the wall over the run; with ``t=`` its value in that step); a study passes
functions of the dataset instead.
"""

from __future__ import annotations

import json
import math
import pathlib
import re

import attrs
import numpy

from granframe import validators as check

#: the parameters a refinement knows the resolution of, and whether it grows with them
#: (modes, cells: h ~ 1 / value) or is the value (the time step)
RESOLUTIONS = {"grid.n_modes": "inverse", "space.cells": "inverse", "time_step": "direct"}

#: the safety factors of the grid convergence index: three members or more, two
SAFETY = {3: 1.25, 2: 3.0}

_SPEC = re.compile(r"^(?P<name>[A-Za-z_]+)(?P<components>(\.v[1-3]){0,2})"
                   r"(@(?P<selectors>[^@]+))?$")


def _check_values(owner, key, values):
    if not isinstance(values, (list, tuple)) or len(values) < 2:
        check.reject(owner, "vary", {key: values}, "must give at least two values per "
                     "parameter, coarse to fine", error=TypeError)
    numbers = []
    for value in values:
        if not check.is_real(value) or not float(value) > 0 or not math.isfinite(value):
            check.reject(owner, "vary", {key: values}, "must hold positive finite numbers")
        numbers.append(float(value))
    return numbers


@attrs.frozen
class Refinement:
    """A base description refined along one or several parameters together.

    Parameters
    ----------
    base : dict
        A run description table (TOML layout).
    vary : dict
        Dotted parameter (``grid.n_modes``, ``space.cells``, ``time_step``) -> values from
        coarse to fine, all of one length, each refined by the same ratio at every level.
    quantities : tuple
        Quantity specifications (module notes).
    """

    base: dict = attrs.field()
    vary: dict = attrs.field()
    quantities: tuple = attrs.field(converter=tuple)

    def __attrs_post_init__(self):
        owner = "Refinement"
        if not isinstance(self.base, dict):
            check.reject(owner, "base", self.base, "must be a run description table",
                         error=TypeError)
        if not isinstance(self.vary, dict) or not self.vary:
            check.reject(owner, "vary", self.vary, "must map at least one parameter to its "
                         "values", error=TypeError)
        unknown = [key for key in self.vary if key not in RESOLUTIONS]
        if unknown:
            check.reject(owner, "vary", unknown[0], "must be one of "
                         + ", ".join(RESOLUTIONS) + " (a parameter with a known resolution)")
        lengths = {len(v) if isinstance(v, (list, tuple)) else 0 for v in self.vary.values()}
        if len(lengths) != 1:
            check.reject(owner, "vary", {k: len(v) for k, v in self.vary.items()},
                         "must give every parameter the same number of values")
        ratios = None
        for key, values in self.vary.items():
            numbers = _check_values(owner, key, values)
            h = self._spacing(key, numbers)
            steps = [a / b for a, b in zip(h[:-1], h[1:])]
            if any(step <= 1.0 + 1e-12 for step in steps):
                check.reject(owner, "vary", {key: values}, "must go from coarse to fine "
                             "(the resolution refined at every level)")
            if ratios is not None and not numpy.allclose(steps, ratios, rtol=1e-9):
                check.reject(owner, "vary", dict(self.vary), "must refine every parameter "
                             "by the same ratio at each level (their errors are then of one "
                             f"h): ratios {ratios} and {steps}")
            ratios = steps
        if not self.quantities:
            check.reject(owner, "quantities", list(self.quantities), "must name at least one "
                         "quantity")
        for spec in self.quantities:
            if isinstance(spec, str):
                parse(spec)

    @staticmethod
    def _spacing(key, numbers):
        return [1.0 / v for v in numbers] if RESOLUTIONS[key] == "inverse" else list(numbers)

    def spacings(self) -> list[float]:
        """h of each member relative to the coarsest's (1, 1/r, ...), from the first
        parameter."""
        key = next(iter(self.vary))
        h = self._spacing(key, [float(v) for v in self.vary[key]])
        return [x / h[0] for x in h]

    def sweep(self):
        """The family as a sweep: the parameters as zip axes of the base."""
        from granframe.run.sweep import Sweep

        return Sweep(self.base, zip={k: list(v) for k, v in self.vary.items()})


def parse(spec: str) -> dict:
    """The parts of a quantity specification (module notes): name, components, t, x, wall."""
    owner = "quantity"
    if not isinstance(spec, str):
        check.reject(owner, "spec", spec, "must be a text", error=TypeError)
    match = _SPEC.match(spec.strip())
    if not match:
        check.reject(owner, "spec", spec, "must read NAME[.v1[.v2]][@t=T][,x=X|x=mean]"
                     "[,wall=left|right], e.g. 'temperature@t=1,x=0.5'")
    parts = {"name": match["name"], "components": [c for c in match["components"].split(".")
                                                   if c]}
    for selector in (match["selectors"] or "").split(","):
        if not selector:
            continue
        key, _, value = selector.partition("=")
        key, value = key.strip(), value.strip()
        if key in parts or key not in ("t", "x", "wall") or not value:
            check.reject(owner, "spec", spec, f"has the selector '{selector}': each of t=, x=, "
                         "wall= at most once, with a value")
        if key == "wall":
            if value not in ("left", "right"):
                check.reject(owner, "spec", spec, "must name wall=left or wall=right")
            parts[key] = value
        elif key == "x" and value == "mean":
            parts[key] = value
        else:
            try:
                parts[key] = float(value)
            except ValueError:
                check.reject(owner, "spec", spec, f"has {key}={value}: a number"
                             + (" or 'mean'" if key == "x" else ""))
    return parts


def quantity(ds, spec) -> float:
    """The value of ``spec`` (a specification or a function of the dataset) in the run
    dataset ``ds`` (:func:`granframe.open_run` with ``time_axis="steps"``)."""
    if callable(spec):
        return float(spec(ds))
    parts = parse(spec)
    name = parts["name"]
    if name not in ds.data_vars:
        check.reject("quantity", "spec", spec, "must name a recorded variable: "
                     + ", ".join(sorted(k for k, v in ds.data_vars.items()
                                        if "time" in v.dims)))
    data = ds[name]
    for dim, component in zip([d for d in data.dims if d.startswith("axis")],
                              parts["components"]):
        data = data.sel({dim: component})
    if "wall" in data.dims:
        if "wall" not in parts:
            check.reject("quantity", "spec", spec, "must choose wall=left or wall=right")
        data = data.sel(wall=parts["wall"])
    if "t" in parts:
        times = ds.time.values
        k = int(numpy.argmin(numpy.abs(times - parts["t"])))
        if abs(times[k] - parts["t"]) > 1e-9 * max(1.0, abs(parts["t"])):
            check.reject("quantity", "spec", spec, f"must take t at a step end of the run "
                         f"(nearest {times[k]:.10g})")
        data = data.isel(time=k)
    elif name.startswith("wall_"):
        data = data.sum("time")
    else:
        check.reject("quantity", "spec", spec, "must choose a time t= (a field changes in time)")
    if "x" in data.dims:
        if "x" not in parts:
            check.reject("quantity", "spec", spec, "must choose x=X or x=mean")
        if parts["x"] == "mean":
            data = data.mean("x")
        else:
            data = numpy.interp(parts["x"], ds.x.values, data.values)
    value = numpy.asarray(data, dtype=float)
    if value.size != 1:
        check.reject("quantity", "spec", spec, f"leaves {value.size} values (dimensions "
                     f"{getattr(data, 'dims', ())}); choose the components (.v1, .v2)")
    return float(value.reshape(()))


def grid_convergence(values, spacings, formal_order: float | None = None) -> dict:
    r"""The analysis of the module notes for one quantity.

    Parameters
    ----------
    values : sequence of float
        phi of each member, coarse to fine (two or more).
    spacings : sequence of float
        h of each member, coarse to fine, in any unit.
    formal_order : float, optional
        The scheme's order: required with two members, and used where the observed order
        cannot be (oscillatory or round-off differences).

    Returns
    -------
    dict
        ``value`` (the finest), ``differences`` (phi_{k+1} - phi_k), ``order`` (observed or
        formal), ``observed`` (bool), ``extrapolated``, ``gci`` (relative),
        ``error_bar`` (GCI |phi_1|), ``convergence`` ('monotone', 'oscillatory',
        'divergent' (the finest refinement moved the value no less than the one before:
        not in the asymptotic range, no error bar), 'round-off', 'two members').
    """
    owner = "grid_convergence"
    phi = [float(v) for v in values]
    h = [float(v) for v in spacings]
    if len(phi) != len(h) or len(phi) < 2:
        check.reject(owner, "values", values, "must give at least two values, one per spacing")
    if not all(math.isfinite(v) for v in phi):
        check.reject(owner, "values", values, "must be finite")
    if any(b >= a for a, b in zip(h[:-1], h[1:])) or not h[-1] > 0:
        check.reject(owner, "spacings", spacings, "must decrease, coarse to fine, and be > 0")
    if formal_order is not None and not (check.is_real(formal_order) and formal_order > 0):
        check.reject(owner, "formal_order", formal_order, "must be a positive number")
    differences = [b - a for a, b in zip(phi[:-1], phi[1:])]
    phi1, phi2 = phi[-1], phi[-2]
    r21 = h[-2] / h[-1]
    scale = max(abs(v) for v in phi[-3:]) or 1.0
    result = {"value": phi1, "differences": differences, "observed": False}
    if len(phi) == 2:
        if formal_order is None:
            check.reject(owner, "formal_order", formal_order, "must be given with two members "
                         "(no order can be observed)")
        order, safety, convergence = float(formal_order), SAFETY[2], "two members"
    else:
        phi3, r32 = phi[-3], h[-3] / h[-2]
        e21, e32 = phi2 - phi1, phi3 - phi2
        if abs(e21) <= 1e-13 * scale or abs(e32) <= 1e-13 * scale:
            convergence = "round-off"
            order, safety = formal_order, SAFETY[3]
        elif e32 / e21 < 0:
            convergence = "oscillatory"
            order, safety = formal_order, SAFETY[3]
        elif abs(e32) <= abs(e21):
            convergence = "divergent"            # the last refinement moved it the most
            order, safety = None, SAFETY[3]
        else:
            convergence, safety = "monotone", SAFETY[3]
            ratio = abs(e32 / e21)
            order = math.log(ratio) / math.log(r21)
            for _ in range(200):
                q = math.log((r21 ** order - 1.0) / (r32 ** order - 1.0)) if order > 0 else 0.0
                new = abs(math.log(ratio) + q) / math.log(r21)
                if abs(new - order) < 1e-12:
                    order = new
                    break
                order = new
            result["observed"] = True
    result["convergence"] = convergence
    result["order"] = order
    if order is None or not order > 0:
        result.update(extrapolated=math.nan, gci=math.nan, error_bar=math.nan)
        return result
    factor = r21 ** order - 1.0
    extrapolated = (r21 ** order * phi1 - phi2) / factor
    relative = abs((phi2 - phi1) / phi1) if phi1 != 0 else math.inf
    gci = safety * relative / factor
    result.update(extrapolated=extrapolated, gci=gci, error_bar=gci * abs(phi1))
    return result


@attrs.frozen
class RefinementResult:
    """The family's stores (the sweep store), the spacings and each quantity's analysis."""

    store: str
    spacings: list
    rows: list


def run_refinement(refinement: Refinement, out, *, workers: int | None = None,
                   formal_order: float | None = None, progress: bool = True,
                   overwrite: bool = False, client=None) -> RefinementResult:
    """Run the family into ``out``/family.zarr (a sweep store: resumed when run again) and
    write ``out``/refinement.json, refinement.md (the table) and refinement.png (each
    quantity against h, the Richardson estimate and the finest value's error bar).
    Members that do not finish are reported and left out of the analysis."""
    import granframe
    from granframe.run.sweep import read_table, run_name, run_sweep

    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    store = out / "family.zarr"
    sweep = refinement.sweep()
    run_sweep(sweep, store, workers=workers, progress=progress, overwrite=overwrite,
              client=client)
    table = read_table(store)
    status = dict(zip([str(n) for n in table["name"]], [str(s) for s in table["status"]]))
    h = refinement.spacings()
    members = []
    for point, spacing in zip(sweep.points(), h):
        name = run_name(point)
        if status.get(name) == "finished":
            members.append((spacing, store / "runs" / name, point))
    rows = []
    datasets = [(spacing, granframe.open_run(path, time_axis="steps"), point)
                for spacing, path, point in members]
    for spec in refinement.quantities:
        label = spec if isinstance(spec, str) else getattr(spec, "__name__", "quantity")
        values = [quantity(ds, spec) for _, ds, _ in datasets]
        row = {"quantity": label, "members": [p for _, _, p in datasets],
               "spacings": [s for s, _, _ in datasets], "values": values}
        if len(values) >= 2:
            row.update(grid_convergence(values, row["spacings"], formal_order))
        rows.append(row)
    result = RefinementResult(str(store), h, rows)
    (out / "refinement.json").write_text(json.dumps(
        {"vary": refinement.vary, "quantities": [r["quantity"] for r in rows],
         "rows": rows, "unfinished": [run_name(p) for p in sweep.points()
                                      if status.get(run_name(p)) != "finished"]},
        indent=1, default=float))
    (out / "refinement.md").write_text(table_text(result, refinement))
    figure(result, out / "refinement.png")
    return result


def table_text(result: RefinementResult, refinement: Refinement) -> str:
    """The markdown table: each quantity's values coarse to fine, the observed order, the
    Richardson estimate, the GCI of the finest and its error bar."""
    names = ", ".join(f"{k} = {list(v)}" for k, v in refinement.vary.items())
    lines = [f"refinement: {names}", "",
             "| quantity | values (coarse to fine) | order | convergence | Richardson | "
             "GCI (fine) | finest ± error bar |", "|---|---|---|---|---|---|---|"]
    for row in result.rows:
        values = ", ".join(f"{v:.8g}" for v in row["values"])
        order = row.get("order")
        shown = "—" if order is None else f"{order:.3g}" + ("" if row.get("observed") else
                                                            " (formal)")
        lines.append(f"| {row['quantity']} | {values} | {shown} | "
                     f"{row.get('convergence', 'one member')} | "
                     f"{row.get('extrapolated', math.nan):.8g} | "
                     f"{row.get('gci', math.nan):.3g} | {row['values'][-1]:.8g} ± "
                     f"{row.get('error_bar', math.nan):.2g} |")
    return "\n".join(lines) + "\n"


def figure(result: RefinementResult, path) -> None:
    """Each quantity against h (relative to the coarsest), the Richardson estimate at h = 0
    and the finest value's GCI error bar."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    count = max(len(result.rows), 1)
    fig, axes = plt.subplots(1, count, figsize=(4.2 * count, 3.4), layout="tight",
                             squeeze=False)
    for ax, row in zip(axes[0], result.rows):
        h, values = row["spacings"], row["values"]
        ax.plot(h, values, "o-", lw=0.8, label="members")
        if math.isfinite(row.get("extrapolated", math.nan)):
            ax.plot([0.0], [row["extrapolated"]], "s", label="Richardson")
            ax.errorbar([h[-1]], [values[-1]], yerr=[row["error_bar"]], fmt="none",
                        capsize=4, color="k", label="GCI error bar")
        ax.set_xlabel("h / h of the coarsest")
        ax.set_title(row["quantity"], fontsize=8)
        ax.set_xlim(left=-0.05)
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=110)
    plt.close(fig)
