"""A granule's free flight over a rotor's floor (perga.analytic.floor_flight) against closed
forms (a stationary floor: a straight line slowed at f g; drag alone: |v| = v0/(1 + k v0 t))
and against an independent integration of the same flight in the floor's rotating frame
(centrifugal and Coriolis forces, friction against the velocity there). The flight runs at
rtol 1e-10 (DOP853): 1e-8 leaves two orders."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from perga.analytic.floor_flight import FloorFlight
from perga.stats.trajectory import free_flight

G = 9.80665


def test_a_stationary_floor_is_a_straight_line_slowed_at_f_g() -> None:
    r0, v0 = (0.05, 0.02), (3.0, -1.0)
    result = FloorFlight(0.0, 0.35).integrate(r0, v0, 0.05)
    assert result.event == "end"
    exact = free_flight(result.t, r0, v0, 0.35 * G)
    assert result.r == pytest.approx(exact, rel=1e-8, abs=1e-12)


def test_drag_alone_follows_its_closed_form() -> None:
    k, v0 = 2.5, 4.0
    result = FloorFlight(drag=k).integrate((0.0, 0.0), (v0, 0.0), 0.1)
    t = result.t
    assert result.v[:, 0] == pytest.approx(v0 / (1 + k * v0 * t), rel=1e-9)
    assert result.r[:, 0] == pytest.approx(np.log1p(k * v0 * t) / k, rel=1e-9, abs=1e-15)


def test_a_turning_floor_agrees_with_the_flight_in_its_own_frame() -> None:
    """In the floor's frame (turning at ω): ü = ω²x − 2ω ẑ × u − f g u/|u| + drag, the drag
    the fixed frame's force seen there; turned back to the fixed frame at the end (Radau at
    rtol 1e-11: another method, another frame)."""
    w, f, k, t_end = 62.83, 0.35, 1.0, 0.03
    r0, v0 = np.array([0.08, 0.01]), np.array([1.0, 7.0])
    flight = FloorFlight(w, f, drag=k).integrate(tuple(r0), tuple(v0), t_end)
    assert flight.event == "end"

    def rotating(_t, y):
        x, u = y[:2], y[2:]
        c = math.hypot(*u)
        absolute = u + w * np.array([-x[1], x[0]])
        drag = -k * math.hypot(*absolute) * absolute
        # centrifugal ω²x, Coriolis −2ω ẑ × u, friction, drag (a fixed-frame force, the same
        # vector seen in this frame at the same instant)
        a = w**2 * x - 2 * w * np.array([-u[1], u[0]]) - f * G * u / c + drag
        return np.concatenate((u, a))

    u0 = v0 - w * np.array([-r0[1], r0[0]])
    sol = solve_ivp(rotating, (0, t_end), np.concatenate((r0, u0)), method="Radau",
                    rtol=1e-11, atol=1e-14)  # fmt: skip
    x, u = sol.y[:2, -1], sol.y[2:, -1]
    turn = w * t_end
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    r_end = rot @ x
    v_end = rot @ (u + w * np.array([-x[1], x[0]]))
    assert flight.r[-1] == pytest.approx(r_end, rel=1e-8)
    assert flight.v[-1] == pytest.approx(v_end, rel=1e-8)


def test_the_floor_catches_a_granule_it_carries() -> None:
    """A granule sliding over the floor near the axis, where the floor's speed is below f g/ω:
    friction brings its velocity relative to the floor to 0 within the flight, and the flight
    says so (``caught``); a negative friction is refused."""
    w = 10.0
    result = FloorFlight(w, 0.5).integrate((0.0, 0.0), (0.3, 0.0), 1.0)
    assert result.event == "caught" and result.t[-1] < 1.0
    with pytest.raises(ValueError, match="friction"):
        FloorFlight(w, -0.1)
