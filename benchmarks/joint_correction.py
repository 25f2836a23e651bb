"""Issue 15, item 2: how much of the energy ledger's residual is the pivot joints' correction
work. Per step, each pivot's accumulated impulse J (read raw, ``perga.machine.chipmunk_state``)
times the mean relative velocity of its two anchors, v̄_b − v̄_a (each body's velocity before and
after the step at the lever arm of the step's new positions, where Chipmunk applies the
impulse): the energy the joint's position correction puts in (or takes out). An ideal hinge does
no work; the ledger books the rotor's side as drive work and the hammer's gain as kinetic
energy, so their difference shows up as the residual.

    python benchmarks/joint_correction.py single-granule 0.01
    python benchmarks/joint_correction.py separator 0.1 rotor.rpm=3000
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pymunk

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.machine import units as u
from perga.machine.chipmunk_state import JointImpulses
from perga.model.compile import compile_case


def mean_anchor_velocity(body: pymunk.Body, local: pymunk.Vec2d, v0, w0) -> pymunk.Vec2d:
    """The anchor's velocity, mean of before (v0, w0) and now, at the lever arm of now."""
    r = body.local_to_world(local) - body.local_to_world(body.center_of_gravity)
    w = 0.5 * (w0 + body.angular_velocity)
    return 0.5 * (v0 + body.velocity) + w * pymunk.Vec2d(-r.y, r.x)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("case", help="a bundled case's name")
    parser.add_argument("duration", type=float, help="simulated s")
    parser.add_argument("overrides", nargs="*", help="KEY=VALUE")
    args = parser.parse_args()
    case = load_case(Path("cases") / f"{args.case}.toml", overrides=args.overrides)
    sim = Simulation(compile_case(case))
    pivots = [c for c in sim.machine.space.constraints if isinstance(c, pymunk.PivotJoint)]
    impulses = JointImpulses(pivots)
    work = at_b = 0.0
    for _ in range(round(args.duration / sim.dt)):
        before = [(c.a.velocity, c.a.angular_velocity, c.b.velocity, c.b.angular_velocity)
                  for c in pivots]  # fmt: skip
        sim.step()
        for c, (va, wa, vb, wb), j in zip(
            pivots, before, impulses.read().reshape(-1, 2), strict=True
        ):
            impulse = pymunk.Vec2d(*j)
            relative = mean_anchor_velocity(c.b, c.anchor_b, vb, wb) - mean_anchor_velocity(
                c.a, c.anchor_a, va, wa
            )
            work += impulse.dot(relative)
            # the rotor's velocity at the hammer's anchor: where the meter's drive rule (the
            # angular momentum balance of the hinged body) puts the impulse
            anchor_b = c.b.local_to_world(c.anchor_b)
            rotor_at_b = mean_anchor_velocity(c.a, c.a.world_to_local(anchor_b), va, wa)
            at_b += impulse.dot(mean_anchor_velocity(c.b, c.anchor_b, vb, wb) - rotor_at_b)
    e = sim.energy()
    change = e.kinetic - e.kinetic_initial + e.elastic - e.elastic_initial
    residual = (e.drive_work + e.gravity_work + e.inflow - e.outflow - change
                - e.contact_dissipation - e.friction - e.drag)  # fmt: skip
    joints, joints_b = work * u.ENERGY, at_b * u.ENERGY
    print(f"{args.case} {' '.join(args.overrides)} t = {args.duration} s: ledger residual "
          "without its joint_correction term "
          f"{residual:.5g} J (closure {e.closure:+.2%}); the pivots' correction work "
          f"{joints:.5g} J (residual + it: {residual + joints:.3g} J); measured against the "
          f"rotor at the hammer's anchor {joints_b:.5g} J (residual + it: "
          f"{residual + joints_b:.3g} J)")  # fmt: skip


if __name__ == "__main__":
    main()
