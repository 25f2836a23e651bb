"""The rigid contacts' dissipation and moment (perga.contact.rigid.dissipation) against the
per-contact callbacks they replace."""

import numpy as np
import pytest
from tests.engine.helpers import plate

from perga.engine import Simulation
from perga.machine import units
from perga.model import ContactSpec, GranuleSpec, RotorSpec, System

R_G = 0.002


class _CallbackReference:
    """The contact term measured the old way, per contact in ``pre_solve``/``post_solve``
    (swap-aware ``contact_point_set``, ``velocity_at_world_point``): what the batch meter
    replaces."""

    def __init__(self, sim: Simulation) -> None:
        self.contact = 0.0
        self.moment = 0.0
        self._machine = {sim.machine.rotor, *(j.b for j in sim.machine.hinges)}
        self._pending: dict = {}
        sim.contacts.bodies.listen("pre_solve", self._pre_solve)
        sim.contacts.bodies.listen("post_solve", self._post_solve)

    @staticmethod
    def _relative(arbiter, pa, pb):
        a, b = arbiter.bodies
        return a.velocity_at_world_point(pa) - b.velocity_at_world_point(pb)

    def _pre_solve(self, arbiter, _space, _data) -> None:
        point = arbiter.contact_point_set.points[0]
        pa, pb = point.point_a, point.point_b
        self._pending[arbiter.shapes] = (pa, pb, self._relative(arbiter, pa, pb))

    def _post_solve(self, arbiter, _space, _data) -> None:
        pa, pb, before = self._pending.pop(arbiter.shapes)
        impulse = arbiter.total_impulse
        self.contact -= 0.5 * impulse.dot(before + self._relative(arbiter, pa, pb))
        if arbiter.bodies[1] in self._machine:
            self.moment -= pb.cross(impulse)


@pytest.mark.parametrize("first", ["a", "b"])
@pytest.mark.parametrize("mount", ["hinged", "welded"])
def test_batch_contact_term_equals_per_contact_callbacks(mount: str, first: str) -> None:
    """The arbiter meter reads contacts through ``pymunk.batch`` after the step; the per-contact
    callbacks it replaces give the same contact dissipation and contact moment on the
    rotor-driven bodies, step by step, to rounding (measured ~1e-14 of the step's largest
    term). Two granule materials in both orders, so that the batch reads some arbiters in the
    opposite body order to the callbacks' (asserted to happen: the meter must not depend on
    the order), rolling granules with friction in a packed cluster (several contacts per
    body). Also: every touching arbiter's normal impulse pushes its bodies apart in the read
    order (J·n <= 0), i.e. ids, normal, impulse and points are consistent."""
    R = 0.12
    hammer = plate(
        -0.01, 0.09, -0.01, 0.01, 0.078,
        hinge_radius=R, angle_on_rotor=0.0, mount=mount, material="steel",
    )  # fmt: skip
    other = "b" if first == "a" else "a"
    granules = tuple(
        GranuleSpec(
            position=(
                R + 0.02 + 2.05 * R_G * (i + 0.5 * (j % 2)),
                0.01 + R_G + 1e-4 + 1.8 * R_G * j,
            ),
            velocity=(0.0, 0.0),
            radius=R_G,
            mass=100e-6,
            material=first if (i + j) % 2 else other,
        )
        for i in range(6)
        for j in range(3)
    )
    contacts = (
        ContactSpec("a", "steel", restitution=0.6, friction=0.3),
        ContactSpec("b", "steel", restitution=0.4, friction=0.5),
        ContactSpec("a", "a", restitution=0.5, friction=0.4),
        ContactSpec("b", "b", restitution=0.3, friction=0.2),
        ContactSpec("a", "b", restitution=0.7, friction=0.35),
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=100.0, radius=0.2),
        hammers=(hammer,),
        granules=granules,
        contacts=contacts,
        granule_dt=1e-5,
        granule_collisions=True,
    )
    sim = Simulation(spec, record_impacts=False)
    reference = _CallbackReference(sim)
    meter = sim.contacts.arbiters  # type: ignore[attr-defined]
    assert meter is not None
    dt = units.to_internal(sim.dt, units.TIME)
    material = {
        b.id: g.material for b, g in zip(sim.contacts.bodies.granule_bodies, granules, strict=True)
    }
    orders: set[tuple[str, str]] = set()
    touching = 0
    largest = worst = worst_moment = 0.0
    for _ in range(300):
        c0, c0_ref, m0_ref = meter.dissipated, reference.contact, reference.moment
        meter.before_step()
        sim.machine.space.step(dt)
        moment = meter.after_step()
        step, step_ref = meter.dissipated - c0, reference.contact - c0_ref
        largest = max(largest, abs(step_ref))
        worst = max(worst, abs(step - step_ref))
        worst_moment = max(worst_moment, abs(moment - (reference.moment - m0_ref)))
        ids, f = meter.touching()
        assert np.all((f[:, 0:2] * f[:, 2:4]).sum(axis=1) <= 0)
        assert np.all(((f[:, 6:8] - f[:, 4:6]) * f[:, 2:4]).sum(axis=1) < 0)
        orders |= {(material.get(int(a), "-"), material.get(int(b), "-")) for a, b in ids}
        touching += len(f)
    assert touching > 300 and largest > 0
    assert worst <= 1e-12 * largest
    assert meter.dissipated == pytest.approx(reference.contact, rel=1e-12)
    assert worst_moment <= 1e-12 * max(abs(reference.moment), 1e-30) or reference.moment == 0
    assert {("a", "b"), ("b", "a")} <= orders, orders
