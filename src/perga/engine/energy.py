"""Energy ledger: every term measured on its own, so that their balance is a real check.

Per step Chipmunk changes each body's velocity by impulses (contacts, joints, motors) and kicks
(gravity, the effects' velocity functions). For one body the exact change of kinetic energy
over the step is Σ J·v̄ over those impulses, v̄ the mean of the velocities at the application
point before and after the step. The ledger uses that identity term by term:

* ``contact_dissipation``: per contact, −J·(v̄_a − v̄_b), J the arbiter's total impulse on the
  first body, v_a, v_b the two bodies' velocities at their own contact points, taken in
  ``pre_solve`` (start of step: before gravity, kicks and impulses) and ``post_solve`` (end of
  step). This is exact for one contact (it reproduces ½μ(1 − e²)w² of a free impact to
  rounding) and covers restitution losses, dynamic and static friction alike. Chipmunk's
  ``arbiter.total_ke`` is not used: it assumes one impact and ignores dynamic friction. Limits:
  where several impulses act on a body in one step each contact is still charged with the
  body's whole-step mean velocity, which is the exact split of ΔKE but attributes the other
  impulses' cross terms to the contacts, and when gravity or a kick acts in the same step the
  velocity before includes neither (the kick's energy is counted by the kick itself at its own
  velocities), so the split is exact to first order in dt; Chipmunk's position correction
  (``v_bias``) moves bodies without changing velocities and is not an energy term.
* ``drive_work``: the work the rotor does on the rest, impulse × the rotor's velocity at the
  application point. Chipmunk exposes only |impulse| for a pivot joint or motor, so the rotor's
  angular impulse about its axis is measured through the angular momentum balance of the
  rotor-driven bodies (hinged hammers, plus the rotor itself when it is driven): ΔL about the
  axis, minus the contact impulses on those bodies and on welded hammers (from the arbiters)
  and minus gravity's moment; times the rotor's angular velocity (its mean over the step when
  driven). This is the moment equation, not the energy equation, so the closure remains an
  independent check. The co-rotating floor's work comes from its own kicks.
* ``friction``, ``drag``: what the effects removed (:mod:`perga.engine.effects`).
* ``gravity_work``: the potential energy released by in-plane gravity, Σ m g·Δr_cg.
* ``closure`` = (drive_work + gravity_work − ΔKE − contact_dissipation − friction − drag) /
  max(|drive_work|, |ΔKE|, |gravity_work|, ½Σ_i|ΔKE_i|, 1e-30 J): the pivot joints' error
  correction, the first-order split of the kicks and rounding, nothing else. The term
  ½Σ_i|ΔKE_i| (kinetic energy moved between bodies) keeps the closure meaningful where nothing
  is driven or lost, e.g. an elastic free impact (ΔKE = 0).

Costs: one pre- and one post-solve callback per touching contact, a loop over the few
rotor-driven bodies per step, and a loop over all bodies only when :meth:`EnergyMeter.ledger`
is called.
"""

from __future__ import annotations

from dataclasses import dataclass

import pymunk

from perga.engine import units as u
from perga.engine.scene import Scene

TINY = 1e-30
"""J: the closure's denominator floor (a scene where nothing moves has closure 0)."""


@dataclass(frozen=True)
class EnergyLedger:
    """Cumulative energy terms since t = 0, J (SI); ``closure`` is dimensionless."""

    kinetic: float
    """Current kinetic energy of all dynamic bodies (translation and rotation)."""
    kinetic_initial: float
    """Kinetic energy at t = 0."""
    drive_work: float
    """Work done by the rotor (kinematic or driven) on the other bodies."""
    gravity_work: float
    """Work done by in-plane gravity (potential energy released)."""
    contact_dissipation: float
    """Energy lost in granule-hammer, granule-granule and granule-wall contacts."""
    friction: float
    """Energy removed by floor and hinge friction."""
    drag: float
    """Energy removed by air drag."""
    closure: float
    """(drive + gravity − ΔKE − contact − friction − drag) / energy scale (module doc)."""


def _kinetic(body: pymunk.Body) -> float:
    """½m|v|² + ½Iω² (internal units); no rotational term for an infinite moment."""
    spin = 0.0 if body.moment == float("inf") else body.moment * body.angular_velocity**2
    return 0.5 * (body.mass * body.velocity.dot(body.velocity) + spin)


def _centre(body: pymunk.Body) -> pymunk.Vec2d:
    return body.local_to_world(body.center_of_gravity)


class EnergyMeter:
    """Measures the ledger's terms of one scene from the moment it is built (see module doc).

    Call :meth:`before_step` and :meth:`after_step` around every ``space.step``.
    """

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._space = scene.space
        self._rotor = scene.rotor
        driven = scene.rotor.body_type == pymunk.Body.DYNAMIC
        self._bodies = [b for b in scene.space.bodies if b.body_type == pymunk.Body.DYNAMIC]
        hinged = [j.b for j in scene.joints]
        self._machine = ([scene.rotor] if driven else []) + hinged
        self._machine_set = {scene.rotor, *hinged}
        self._needs_balance = bool(self._machine or scene.rotor.shapes)
        self._kinetics0 = [_kinetic(b) for b in self._bodies]
        self._centres0 = [_centre(b) for b in self._bodies]
        self._contact = 0.0
        self._drive = 0.0
        self._moment = 0.0  # contact angular impulse on rotor-driven bodies this step
        self._before: list[tuple[pymunk.Vec2d, float]] = []
        self._pending: dict[tuple[pymunk.Shape, pymunk.Shape], tuple[pymunk.Vec2d, ...]] = {}
        scene.listen("pre_solve", self._pre_solve)
        scene.listen("post_solve", self._post_solve)

    # --- contacts --------------------------------------------------------------------------

    @staticmethod
    def _points(arbiter: pymunk.Arbiter) -> tuple[pymunk.Vec2d, pymunk.Vec2d]:
        # granules are circles: one contact point per arbiter
        point = arbiter.contact_point_set.points[0]
        return point.point_a, point.point_b

    @staticmethod
    def _relative(arbiter: pymunk.Arbiter, pa: pymunk.Vec2d, pb: pymunk.Vec2d) -> pymunk.Vec2d:
        a, b = arbiter.bodies
        return a.velocity_at_world_point(pa) - b.velocity_at_world_point(pb)

    def _pre_solve(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        pa, pb = self._points(arbiter)
        self._pending[arbiter.shapes] = (pa, pb, self._relative(arbiter, pa, pb))

    def _post_solve(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        pa, pb, before = self._pending.pop(arbiter.shapes)
        after = self._relative(arbiter, pa, pb)
        impulse = arbiter.total_impulse  # on the first body
        self._contact -= 0.5 * impulse.dot(before + after)
        if arbiter.bodies[1] in self._machine_set:
            self._moment -= pb.cross(impulse)

    # --- the rotor's angular momentum balance ------------------------------------------------

    def before_step(self) -> None:
        """Record the rotor-driven bodies' velocities at the start of a step."""
        if not self._needs_balance:
            return
        self._before = [(b.velocity, b.angular_velocity) for b in self._machine]
        self._omega0 = self._rotor.angular_velocity

    def after_step(self, dt: float) -> None:
        """Add the step's drive work; ``dt`` in internal time units."""
        if not self._needs_balance:
            return
        gravity = self._space.gravity
        moment = -self._moment
        for body, (v0, w0) in zip(self._machine, self._before, strict=True):
            r = _centre(body)
            moment += body.mass * r.cross(body.velocity - v0 - gravity * dt)
            moment += body.moment * (body.angular_velocity - w0)
        self._drive += 0.5 * (self._omega0 + self._rotor.angular_velocity) * moment
        self._moment = 0.0

    # --- the ledger ------------------------------------------------------------------------

    def ledger(self) -> EnergyLedger:
        """The cumulative terms now, in J."""
        gravity = self._space.gravity
        kinetics = [_kinetic(b) for b in self._bodies]
        kinetic, kinetic0 = sum(kinetics) * u.ENERGY, sum(self._kinetics0) * u.ENERGY
        moved = 0.5 * sum(abs(k - k0) for k, k0 in zip(kinetics, self._kinetics0, strict=True))
        gravity_work = (
            sum(
                b.mass * gravity.dot(_centre(b) - r0)
                for b, r0 in zip(self._bodies, self._centres0, strict=True)
            )
            * u.ENERGY
        )
        terms = {"friction": 0.0, "drag": 0.0, "drive": 0.0}
        supplied = 0.0
        for effect in self._scene.effects:
            terms[effect.term] += effect.removed
            supplied += effect.supplied
        drive = self._drive * u.ENERGY + supplied
        contact = self._contact * u.ENERGY
        change = kinetic - kinetic0
        residual = drive + gravity_work - change - contact - terms["friction"] - terms["drag"]
        scale = max(abs(drive), abs(change), abs(gravity_work), moved * u.ENERGY, TINY)
        return EnergyLedger(
            kinetic=kinetic,
            kinetic_initial=kinetic0,
            drive_work=drive,
            gravity_work=gravity_work,
            contact_dissipation=contact,
            friction=terms["friction"],
            drag=terms["drag"],
            closure=residual / scale,
        )
