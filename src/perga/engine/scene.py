"""SceneSpec -> Scene: the only place where pymunk objects are created.

Construction (all quantities converted to the internal units of :mod:`perga.engine.units`):

* Rotor: a kinematic body at the origin with ``angular_velocity = ω``; it carries no shapes of
  its own (a rotor disc is out of the granules' plane).
* Hammers, by mount:

  - ``hinged``: a dynamic body whose local origin is the hinge, with mass, centre of gravity
    and the moment about the centre of mass I_C = I_A − M|c|² from the spec, pinned to the
    rotor by a ``PivotJoint`` at the hinge. It starts co-rotating with the rotor.
  - ``welded``: the hammer's polygon is attached to the rotor body itself (its outline
    transformed into the rotor frame). At constant ω this is exactly rigid (no joint error,
    no solver iterations), and the hammer's mass properties are irrelevant because the
    kinematic rotor has infinite inertia. A future dynamic rotor must add them to the rotor.
  - ``free``: a dynamic body with no attachment, starting with the spec's velocity (for
    validation scenes such as a free two-body impact).

* Granules: dynamic bodies with one ``Circle`` each; moment m r²/2 or ``inf`` (sliding point).
* Contacts: Chipmunk multiplies the two shapes' elasticity and friction. Every shape gets
  elasticity = friction = 1 and each material-pair handler sets ``arbiter.restitution`` and
  ``arbiter.friction`` in ``pre_solve`` to the pair's exact values (Chipmunk resets them to
  the product every step, so it must be ``pre_solve``, not ``begin``). Collision types are
  one per (kind, material); handlers are registered only for pairs that can touch.
* Filters: all hammers share one non-zero ``ShapeFilter`` group (hammers never collide with
  each other); when ``granule_collisions`` is False all granules share another group, which
  removes granule pairs before the narrow phase.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import pymunk

from perga.engine import units as u
from perga.engine.spec import GranuleSpec, HammerSpec, SceneSpec

Kind = Literal["granule", "hammer"]

HAMMER_GROUP = 1
GRANULE_GROUP = 2


@dataclass
class Scene:
    """The pymunk objects of one scene, plus the bookkeeping recorders need.

    ``hammer_bodies[i]`` is the rotor body for a welded hammer. ``shape_owner`` maps every
    shape to (kind, index into the spec's list). ``collision_types`` maps (kind, material) to
    the Chipmunk collision type; ``pairs`` lists the (type_a, type_b) handlers installed,
    type_a being a granule type.
    """

    spec: SceneSpec
    space: pymunk.Space
    rotor: pymunk.Body
    hammer_bodies: list[pymunk.Body]
    hammer_shapes: list[pymunk.Poly]
    joints: list[pymunk.Constraint]
    granule_bodies: list[pymunk.Body]
    granule_shapes: list[pymunk.Circle]
    shape_owner: dict[pymunk.Shape, tuple[Kind, int]]
    collision_types: dict[tuple[Kind, str], int]
    pairs: list[tuple[int, int]] = field(default_factory=list)

    def on_granule_hammer(
        self,
        begin: Callable[[pymunk.Arbiter, pymunk.Space, Any], None] | None = None,
        post_solve: Callable[[pymunk.Arbiter, pymunk.Space, Any], None] | None = None,
        separate: Callable[[pymunk.Arbiter, pymunk.Space, Any], None] | None = None,
    ) -> None:
        """Add callbacks to every granule-hammer handler (shapes ordered granule, hammer)."""
        for kind_a, kind_b, type_a, type_b in self._typed_pairs():
            if (kind_a, kind_b) == ("granule", "hammer"):
                self.space.on_collision(
                    type_a, type_b, begin=begin, post_solve=post_solve, separate=separate
                )

    def _typed_pairs(self) -> list[tuple[Kind, Kind, int, int]]:
        kind_of = {t: k for (k, _), t in self.collision_types.items()}
        return [(kind_of[a], kind_of[b], a, b) for a, b in self.pairs]


def _rotate(x: float, y: float, angle: float) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return (c * x - s * y, s * x + c * y)


def _hinge_position(h: HammerSpec) -> tuple[float, float]:
    """Hinge position in the rotor frame (= fixed frame at t = 0), m."""
    return (
        h.hinge_radius * math.cos(h.angle_on_rotor),
        h.hinge_radius * math.sin(h.angle_on_rotor),
    )


def _set_pair(arbiter: pymunk.Arbiter, _space: pymunk.Space, data: tuple[float, float]) -> None:
    arbiter.restitution, arbiter.friction = data


def build_scene(spec: SceneSpec) -> Scene:
    """Build the pymunk space for ``spec`` (see the module docstring for the choices made)."""
    space = pymunk.Space()
    space.iterations = spec.iterations
    space.gravity = u.vec_to_internal(spec.gravity, u.ACCELERATION)
    space.collision_slop = u.to_internal(u.COLLISION_SLOP, u.LENGTH)

    omega = u.to_internal(spec.rotor.omega, u.ANGULAR_VELOCITY)
    rotor = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    rotor.position = (0.0, 0.0)
    rotor.angular_velocity = omega
    space.add(rotor)

    collision_types: dict[tuple[Kind, str], int] = {}

    def ctype(kind: Kind, material: str) -> int:
        return collision_types.setdefault((kind, material), len(collision_types) + 1)

    shape_owner: dict[pymunk.Shape, tuple[Kind, int]] = {}
    hammer_bodies: list[pymunk.Body] = []
    hammer_shapes: list[pymunk.Poly] = []
    joints: list[pymunk.Constraint] = []
    hammer_filter = pymunk.ShapeFilter(group=HAMMER_GROUP)
    for index, h in enumerate(spec.hammers):
        shape, body, joint = _build_hammer(h, rotor, omega)
        shape.filter = hammer_filter
        shape.elasticity = shape.friction = 1.0
        shape.collision_type = ctype("hammer", h.material)
        if body is not rotor:
            space.add(body)
        space.add(shape)
        if joint is not None:
            space.add(joint)
            joints.append(joint)
        hammer_bodies.append(body)
        hammer_shapes.append(shape)
        shape_owner[shape] = ("hammer", index)

    granule_bodies: list[pymunk.Body] = []
    granule_shapes: list[pymunk.Circle] = []
    granule_filter = (
        pymunk.ShapeFilter() if spec.granule_collisions else pymunk.ShapeFilter(group=GRANULE_GROUP)
    )
    for index, g in enumerate(spec.granules):
        body, shape = _build_granule(g)
        shape.filter = granule_filter
        shape.elasticity = shape.friction = 1.0
        shape.collision_type = ctype("granule", g.material)
        space.add(body, shape)
        granule_bodies.append(body)
        granule_shapes.append(shape)
        shape_owner[shape] = ("granule", index)

    scene = Scene(
        spec=spec,
        space=space,
        rotor=rotor,
        hammer_bodies=hammer_bodies,
        hammer_shapes=hammer_shapes,
        joints=joints,
        granule_bodies=granule_bodies,
        granule_shapes=granule_shapes,
        shape_owner=shape_owner,
        collision_types=collision_types,
    )
    granule_keys = [k for k in collision_types if k[0] == "granule"]
    hammer_keys = [k for k in collision_types if k[0] == "hammer"]
    candidate = [(g, h) for g in granule_keys for h in hammer_keys]
    if spec.granule_collisions:
        candidate += [(a, b) for i, a in enumerate(granule_keys) for b in granule_keys[i:]]
    for key_a, key_b in candidate:
        contact = spec.contact(key_a[1], key_b[1])
        type_a, type_b = collision_types[key_a], collision_types[key_b]
        space.on_collision(
            type_a, type_b, pre_solve=_set_pair, data=(contact.restitution, contact.friction)
        )
        scene.pairs.append((type_a, type_b))
    return scene


def _build_hammer(
    h: HammerSpec, rotor: pymunk.Body, omega: float
) -> tuple[pymunk.Poly, pymunk.Body, pymunk.Constraint | None]:
    hinge = u.vec_to_internal(_hinge_position(h), u.LENGTH)
    outline = [u.vec_to_internal(v, u.LENGTH) for v in h.outline]
    axis_angle = h.angle_on_rotor + h.swing_angle
    if h.mount == "welded":
        vertices = [
            (hinge[0] + x, hinge[1] + y)
            for x, y in (_rotate(vx, vy, axis_angle) for vx, vy in outline)
        ]
        return pymunk.Poly(rotor, vertices), rotor, None

    body = pymunk.Body(
        u.to_internal(h.mass, u.MASS), u.to_internal(h.moment_about_centre, u.MOMENT)
    )
    # order matters: centre of gravity, then angle, then position of the local origin (hinge)
    body.center_of_gravity = u.vec_to_internal(h.centre_of_mass, u.LENGTH)
    body.angle = axis_angle
    body.position = hinge
    shape = pymunk.Poly(body, outline)
    if h.mount == "free":
        body.velocity = u.vec_to_internal(h.velocity, u.VELOCITY)
        body.angular_velocity = u.to_internal(h.angular_velocity, u.ANGULAR_VELOCITY)
        return shape, body, None
    # hinged: co-rotate with the rotor (velocity of the centre of gravity = ω × r_cog)
    cog = body.local_to_world(body.center_of_gravity)
    body.velocity = (-omega * cog.y, omega * cog.x)
    body.angular_velocity = omega
    joint = pymunk.PivotJoint(rotor, body, hinge, (0.0, 0.0))
    joint.collide_bodies = False
    return shape, body, joint


def _build_granule(g: GranuleSpec) -> tuple[pymunk.Body, pymunk.Circle]:
    mass = u.to_internal(g.mass, u.MASS)
    moment = u.to_internal(g.moment, u.MOMENT) if g.rolls else math.inf
    body = pymunk.Body(mass, moment)
    body.position = u.vec_to_internal(g.position, u.LENGTH)
    body.velocity = u.vec_to_internal(g.velocity, u.VELOCITY)
    body.angular_velocity = u.to_internal(g.angular_velocity, u.ANGULAR_VELOCITY)
    return body, pymunk.Circle(body, u.to_internal(g.radius, u.LENGTH))
