"""Heated Maxwell molecules in 2D: the review's Test 1(b) set-up, against the exact temperature law.

d_t f = Q(f, f) + tau Delta_v f with B = 1/(2 pi), e = 0.5, tau = 0.1, from the Maxwellian
with T0 = 8 (review, section 3, eq. (maxw_init)); N = 64, N_rho = 32, M = 16, R = 20,
L = 5(3 + sqrt 2), classical RK4 with dt = 0.01 -- all as in the review. The run goes to
t = 20, where T has come within 2 % of its limit 8 tau / (1 - e^2) = 1.067 (the review goes
on to t = 55 for f_infinity).

    granframe run studies/heated_maxwell.py --out runs/heated_maxwell.zarr
    granframe plot runs/heated_maxwell.zarr --out figures/heated_maxwell

``--quick`` (the CI smoke test): N = 32, N_rho = 16, M = 8, dt = 0.02 to t = 2.
"""

from granframe.run.description import RunDescription


def description(quick: bool = False) -> RunDescription:
    n_modes, radial, circle, dt, final = (32, 16, 8, 0.02, 2.0) if quick else (64, 32, 16, 0.01, 20.0)
    return RunDescription(
        title="heated Maxwell molecules, e = 0.5, tau = 0.1" + (" (quick)" if quick else ""),
        grid={"dimension": 2, "n_modes": n_modes, "support_radius": 10.0},  # L = 5(3+√2), R = 20
        kernel="maxwell",
        restitution={"name": "constant", "value": 0.5},
        initial={"name": "maxwellian", "temperature": 8.0},
        operator={"name": "fast_spectral", "radial_points": radial,
                  "sphere": {"name": "circle_trapezoid", "n_points": circle}},
        integrator="rk4",
        heat_bath=0.1,
        time_step=dt,
        final_time=final,
        output={"snapshot_interval": final / 20},
    )
