"""After a kernel call, ``SoftGranules.f`` and ``tq`` hold the contact forces and torques of
the call's last step (the kernel stores them only then)."""

import copy

import numpy as np

from perga.contact.soft import contact_parameters

from .helpers import chamber_gas


def test_a_call_keeps_its_last_steps_forces() -> None:
    """A dense gas in a chamber (pairs, wall contacts, friction): one call of 7 steps leaves
    the same forces and torques, bit for bit, as 7 calls of one step, whose last call's are
    the 7th step's; and they are not those of a call's first step."""
    row = contact_parameters("linear", 0.6, k_n=1e5, friction=0.4)
    g = chamber_gas(40, 5, row, overlapping=True)
    one_call, first = copy.deepcopy(g), copy.deepcopy(g)
    one_call.step(7)
    for _ in range(7):
        g.step(1)
    first.step(1)
    assert np.count_nonzero(g.f[:, 0]) >= 5 and np.count_nonzero(g.tq) >= 3
    assert np.array_equal(one_call.f, g.f) and np.array_equal(one_call.tq, g.tq)
    assert not np.array_equal(one_call.f, first.f)
