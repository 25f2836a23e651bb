"""The frame clock (``perga.output.recorders.PhaseLock``): how many steps to its next frame, as
stepping one step at a time and asking ``due`` finds it."""

import pytest

from perga.output.recorders import PhaseLock


def _one_by_one(clock: PhaseLock, step: int, dt: float) -> int:
    """The steps to the next frame found by asking ``due`` after each step (on a copy)."""
    probe = PhaseLock(clock.every)
    probe.frame = clock.frame
    n = step + 1
    while not probe.due(n * dt):
        n += 1
    return n - step


@pytest.mark.parametrize("dt", [1e-6, 1.369e-6, 2e-5, 0.1 / 3])
@pytest.mark.parametrize("steps", [1, 3, 7, 10, 25, 2.5, 13.37])
def test_steps_to_the_next_frame_are_those_due_finds(dt, steps) -> None:
    """Frames every ``steps`` steps of ``dt``, whole numbers among them (where round-off of
    k·every against n·dt decides): steps_to_next is the count ``due`` finds, for every frame
    of a run of 2,000 steps, and at a step between frames."""
    clock = PhaseLock(steps * dt)
    clock.due(0.0)
    step = 0
    while step < 2000:
        n = clock.steps_to_next(step, dt)
        assert n == _one_by_one(clock, step, dt)
        if n > 1:
            assert clock.steps_to_next(step + 1, dt) == n - 1
        assert [clock.due((step + k) * dt) for k in range(1, n + 1)] == [False] * (n - 1) + [True]
        step += n


def test_a_frame_already_due_is_one_step_away() -> None:
    """A clock whose frame falls due before the next step still waits for that step (at least
    one step: the simulation moves before it looks)."""
    clock = PhaseLock(1e-3)
    clock.due(0.0)
    assert clock.steps_to_next(100, 1e-4) == 1
