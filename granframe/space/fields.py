r"""The hydrodynamic fields of every cell in one pass, and Maxwellians of given fields.

For f of shape (cells, *grid.shape) the raw moments of each cell are one matrix product
f (cells x N^d) times the basis (N^d x m) of 1, v_i, v_i v_j (i <= j), v_i |v|^2 weighted
by the cell volume of the velocity grid; from them, with rho u = J,

.. math:: P_{ij} = M_{ij} - \rho u_i u_j,\qquad T = \frac{\operatorname{tr} P}{d\,\rho},\qquad
          q_i = \tfrac12\bigl(M^{(3)}_i - 2 u_j M_{ij} - u_i \operatorname{tr} M
          + 2 \rho u_i |u|^2\bigr),

the central moments of granframe's conventions (the homogeneous ones of
:meth:`~granframe.velocity.grid.VelocityGrid.moments`, cell by cell), with one difference:
the node v_1 = -L, which the periodic grid shares between -L and +L and whose content the
transport moves half each way (:func:`~granframe.space.transport.upwind_speeds`), counts
as its two halves: v_1 = 0 in the odd powers of v_1 (momentum, P_1j for j != 1, q_i), and
v_1^2 = L^2 in the even ones. The fields are then those of what the transport carries;
as -L (the homogeneous convention) that node's content, which the collision operator's
ringing puts there next to walls, would show as a bulk velocity and a heat flux.
"""

from __future__ import annotations

import numpy

from granframe.backends import to_host

#: the fields recorded for every cell after every step: name -> (components, dimensions)
FIELDS = {"density": ((), ()), "velocity": (("d",), ("axis",)), "temperature": ((), ()),
          "pressure_tensor": (("d", "d"), ("axis", "axis2")), "heat_flux": (("d",), ("axis",))}


class FieldMoments:
    """The fields of every cell of f (:data:`FIELDS`), totals and extremes, in one pass.

    Parameters
    ----------
    grid : VelocityGrid
    dx : float
        The cell width (the totals are int int f dx dv).
    xp : module
        The array namespace of f.
    """

    def __init__(self, grid, dx: float, xp=numpy):
        d = grid.dimension
        self.grid, self.dx, self.xp, self.d = grid, float(dx), xp, d
        mesh = [m.reshape(-1) for m in numpy.meshgrid(*[grid.points()] * d, indexing="ij")]
        squared = sum(m * m for m in mesh)
        odd = mesh[0].copy()
        odd[mesh[0] == -grid.half_width] = 0.0        # the node -L: half at -L, half at +L
        mesh = [odd] + mesh[1:]
        self.pairs = [(i, j) for i in range(d) for j in range(i, d)]
        columns = ([numpy.ones_like(odd)] + mesh
                   + [squared - sum(m * m for m in mesh[1:]) if (i, j) == (0, 0)
                      else mesh[i] * mesh[j] for i, j in self.pairs]
                   + [m * squared for m in mesh])
        self.basis = xp.asarray(numpy.stack(columns, axis=1) * grid.cell_volume)

    def __call__(self, f) -> dict:
        """Fields (NumPy arrays over cells) and totals of f (cells, *grid.shape).

        Returns density (cells), velocity (cells, d), temperature (cells),
        pressure_tensor (cells, d, d), heat_flux (cells, d), and the scalars mass
        (sum rho dx), kinetic_energy (sum int |v|^2/2 f dv dx), min_f and
        negative_mass_fraction (int max(-f, 0) / int |f| over all cells).
        """
        xp, d = self.xp, self.d
        flat = f.reshape(f.shape[0], -1)
        raw = to_host(flat @ self.basis)
        negative = float(to_host(xp.maximum(-flat, 0.0).sum()))
        absolute = float(to_host(xp.abs(flat).sum()))
        minimum = float(to_host(flat.min()))
        rho = raw[:, 0]
        momentum = raw[:, 1:1 + d]
        second = numpy.zeros((len(rho), d, d))
        for k, (i, j) in enumerate(self.pairs):
            second[:, i, j] = second[:, j, i] = raw[:, 1 + d + k]
        third = raw[:, 1 + d + len(self.pairs):]
        with numpy.errstate(divide="ignore", invalid="ignore"):
            u = momentum / rho[:, None]
            pressure = second - rho[:, None, None] * u[:, :, None] * u[:, None, :]
            trace = numpy.trace(second, axis1=1, axis2=2)
            temperature = numpy.trace(pressure, axis1=1, axis2=2) / (d * rho)
            heat = 0.5 * (third - 2.0 * numpy.einsum("cj,cij->ci", u, second)
                          - u * trace[:, None]
                          + 2.0 * rho[:, None] * u * (u * u).sum(axis=1)[:, None])
        return {"density": rho, "velocity": u, "temperature": temperature,
                "pressure_tensor": pressure, "heat_flux": heat,
                "mass": float(rho.sum() * self.dx),
                "kinetic_energy": float(0.5 * trace.sum() * self.dx),
                "min_f": minimum,
                "negative_mass_fraction": negative / absolute if absolute > 0 else 0.0}


def maxwellians(grid, density, velocity, temperature, xp=numpy):
    """rho (2 pi T)^{-d/2} exp(-|v - u|^2 / (2T)) for each cell, (cells, *grid.shape),
    each scaled to have exactly the grid mass rho (``density``, ``velocity`` (cells, d),
    ``temperature`` arrays in ``xp``)."""
    d = grid.dimension
    points = xp.asarray(grid.points())
    cells = density.shape[0]
    result = xp.ones((cells,) + tuple(grid.shape))
    for i in range(d):
        shape = [cells] + [1] * d
        shape[1 + i] = -1
        factor = xp.exp(-(points[None, :] - velocity[:, i:i + 1]) ** 2
                        / (2.0 * temperature[:, None]))
        result = result * factor.reshape(shape)
    mass = result.reshape(cells, -1).sum(axis=1) * grid.cell_volume
    return result * (density / mass).reshape((cells,) + (1,) * d)
