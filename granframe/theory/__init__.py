"""The theory granframe's runs are compared with: closed forms and reference solvers that
use nothing of granframe but NumPy, SciPy and its validators.

- :mod:`granframe.theory.cooling`: the cooling rate zeta of a Maxwellian, any kernel
  |g|^lambda and restitution law (Maxwell molecules: exact for any f);
- :mod:`granframe.theory.sonine`: the first-Sonine transport coefficients and cooling rate
  of 3D inelastic hard spheres (Brey, Dufty, Kim & Santos 1998; Garzo & Dufty 1999);
- :mod:`granframe.theory.modes`: linear granular Navier-Stokes about the homogeneous
  cooling state (the shear, sound and heat modes, k_c and k_h);
- :mod:`granframe.theory.euler`: the exact Riemann solver of the Euler equations (Toro),
  the piston problem's Rankine-Hugoniot state, and a finite-volume solver of the granular
  Euler equations;
- :mod:`granframe.theory.walls`: the granular Navier-Stokes profile between two heated walls,
  with Sone's temperature jump;
- :mod:`granframe.theory.shock`: the Navier-Stokes profile of a normal shock of hard spheres;
- :mod:`granframe.theory.cells`: cell averages of piecewise-smooth profiles.

Temperature, pressure and heat flux follow granframe's conventions: T = int |v-u|^2 f dv
/ (d rho), p = rho T, q_i = int (v-u)_i |v-u|^2 f dv / 2, and Q(f, f)/eps with the review's
collision constants (B = |g|^lambda / |S^{d-1}|).
"""
