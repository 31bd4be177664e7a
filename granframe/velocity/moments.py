r"""The moment service: the moments of a batch of distributions in one pass on the backend.

For f of shape (cells, *grid.shape) (a space run's cells; a space-homogeneous run or a
single distribution is a batch of one) the raw moments of each are one matrix product
f (cells x N^d) times the basis (N^d x m) of 1, v_i, v_i v_j (i <= j), v_i |v|^2, |v|^4
and the content of the node v_a = -L of each transport axis a (v_1 for a run along x)
times 1, v_j (j != a) and |v|^2, weighted by the cell volume of the velocity grid;
from them, with rho u = J,

.. math:: P_{ij} = M_{ij} - \rho u_i u_j,\qquad T = \frac{\operatorname{tr} P}{d\,\rho},\qquad
          q_i = \tfrac12\bigl(M^{(3)}_i - 2 u_j M_{ij} - u_i \operatorname{tr} M
          + 2 \rho u_i |u|^2\bigr),

the central moments of granframe's conventions. The node v_a = -L of a transport axis,
which the periodic grid shares between -L and +L, has one documented rule, with two
readings of the same raw moments (the node's columns turn one into the other,
:meth:`FieldMoments.central`; v_1 below stands for each transport axis's component):

- ``"halves"``, the fields of a space run: the node counts as its two halves, v_1 = 0 in
  the odd powers of v_1 (momentum, P_1j for j != 1, q_i) and v_1^2 = L^2 in the even ones,
  as the transport carries it (half each way, :func:`~granframe.space.transport.upwind_speeds`);
  as -L, that node's content, which the collision operator's ringing puts there next to
  walls, would show as a bulk velocity and a heat flux;
- ``"periodic"``, what the collision operator conserves: the node at -L (the grid's own
  :meth:`~granframe.velocity.grid.VelocityGrid.momentum`); the BGK penalisation, the
  restoration of the conserved moments and the conservative correction take it.

:class:`FieldMoments` is the one place a run takes moments of a batch: the recorded fields
and totals (with the wall totals, one device->host transfer per step), the density,
velocity, temperature and energy of every cell on the device for the penalisation, the
hierarchy and the collision step, the edge shares and the resolution indicators of every
cell at output points.
"""

from __future__ import annotations

import numpy

from granframe import validators as check
from granframe.backends import to_host

#: the fields recorded for every cell after every step: name -> (components, dimensions)
FIELDS = {"density": ((), ()), "velocity": (("d",), ("axis",)), "temperature": ((), ()),
          "pressure_tensor": (("d", "d"), ("axis", "axis2")), "heat_flux": (("d",), ("axis",))}

#: the totals over all cells recorded after every step
TOTALS = ("mass", "kinetic_energy", "min_f", "negative_mass_fraction")


def _checked_axes(axes, dimension: int) -> tuple:
    """``axes`` as a tuple of distinct velocity axes in increasing order, refused by name
    otherwise."""
    try:
        values = tuple(int(a) for a in axes)
    except (TypeError, ValueError):
        values = None
    if (values is None or any(isinstance(a, bool) for a in axes)
            or values != tuple(sorted(set(values))) or any(not 0 <= a < dimension for a in values)
            or values != tuple(axes)):
        check.reject("FieldMoments", "transport_axes", axes, "must be distinct velocity axes in "
               f"increasing order, each in 0 .. {dimension - 1}")
    return values


class FieldMoments:
    """The reductions of every cell of f (see the module notes), on the backend.

    Parameters
    ----------
    grid : VelocityGrid
    dx : float
        The cell width (the totals are sum_j int f dv dx).
    xp : module
        The array namespace of f; the basis and the node arrays are put there once.
    transport_axes : tuple of int
        The velocity components that carry f along the space axes, whose node -L the
        "halves" reading counts as its two halves: (0,), v_1, for a run along x (and a
        space-homogeneous one, which reads its moments "periodic").
    """

    def __init__(self, grid, dx: float, xp=numpy, transport_axes: tuple = (0,)):
        d = grid.dimension
        self.grid, self.dx, self.xp, self.d = grid, float(dx), xp, d
        self.transport_axes = axes = _checked_axes(transport_axes, d)
        actual = [m.reshape(-1) for m in numpy.meshgrid(*[grid.points()] * d, indexing="ij")]
        squared = sum(m * m for m in actual)
        # the node -L of each transport axis: half at -L, half at +L
        edges = [actual[a] == -grid.half_width for a in axes]
        mesh = list(actual)
        for a, edge in zip(axes, edges):
            mesh[a] = numpy.where(edge, 0.0, actual[a])
        self.pairs = [(i, j) for i in range(d) for j in range(i, d)]
        columns = ([numpy.ones_like(squared)] + mesh
                   + [squared - sum(actual[k] * actual[k] for k in range(d) if k != i)
                      if i == j and i in axes else mesh[i] * mesh[j] for i, j in self.pairs]
                   + [m * squared for m in mesh] + [squared * squared])
        for a, edge in zip(axes, edges):
            columns += ([edge.astype(float)] + [edge * mesh[j] for j in range(d) if j != a]
                        + [edge * squared])
        columns += [ea * eb for k, ea in enumerate(edges) for eb in edges[k + 1:]]
        count = len(self.pairs)
        #: the columns of the raw moments: J_i, M_ij (pairs), M3_i = int v_i |v|^2 f, M4 =
        #: int |v|^4 f, and for each transport axis a the content of its node -L times 1,
        #: the other components v_j (j != a) and |v|^2, then that of the nodes -L of two
        #: transport axes at once
        start = 2 + 2 * d + count
        self.columns = {"momentum": slice(1, 1 + d), "second": slice(1 + d, 1 + d + count),
                        "third": slice(1 + d + count, 1 + 2 * d + count),
                        "fourth": 1 + 2 * d + count,
                        "edge": slice(start, len(columns))}
        self.basis = xp.asarray(numpy.stack(columns, axis=1) * grid.cell_volume)
        #: the nodes v (d, N^d) with the nodes -L at -L, and |v|^2 (N^d), for the edge
        #: shares (where the collision operator sees those nodes)
        self.nodes = xp.asarray(numpy.stack(actual))
        self.squared = xp.asarray(squared)
        #: the 1-D nodes, for the discrete Maxwellians of the BGK penalisation
        #: (:func:`~granframe.velocity.equilibrium.discrete_maxwellians`)
        self.points = xp.asarray(grid.points())
        self._diagonal = [1 + d + self.pairs.index((i, i)) for i in range(d)]

    def raw(self, f):
        """The raw moments (cells, m) of f (cells, *grid.shape): one matrix product."""
        return f.reshape(f.shape[0], -1) @ self.basis

    def primitives(self, f, node: str = "halves"):
        """rho, u (cells, d), T and the kinetic energy density int |v|^2/2 f dv of every cell
        of f, on the device (no transfer).

        ``node`` "halves": the node -L as its two halves (the fields' convention);
        "periodic": as -L, the periodic grid's own convention, in which the collision
        operator conserves momentum (:meth:`~granframe.velocity.grid.VelocityGrid.momentum`;
        the BGK penalisation takes these, so that it conserves what Q conserves). Both come
        from the same raw moments: the node's content turns one into the other.
        """
        d = self.d
        raw = self.raw(f)
        rho = raw[:, 0]
        momentum = raw[:, 1:1 + d]
        if node == "periodic":
            start, axes = self.columns["edge"].start, self.transport_axes
            momentum = self.xp.stack(
                [momentum[:, i] - self.grid.half_width * raw[:, start + axes.index(i) * (d + 1)]
                 if i in axes else momentum[:, i] for i in range(d)], axis=1)
        trace = raw[:, self._diagonal].sum(axis=1)
        with numpy.errstate(divide="ignore", invalid="ignore"):
            velocity = momentum / rho[:, None]
            temperature = (trace - (momentum * momentum).sum(axis=1) / rho) / (d * rho)
        return rho, velocity, temperature, 0.5 * trace

    def packed(self, f, extra=None):
        """The raw moments, min f, int max(-f, 0), int |f| and ``extra`` (a device array of
        further values, e.g. the wall totals) as one device vector: what one transfer takes
        to the host (:meth:`unpack`)."""
        xp = self.xp
        flat = f.reshape(f.shape[0], -1)
        parts = [self.raw(f).reshape(-1),
                 xp.stack([flat.min(), xp.maximum(-flat, 0.0).sum(), xp.abs(flat).sum()])]
        if extra is not None:
            parts.append(extra.reshape(-1))
        return xp.concatenate(parts)

    def unpack(self, vector, cells: int) -> dict:
        """The fields and totals (:data:`FIELDS`, :data:`TOTALS`) from :meth:`packed`'s vector
        on the host; the values beyond them as ``extra``."""
        m = self.basis.shape[1]
        minimum, negative, absolute = vector[cells * m:cells * m + 3]
        rho, u, pressure, temperature, heat, trace = self.fields_of(
            self.central(vector[:cells * m].reshape(cells, m), "halves"))
        return {"density": rho, "velocity": u, "temperature": temperature,
                "pressure_tensor": pressure, "heat_flux": heat,
                "mass": float(rho.sum() * self.dx),
                "kinetic_energy": float(0.5 * trace.sum() * self.dx),
                "min_f": float(minimum),
                "negative_mass_fraction": float(negative / absolute) if absolute > 0 else 0.0,
                "extra": vector[cells * m + 3:]}

    def central(self, raw, node: str) -> dict:
        r"""The raw moments of every cell in the reading ``node`` of the node -L (module
        notes), on the host: ``density`` (cells,), ``momentum`` (cells, d), ``second``
        M_ij (cells, d, d), ``third`` M3_i (cells, d) and ``fourth`` M4 (cells,), from the
        raw moments ``raw`` (cells, m) on the host.

        "periodic" takes the nodes at v_a = -L of the transport axes a: with E^a_w the
        content of the node -L of axis a times w = 1, v_j (j != a, read in halves), |v|^2,
        and E^ab that of the nodes -L of two axes, J_a - L E^a_1,
        M_aj - L E^a_{v_j} - L E^j_{v_a} + L^2 E^aj (the last two where j is a transport axis
        too) and M3_a - L E^a_{|v|^2}; the even powers are the same in both readings."""
        d, columns, cells = self.d, self.columns, raw.shape[0]
        momentum = numpy.array(raw[:, columns["momentum"]], dtype=float)
        second = numpy.zeros((cells, d, d))
        for k, (i, j) in enumerate(self.pairs):
            second[:, i, j] = second[:, j, i] = raw[:, columns["second"].start + k]
        third = numpy.array(raw[:, columns["third"]], dtype=float)
        if node == "periodic":
            self._periodic(raw[:, columns["edge"]], momentum, second, third)
        return {"density": raw[:, 0], "momentum": momentum, "second": second,
                "third": third, "fourth": raw[:, columns["fourth"]]}

    def _periodic(self, edge, momentum, second, third) -> None:
        """The halves moments turned into the periodic ones in place, from the nodes'
        columns ``edge`` (:meth:`central`)."""
        d, axes, L = self.d, self.transport_axes, self.grid.half_width
        for g, a in enumerate(axes):
            block = edge[:, g * (d + 1):(g + 1) * (d + 1)]
            momentum[:, a] -= L * block[:, 0]
            for k, j in enumerate(j for j in range(d) if j != a):
                second[:, a, j] -= L * block[:, 1 + k]
                second[:, j, a] = second[:, a, j]
            third[:, a] -= L * block[:, -1]
        cross = len(axes) * (d + 1)
        for k, (a, b) in enumerate((a, b) for i, a in enumerate(axes) for b in axes[i + 1:]):
            second[:, a, b] += L * L * edge[:, cross + k]
            second[:, b, a] = second[:, a, b]

    @staticmethod
    def fields_of(moments: dict) -> tuple:
        """rho, u, P, T, q and tr M of every cell from :meth:`central`'s moments (host)."""
        rho, second = moments["density"], moments["second"]
        d = second.shape[1]
        with numpy.errstate(divide="ignore", invalid="ignore"):
            u = moments["momentum"] / rho[:, None]
            pressure = second - rho[:, None, None] * u[:, :, None] * u[:, None, :]
            trace = numpy.trace(second, axis1=1, axis2=2)
            temperature = numpy.trace(pressure, axis1=1, axis2=2) / (d * rho)
            heat = 0.5 * (moments["third"] - 2.0 * numpy.einsum("cj,cij->ci", u, second)
                          - u * trace[:, None]
                          + 2.0 * rho[:, None] * u * (u * u).sum(axis=1)[:, None])
        return rho, u, pressure, temperature, heat, trace

    def distribution(self, f) -> dict:
        r"""Every moment the record of a space-homogeneous run holds, of one distribution f
        (*grid.shape), with the node -L at -L ("periodic", the grid's own convention):
        one pass over f and one device->host transfer (:meth:`packed`).

        Returns ``mass``, ``momentum`` and ``bulk_velocity`` (length d), ``kinetic_energy``,
        ``temperature``, ``kurtosis``, ``sonine_a2``, ``min_f``, ``negative_mass_fraction``
        (int max(-f, 0) / int |f|) as floats, ``pressure_tensor`` (d x d) and
        ``heat_flux`` (d); NaN where a moment is undefined (a zero mass, a zero second
        central moment). The central fourth moment is

        .. math:: \int |v - u|^4 f = M_4 - 4 u_i M^{(3)}_i + 4 u_i u_j M_{ij}
                  + 2 |u|^2 \operatorname{tr} M - 4 |u|^2 u\cdot J + |u|^4 \rho,

        and kappa = rho int |v-u|^4 f / (int |v-u|^2 f)^2; a central moment of order n
        loses about (|u|^2/T)^{n/2} of relative accuracy to cancellation, nothing at u = 0.
        """
        m = self.basis.shape[1]
        vector = numpy.asarray(to_host(self.packed(f[None])), dtype=float)
        minimum, negative, absolute = vector[m:m + 3]
        moments = self.central(vector[:m].reshape(1, m), "periodic")
        rho, u, pressure, temperature, heat, trace = (a[0] for a in self.fields_of(moments))
        if rho == 0.0:          # no mass: no velocity, nor any central moment
            u, pressure, temperature, heat = (numpy.full_like(a, numpy.nan) for a in
                                              (u, pressure, temperature, heat))
        with numpy.errstate(divide="ignore", invalid="ignore"):
            speed = float(u @ u)
            central2 = float(numpy.trace(pressure))
            central4 = (moments["fourth"][0] - 4.0 * u @ moments["third"][0]
                        + 4.0 * u @ moments["second"][0] @ u + 2.0 * speed * trace
                        - 4.0 * speed * (u @ moments["momentum"][0]) + speed * speed * rho)
            kurtosis = (rho * central4 / (central2 * central2)
                        if rho != 0.0 and central2 != 0.0 else numpy.nan)
        d = self.d
        return {"mass": float(rho), "momentum": moments["momentum"][0], "bulk_velocity": u,
                "kinetic_energy": 0.5 * float(trace), "temperature": float(temperature),
                "kurtosis": float(kurtosis), "sonine_a2": float(d / (d + 2.0) * kurtosis - 1.0),
                "min_f": float(minimum),
                "negative_mass_fraction": (float(negative / absolute) if absolute != 0.0
                                           else numpy.nan),
                "pressure_tensor": pressure, "heat_flux": heat}

    def partial_totals(self, vector, fields: dict) -> numpy.ndarray:
        """What the cells of one process add to the totals: the host vector
        [mass, kinetic energy, min f, int max(-f, 0), int |f|, min T, max T, extra...] from
        :meth:`packed`'s ``vector`` and its :meth:`unpack` ``fields`` (min and max of T over
        the cells where it is finite, NaN where it is nowhere); :meth:`combine` reduces the
        vectors of all processes."""
        cells, m = len(fields["density"]), self.basis.shape[1]
        minimum, negative, absolute = vector[cells * m:cells * m + 3]
        temperature = fields["temperature"]
        finite = temperature[numpy.isfinite(temperature)]
        low, high = (finite.min(), finite.max()) if finite.size else (numpy.nan, numpy.nan)
        return numpy.concatenate([[fields["mass"], fields["kinetic_energy"], minimum,
                                   negative, absolute, low, high], fields["extra"]])

    @staticmethod
    def combine(rows) -> dict:
        """The totals over all cells from the :meth:`partial_totals` of every process
        (rows in rank order): mass, kinetic_energy, min_f, negative_mass_fraction (sums of
        int max(-f, 0) over those of int |f|), ``temperature_range`` (min, max) and
        ``walls``, the sum of the extra values."""
        rows = numpy.asarray(rows, dtype=float)
        negative, absolute = rows[:, 3].sum(), rows[:, 4].sum()
        low, high = rows[:, 5], rows[:, 6]
        finite = numpy.isfinite(low)
        return {"mass": float(rows[:, 0].sum()), "kinetic_energy": float(rows[:, 1].sum()),
                "min_f": float(rows[:, 2].min()),
                "negative_mass_fraction": float(negative / absolute) if absolute > 0 else 0.0,
                "temperature_range": ((float(low[finite].min()), float(high[finite].max()))
                                      if finite.any() else (numpy.nan, numpy.nan)),
                "walls": rows[:, 7:].sum(axis=0)}

    def __call__(self, f) -> dict:
        """Fields (NumPy arrays over cells) and totals of f (cells, *grid.shape), in one
        device->host transfer.

        Returns density (cells), velocity (cells, d), temperature (cells),
        pressure_tensor (cells, d, d), heat_flux (cells, d), and the scalars mass
        (sum rho dx), kinetic_energy (sum int |v|^2/2 f dv dx), min_f and
        negative_mass_fraction (int max(-f, 0) / int |f| over all cells).
        """
        fields = self.unpack(to_host(self.packed(f)), f.shape[0])
        del fields["extra"]
        return fields

    def edge_shares(self, f, velocity, radius: float):
        r"""The shares of mass and energy of each cell of f beyond ``radius`` about its
        velocity u_c (``velocity``, (cells, d) on the device), as (cells, 2) on the device:

        .. math:: \frac{\sum_{|v_j - u_c| > r} f_{c,j}}{\sum_j f_{c,j}}, \qquad
                  \frac{\sum_{|v_j - u_c| > r} |v_j - u_c|^2 f_{c,j}}
                  {\sum_j |v_j - u_c|^2 f_{c,j}},

        :func:`granframe.run.monitors.edge_shares` for every cell at once, with the node
        -L at -L, where the collision operator meets its periodic images. NaN where a
        denominator is not positive.
        """
        xp = self.xp
        flat = f.reshape(f.shape[0], -1)
        distance = (self.squared[None, :] - 2.0 * (velocity @ self.nodes)
                    + (velocity * velocity).sum(axis=1)[:, None])
        beyond = distance > float(radius) ** 2
        weighted = flat * distance
        totals = xp.stack([flat.sum(axis=1), weighted.sum(axis=1)], axis=1)
        outside = xp.stack([(flat * beyond).sum(axis=1), (weighted * beyond).sum(axis=1)],
                           axis=1)
        with numpy.errstate(divide="ignore", invalid="ignore"):
            return xp.where(totals > 0.0, outside / totals, xp.nan)


    def resolution(self, f, backend):
        r"""The resolution indicators of every cell of f, (cells, 5) on the device: the
        spectral tail, the share of pairs beyond 2S, the negative mass share, the heat
        flux of the outermost shell and the change of the fields without that shell.

        With \hat f_{c,k} the DFT of cell c over the velocity axes and B the outermost
        evolved shell, max_i |k_i| = N/2 - 1 (:func:`~granframe.velocity.estimators.outer_band`):

        - tail: max_{k in B} |\hat f_{c,k}| / |\hat f_{c,0}|
          (:func:`~granframe.velocity.estimators.spectral_tail`);
        - pairs: the share of the autocorrelation of |f_c| (FFT on the grid padded to 2N)
          at lags |g| > 2S (:func:`~granframe.velocity.estimators.pair_share_beyond`,
          p = 0);
        - negative share: \sum_j \max(-f_{c,j}, 0) / \sum_j |f_{c,j}|;
        - heat flux of the shell: with s_c the part of f_c on B (the inverse DFT of
          \hat f_{c,k} 1_B(k)) and q[g] the heat flux of the module notes taken with the
          bulk velocity u_c of f_c,

          .. math:: \frac{|q[s_c]|}{\rho_c T_c^{3/2}},

          the heat flux carried by the last modes the grid keeps, in units of the cell's
          thermal heat flux scale (the estimate of what the modes it cuts off carry).
          The weight v |v|^2 is of size L^3 at the faces of the box, where the modes of B
          spread, so q needs more of N than f does;
        - fields of the shell: the largest relative change of the fields a run reports
          when the shell is taken out of f_c, with (rho', u', T') those of f_c - s_c,

          .. math:: \max\Bigl(\frac{|\rho' - \rho_c|}{\rho_c},
                    \frac{|u' - u_c|_\infty}{\sqrt{T_c}}, \frac{|T' - T_c|}{T_c},
                    \frac{|q[s_c]|}{\rho_c T_c^{3/2}}\Bigr):

          the error of the fields that the last modes the grid keeps carry, which
          estimates what the modes it cuts off carry (the coarsening of the velocity
          grid by one shell). A jump of f at v_1 = 0, where a wall joins what it sends
          back to what arrives, spreads over every shell and makes the spectral tail
          decay like 1/N, but its last shell changes the fields like 1/N^2 (the
          trapezoid sums of a piecewise smooth f): this indicator sees the resolution of
          the fields, not the jump (docs/space.md, "Resolution indicators of a cell").

        Three batched FFTs over the cells, by ``backend``'s transforms (``rfftn``,
        ``irfftn``: on its device); NaN where the mass or T is not positive. The cells go
        through in batches whose grids padded to 2N hold at most
        :data:`~granframe.memory.RESOLUTION_BATCH_BYTES` (2^d times f's size each, and three such arrays at
        once: a whole 3D run at a time peaked at 30 copies of its f).
        """
        from granframe.memory import resolution_batch

        batch = resolution_batch(self.grid.n_modes, self.d)
        if f.shape[0] > batch:
            return self.xp.concatenate([self.resolution(f[start:start + batch], backend)
                                        for start in range(0, f.shape[0], batch)])
        from granframe.velocity.estimators import outer_band, squared_lags

        xp, grid, d = self.xp, self.grid, self.d
        if not hasattr(self, "_band"):
            #: the outermost shell and the lags beyond 2S, put on the device once
            self._band = xp.asarray(outer_band(grid).astype(float))
            self._lags_beyond = xp.asarray(
                (squared_lags(grid) > (2.0 * grid.support_radius) ** 2).astype(float).reshape(-1))
        axes = tuple(range(1, d + 1))
        cells = f.shape[0]
        spectrum = backend.rfftn(f, axes=axes)
        modulus = xp.abs(spectrum).reshape(cells, -1)
        band = self._band.reshape(-1)
        zero = modulus[:, 0]
        tail = (modulus * band).max(axis=1) / zero
        padded = backend.rfftn(xp.pad(xp.abs(f), [(0, 0)] + [(0, grid.n_modes)] * d),
                               axes=axes)
        correlation = backend.irfftn(padded * xp.conj(padded), (2 * grid.n_modes,) * d,
                                     axes=axes).reshape(cells, -1)
        pairs = (correlation @ self._lags_beyond) / correlation.sum(axis=1)
        flat = f.reshape(cells, -1)
        negative = xp.maximum(-flat, 0.0).sum(axis=1) / xp.abs(flat).sum(axis=1)
        shell = backend.irfftn(spectrum * self._band, tuple(grid.shape), axes=axes)
        rho, u, temperature, _ = self.primitives(f)
        heat = self._heat_flux(self.raw(shell), u)
        rest = self.primitives(f - shell)
        with numpy.errstate(divide="ignore", invalid="ignore"):
            valid = (rho > 0.0) & (temperature > 0.0)
            scale = rho * xp.abs(temperature) ** 1.5
            share = xp.where(valid, xp.sqrt((heat * heat).sum(axis=1)) / scale, xp.nan)
            fields = xp.stack([xp.abs(rest[0] - rho) / rho,
                               xp.abs(rest[1] - u).max(axis=1) / xp.sqrt(xp.abs(temperature)),
                               xp.abs(rest[2] - temperature) / xp.abs(temperature), share],
                              axis=1).max(axis=1)
            fields = xp.where(valid, fields, xp.nan)
        return xp.stack([tail, pairs, negative, share, fields], axis=1)

    def _heat_flux(self, raw, velocity):
        """q_i = (M3_i - 2 u_j M_ij - u_i tr M + 2 rho u_i |u|^2) / 2 of the raw moments
        ``raw`` (cells, m) about ``velocity`` (cells, d), on the device."""
        d, xp = self.d, self.xp
        second = [[None] * d for _ in range(d)]
        for k, (i, j) in enumerate(self.pairs):
            second[i][j] = second[j][i] = raw[:, 1 + d + k]
        trace = raw[:, self._diagonal].sum(axis=1)
        third = raw[:, self.columns["third"]]
        speed = (velocity * velocity).sum(axis=1)
        contracted = xp.stack([sum(velocity[:, j] * second[i][j] for j in range(d))
                               for i in range(d)], axis=1)
        return 0.5 * (third - 2.0 * contracted - velocity * trace[:, None]
                      + 2.0 * raw[:, :1] * velocity * speed[:, None])
