"""Shared test helpers."""

import numpy as np
from scipy.integrate import solve_ivp

# Independent integrations run at rtol 1e-10 (the setting) with DOP853; their global
# error on these smooth, few-time-constant problems is ~1e-10 relative, so closed forms are
# compared at 1e-8 relative: two orders of margin over the integrator, far below any modelling
# difference we want to detect.
RTOL_IVP = 1e-10
RTOL_CLOSED_FORM = 1e-8


def integrate(rhs, y0, t_eval, **kwargs):
    """solve_ivp with the project's test settings; returns the solution array (n_state, n_t)."""
    t_eval = np.asarray(t_eval, dtype=float)
    sol = solve_ivp(
        rhs,
        (0.0, float(t_eval[-1])),
        y0,
        method="DOP853",
        t_eval=t_eval,
        rtol=RTOL_IVP,
        atol=kwargs.pop("atol", 1e-14),
        **kwargs,
    )
    assert sol.success, sol.message
    return sol.y
