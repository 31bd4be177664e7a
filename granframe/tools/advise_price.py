"""The price of a space run on this machine, all-kinetic and with a hierarchy of collision
models: the record :func:`granframe.tools.advise.price_hierarchy` fills with its
measurements, its predictions and the report ``granframe advise`` prints.
"""

from __future__ import annotations

import json

import attrs

from granframe.run.description import Hierarchy, RunDescription, fixed_steps


@attrs.frozen
class HierarchyPrice:
    r"""What the steps of a space run cost on this machine, all-kinetic and with a hierarchy
    of collision models (:func:`~granframe.tools.advise.price_hierarchy` measures it).

    With C cells, n_l of them at level l when the levels are chosen from f0 (as the run's
    first step chooses them), and K the full level (the last), one step costs

    .. math:: T_{kin} = \tau_x + a_K + b_K C, \qquad
              T_{hier} = \tau_x + \sum_{l:\,n_l > 0} (a_l + b_l n_l) + m + c / I,

    with tau_x the transport of all cells (two half steps), a_l + b_l n the collision step
    of a batch of n cells at level l (each level advances its cells in one call), m the
    indicators of all cells (measured every step), c the choice of the levels (every
    I = ``interval`` steps). The run costs its steps times that. The all-kinetic step is
    the full level on every cell, which is what a run without a hierarchy does.

    The levels change as waves move. For a Riemann problem the price also estimates them at
    the final time t_f (:func:`granframe.tools.advise._swept_levels`): the cells the Euler
    waves have swept at the full level, the others as at t = 0, n_l(t_f). The swept
    region grows linearly in time, so the run is estimated at
    steps x (T_hier(n(0)) + T_hier(n(t_f))) / 2.

    Parameters
    ----------
    run : RunDescription
        The run as given.
    priced : RunDescription
        The run priced: ``run`` when it has a hierarchy; else ``run`` with the default
        :class:`~granframe.run.description.Hierarchy` and ``conservative`` set (which a
        hierarchy needs; the all-kinetic price then includes that correction too).
    counts : tuple of int
        n_l, the cells at each level chosen from f0.
    transport_seconds : float
        tau_x.
    level_seconds : tuple of (float, float)
        (a_l, b_l) of each level, from the levels' timings on 1 and ``batch`` cells.
    measure_seconds, choose_seconds : float
        m and c.
    batch, repeats : int
        The larger batch timed, and how many timings each median is of.
    final_counts : tuple of int or None
        n_l(t_f), the cells at each level at the final time estimated from the waves of a
        Riemann problem; None for other initial data.
    """

    run: RunDescription
    priced: RunDescription
    counts: tuple
    transport_seconds: float
    level_seconds: tuple
    measure_seconds: float
    choose_seconds: float
    batch: int
    repeats: int
    final_counts: tuple | None = None

    @property
    def given(self) -> bool:
        """Whether the hierarchy priced is the run's own (else the default one)."""
        return self.run.space.hierarchy is not None

    @property
    def hierarchy(self) -> Hierarchy:
        return self.priced.space.hierarchy

    @property
    def names(self) -> tuple:
        return tuple(level.name for level in self.hierarchy.levels)

    @property
    def cells(self) -> int:
        return self.priced.space.cells

    @property
    def steps(self) -> int:
        """The run's steps (:func:`~granframe.run.description.fixed_steps`; a short last step
        counts as one)."""
        full, last = fixed_steps(self.priced.final_time, self.priced.time_step)
        return full + (1 if last else 0)

    @property
    def shares(self) -> dict:
        """n_l / C of each level, at t = 0."""
        return {name: count / self.cells for name, count in zip(self.names, self.counts)}

    @property
    def choice_seconds(self) -> float:
        """m + c / I."""
        return self.measure_seconds + self.choose_seconds / self.hierarchy.interval

    @property
    def kinetic_step_seconds(self) -> float:
        """T_kin = tau_x + a_K + b_K C."""
        fixed, per_cell = self.level_seconds[-1]
        return self.transport_seconds + fixed + per_cell * self.cells

    @property
    def hierarchy_step_seconds(self) -> float:
        """T_hier(n(0)) = tau_x + sum over the levels with cells of (a_l + b_l n_l) + m + c / I,
        at the levels of t = 0."""
        return self.step_seconds(self.counts)

    def step_seconds(self, counts) -> float:
        """T_hier(n) with ``counts`` n_l cells at each level."""
        return (self.transport_seconds + self.choice_seconds
                + sum(fixed + per_cell * count for (fixed, per_cell), count
                      in zip(self.level_seconds, counts) if count))

    @property
    def estimated_seconds(self) -> float | None:
        """steps x (T_hier(n(0)) + T_hier(n(t_f))) / 2, the run with the hierarchy as the
        waves of a Riemann problem spread; None without :attr:`final_counts`."""
        if self.final_counts is None:
            return None
        return self.steps * 0.5 * (self.hierarchy_step_seconds
                                   + self.step_seconds(self.final_counts))

    @property
    def kinetic_seconds(self) -> float:
        return self.steps * self.kinetic_step_seconds

    @property
    def hierarchy_seconds(self) -> float:
        return self.steps * self.hierarchy_step_seconds

    @property
    def saving(self) -> float:
        """T_kin / T_hier: above 1 the hierarchy is predicted cheaper at its levels of t = 0."""
        return self.kinetic_step_seconds / self.hierarchy_step_seconds

    def fragment(self) -> str:
        """The TOML to add to the run for the hierarchy priced (with ``conservative = true``
        before it when the run has no correction), one line per parameter; a level without
        parameters by its name."""
        table = self.hierarchy.to_dict()
        table["levels"] = [level["name"] if set(level) == {"name"} else level
                           for level in table["levels"]]
        return "\n".join(([] if self.run.conservative else ["conservative = true"])
                         + ["[space.hierarchy]"]
                         + [f"{key} = {_toml_value(value)}" for key, value in table.items()])

    def to_dict(self) -> dict:
        """JSON-ready: the measurements, the levels at t = 0 and the predictions."""
        return {"cells": self.cells, "steps": self.steps, "time_step": self.priced.time_step,
                "hierarchy": self.hierarchy.to_dict(), "given": self.given,
                "shares_at_start": self.shares,
                "counts_at_start": dict(zip(self.names, self.counts)),
                "transport_seconds": self.transport_seconds,
                "level_seconds": {name: {"fixed": fixed, "per_cell": per_cell}
                                  for name, (fixed, per_cell)
                                  in zip(self.names, self.level_seconds)},
                "measure_seconds": self.measure_seconds,
                "choose_seconds": self.choose_seconds,
                "kinetic_step_seconds": self.kinetic_step_seconds,
                "hierarchy_step_seconds": self.hierarchy_step_seconds,
                "kinetic_seconds": self.kinetic_seconds,
                "hierarchy_seconds": self.hierarchy_seconds, "saving": self.saving,
                "counts_at_end": (None if self.final_counts is None
                                  else dict(zip(self.names, self.final_counts))),
                "estimated_seconds": self.estimated_seconds,
                "batch": self.batch, "repeats": self.repeats}

    def report(self) -> str:
        """The lines ``granframe advise`` prints: the run, what was measured, the levels of
        t = 0, both prices and their ratio, what the shares of t = 0 leave open, and the
        fragment to add when the run has no hierarchy."""
        d, space, h = self.priced, self.priced.space, self.hierarchy
        ms = 1e3
        levels = ", ".join(f"{name} {ms * fixed:.3g} ms + {ms * per_cell:.3g} ms x n"
                           for name, (fixed, per_cell) in zip(self.names, self.level_seconds))
        shares = ", ".join(f"{name} {100 * share:.0f} % ({count})" for (name, share), count
                           in zip(self.shares.items(), self.counts))
        verdict = (f"{self.saving:.3g}x cheaper" if self.saving >= 1
                   else f"{1 / self.saving:.3g}x dearer")
        full = self.steps * (self.kinetic_step_seconds + self.choice_seconds)
        ordered = all(low[0] <= high[0] and low[1] <= high[1] for low, high
                      in zip(self.level_seconds, self.level_seconds[1:]))
        lines = [
            f"space run: {self.cells} cells on [0, {space.length:g}] ({space.left.name} | "
            f"{space.right.name}, {space.reconstruction.name}), {d.grid.dimension}D N = "
            f"{d.grid.n_modes}, S = {d.grid.support_radius:g}, eps = {d.knudsen:g}, "
            f"{d.integrator.name}, dt = {d.time_step:.4g}: {self.steps} steps",
            f"measured here (medians of {self.repeats} after a warm-up): transport "
            f"{ms * self.transport_seconds / self.cells:.3g} ms per cell and step; collision "
            f"step of n cells: {levels}; indicators {ms * self.measure_seconds:.3g} ms per "
            f"step, choice {ms * self.choose_seconds:.3g} ms every {h.interval} step(s)",
            f"levels chosen from f0 (t = 0): {shares} of the cells",
            f"all-kinetic: {self.kinetic_step_seconds:.3g} s per step x {self.steps} = "
            f"{self.kinetic_seconds:.3g} s"
            + ("" if self.run.conservative else " (with the conservative correction a "
                                                "hierarchy needs, which the run has not)"),
            f"with the {'hierarchy' if self.given else 'default hierarchy'} "
            f"({' < '.join(self.names)}): {self.hierarchy_step_seconds:.3g} s per step x "
            f"{self.steps} = {self.hierarchy_seconds:.3g} s at the levels of t = 0: {verdict}",
            "- these shares are those of t = 0 and change as waves move: where the "
            "non-equilibrium spreads from the initial data, cells rise to higher levels; "
            f"with every cell at {self.names[-1]} the hierarchy costs {full:.3g} s (the "
            "all-kinetic price, the indicators and the choice). "
            + ("Each level costs more than the one below it, so the saving of t = 0 is then "
               "an upper bound. " if ordered else
               "The levels are not dearer in their order here (a + b n above), so cells that "
               "rise may lower the cost as well as raise it. ")
            + f"The all-kinetic price, {self.kinetic_seconds:.3g} s, holds whatever the "
            "levels."]
        if self.final_counts is not None:
            estimate = self.estimated_seconds
            lines.append(
                f"- at t = {d.final_time:g} the Euler waves of the Riemann problem have swept "
                f"{self.final_counts[-1] - self.counts[-1]} more cells (with the buffer): with "
                f"them at {self.names[-1]}, a step costs "
                f"{self.step_seconds(self.final_counts):.3g} s; as the waves spread linearly in "
                f"time the run costs about {estimate:.3g} s, "
                + (f"{self.kinetic_seconds / estimate:.3g}x cheaper" if estimate
                   <= self.kinetic_seconds else f"{estimate / self.kinetic_seconds:.3g}x dearer")
                + " than all-kinetic (an estimate: cells the waves have left may stay above "
                "the fluid level, and the fluid levels take longer on data far from "
                "equilibrium)")
        if not self.given:
            lines.append("- the run has no hierarchy; to use the default one, add:\n"
                         + "\n".join("    " + line for line in self.fragment().splitlines()))
        return "\n".join(lines)


def _toml_value(value) -> str:
    """``value`` (a string, number, boolean, list or table of them) as an inline TOML value."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{key} = {_toml_value(v)}" for key, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value)
