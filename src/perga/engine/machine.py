"""SceneSpec -> Scene: the only place where pymunk objects are created.

Construction (all quantities converted to the internal units of :mod:`perga.engine.units`):

* Rotor: a kinematic body at the origin with ``angular_velocity = ω``; it carries no shapes of
  its own (a rotor disc is out of the granules' plane).
* Hammers, by mount:

  Each convex piece of the hammer's outline (``HammerSpec.pieces``) is one ``Poly`` on the
  hammer's body.

  - ``hinged``: a dynamic body whose local origin is the hinge, with mass, centre of gravity
    and the moment about the centre of mass I_C = I_A − M|c|² from the spec, pinned to the
    rotor by a ``PivotJoint`` at the hinge. It starts co-rotating with the rotor. With
    ``swing_limit`` a ``RotaryLimitJoint`` to the rotor stops it at α = ±swing_limit.
  - ``welded``: the hammer's polygons are attached to the rotor body itself (its outline
    transformed into the rotor frame). At constant ω this is exactly rigid (no joint error,
    no solver iterations), and the hammer's mass properties are irrelevant because the
    kinematic rotor has infinite inertia. A future dynamic rotor must add them to the rotor.
  - ``free``: a dynamic body with no attachment, starting with the spec's velocity (for
    validation scenes such as a free two-body impact).

* Granules: dynamic bodies with one ``Circle`` each; moment m r²/2 or ``inf`` (sliding point).
  With soft contacts (``spec.soft``) there are none: granules and the chamber wall are arrays
  of :mod:`perga.contact.soft`, stepped by :class:`~perga.contact.soft.model.SoftSimulation`;
  Pymunk then holds only the rotor and the hammers.
* Chamber (optional, rigid contacts only): one convex quadrilateral per edge of the wall's inner
  outline on the space's static body, ``wall_thickness`` thick (:mod:`perga.geometry.wall`).
  A round wall's inner outline is the polygon of ``segments`` sides circumscribing the circle
  (at most R(1/cos(π/N) − 1) outside it, 8e-5 m for R = 0.15 m, N = 96); a chamber from a file
  has its own outline. They share the hammers' filter group.
* Effects: :mod:`perga.engine.effects` builds exactly the effects the spec lists, after
  everything else (the drive turns the rotor into a dynamic body).
* Contacts: Chipmunk multiplies the two shapes' elasticity and friction. Each material gets
  factors whose products equal the pair table (:func:`factor_pair_table`: one granule
  material gives 1 on it and the pair value on the others; granule-granule pairs take √), to
  within 1 ulp; only a pair the table cannot split this way gets a ``pre_solve`` handler that
  sets ``arbiter.restitution`` and ``arbiter.friction`` (Chipmunk resets them to the product
  every step, so it must be ``pre_solve``, not ``begin``). The callback is what made the
  engine 1.5× bare Pymunk (docs/performance.md). Collision types are one per (kind,
  material). Each handler phase runs a list of listeners (:meth:`Scene.listen`), so that the
  pair setter, the impact recorder and the energy meter can share one handler.
* Filters: all hammers and the chamber share one non-zero ``ShapeFilter`` group (hammers never
  collide with each other or with the wall); when ``granule_collisions`` is False all granules
  share another group, which removes granule pairs before the narrow phase.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pymunk

from perga.engine import units as u
from perga.engine.effects import Effect, SwingStops, build_effects
from perga.geometry.wall import circumscribed, wall_pieces
from perga.model.spec import ChamberSpec, GranuleSpec, HammerSpec, SceneSpec, Vec2

Kind = Literal["granule", "hammer", "wall"]
Phase = Literal["begin", "pre_solve", "post_solve", "separate"]
Callback = Callable[[pymunk.Arbiter, pymunk.Space, Any], None]

HAMMER_GROUP = 1
GRANULE_GROUP = 2


@dataclass
class Scene:
    """The pymunk objects of one scene, plus the bookkeeping recorders need.

    ``hammer_bodies[i]`` is the rotor body for a welded hammer; ``hammer_shapes[i]`` are hammer
    i's convex pieces, ``hammer_outlines[i]`` its whole outline in its body's frame (internal
    units). ``shape_owner`` maps every
    granule and hammer shape to (kind, index into the spec's list); ``wall_shapes`` are the
    chamber's. ``collision_types`` maps (kind, material) to the Chipmunk collision type;
    ``pairs`` lists the (type_a, type_b) handlers installed, type_a being a granule type.
    ``effects`` are the effects built (:mod:`perga.engine.effects`), in build order.
    """

    spec: SceneSpec
    space: pymunk.Space
    rotor: pymunk.Body
    hammer_bodies: list[pymunk.Body]
    hammer_shapes: list[tuple[pymunk.Poly, ...]]
    hammer_outlines: list[list[tuple[float, float]]]
    joints: list[pymunk.Constraint]
    granule_bodies: list[pymunk.Body]
    granule_shapes: list[pymunk.Circle]
    shape_owner: dict[pymunk.Shape, tuple[Kind, int]]
    collision_types: dict[tuple[Kind, str], int]
    wall_shapes: list[pymunk.Poly] = field(default_factory=list)
    pairs: list[tuple[int, int]] = field(default_factory=list)
    effects: list[Effect] = field(default_factory=list)
    _listeners: dict[tuple[int, int, Phase], list[Callback]] = field(default_factory=dict)

    def listen(
        self, phase: Phase, callback: Callback, kinds: tuple[Kind, Kind] | None = None
    ) -> None:
        """Run ``callback(arbiter, space, None)`` in ``phase`` of every installed pair handler
        (shapes ordered granule first), or only of pairs of ``kinds`` (granule kind first)."""
        for kind_a, kind_b, type_a, type_b in self._typed_pairs():
            if kinds is None or (kind_a, kind_b) == kinds:
                self._listen_pair(type_a, type_b, phase, callback)

    def _listen_pair(self, type_a: int, type_b: int, phase: Phase, callback: Callback) -> None:
        key = (type_a, type_b, phase)
        if key not in self._listeners:
            self._listeners[key] = []
            self.space.on_collision(type_a, type_b, data=self._listeners[key], **{phase: _dispatch})
        self._listeners[key].append(callback)

    def on_granule_hammer(
        self,
        begin: Callback | None = None,
        post_solve: Callback | None = None,
        separate: Callback | None = None,
    ) -> None:
        """Add callbacks to every granule-hammer handler (shapes ordered granule, hammer)."""
        for phase, callback in (
            ("begin", begin),
            ("post_solve", post_solve),
            ("separate", separate),
        ):
            if callback is not None:
                self.listen(phase, callback, ("granule", "hammer"))

    def _typed_pairs(self) -> list[tuple[Kind, Kind, int, int]]:
        kind_of = {t: k for (k, _), t in self.collision_types.items()}
        return [(kind_of[a], kind_of[b], a, b) for a, b in self.pairs]


def _dispatch(arbiter: pymunk.Arbiter, space: pymunk.Space, callbacks: list[Callback]) -> None:
    for callback in callbacks:
        callback(arbiter, space, None)


def _ends(pair: frozenset[str]) -> tuple[str, str]:
    """The two materials of a pair (the same one twice for a self pair)."""
    items = sorted(pair)
    return items[0], items[-1]


def factor_pair_table(
    table: dict[frozenset[str], float],
) -> tuple[dict[str, float], set[frozenset[str]]]:
    """Per-material factors whose pairwise products reproduce ``table`` (pair -> value).

    A breadth-first walk over the material graph gives each material a factor from one pair,
    starting from materials with a self pair (factor √value), else from factor 1; every pair
    is then checked to a relative 4 ulp. Returns the factors and the pairs they do not
    reproduce (those keep a per-contact setter). A zero factor stops the walk, so tables with
    zeros split only where the zero can be carried by one material.
    """
    neighbours: dict[str, set[str]] = {}
    for pair in table:
        a, b = _ends(pair)
        neighbours.setdefault(a, set()).add(b)
        neighbours.setdefault(b, set()).add(a)
    roots = sorted(neighbours, key=lambda m: (frozenset((m,)) not in table, m))
    factors: dict[str, float] = {}
    for root in roots:
        if root in factors:
            continue
        self_value = table.get(frozenset((root,)))
        factors[root] = math.sqrt(self_value) if self_value is not None else 1.0
        queue = [root]
        while queue:
            a = queue.pop(0)
            for b in sorted(neighbours[a]):
                if b not in factors and factors[a] > 0:
                    factors[b] = table[frozenset((a, b))] / factors[a]
                    queue.append(b)
    unsplit = set()
    for pair, value in table.items():
        a, b = _ends(pair)
        product = factors.get(a, math.nan) * factors.get(b, math.nan)
        if not (math.isfinite(product) and abs(product - value) <= 4 * 2.2e-16 * abs(value)):
            unsplit.add(pair)
    return factors, unsplit


def _pair_setter(restitution: float, friction: float) -> Callback:
    def set_pair(arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: Any) -> None:
        arbiter.restitution, arbiter.friction = restitution, friction

    return set_pair


def _rotate(x: float, y: float, angle: float) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return (c * x - s * y, s * x + c * y)


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

    contacts = {c.key: c for c in spec.contacts}
    elasticity, unsplit_e = factor_pair_table({k: c.restitution for k, c in contacts.items()})
    friction, unsplit_f = factor_pair_table({k: c.friction for k, c in contacts.items()})

    def add_shape(shape: pymunk.Shape, kind: Kind, material: str, group: int) -> None:
        shape.filter = pymunk.ShapeFilter(group=group)
        shape.elasticity = elasticity.get(material, 1.0)
        shape.friction = friction.get(material, 1.0)
        shape.collision_type = ctype(kind, material)
        space.add(shape)

    shape_owner: dict[pymunk.Shape, tuple[Kind, int]] = {}
    hammer_bodies: list[pymunk.Body] = []
    hammer_shapes: list[tuple[pymunk.Poly, ...]] = []
    hammer_outlines: list[list[tuple[float, float]]] = []
    joints: list[pymunk.Constraint] = []
    stops: list[pymunk.RotaryLimitJoint] = []
    for index, h in enumerate(spec.hammers):
        body, place, joint = _build_hammer(h, rotor, omega)
        if body is not rotor:
            space.add(body)
        shapes = tuple(pymunk.Poly(body, [place(v) for v in piece]) for piece in h.pieces)
        for shape in shapes:
            add_shape(shape, "hammer", h.material, HAMMER_GROUP)
            shape_owner[shape] = ("hammer", index)
        if joint is not None:
            space.add(joint)
            joints.append(joint)
            if h.swing_limit is not None:
                stops.append(_build_stops(h, rotor, body))
                space.add(stops[-1])
        hammer_bodies.append(body)
        hammer_shapes.append(shapes)
        hammer_outlines.append([place(v) for v in h.outline])

    granule_bodies: list[pymunk.Body] = []
    granule_shapes: list[pymunk.Circle] = []
    granule_group = 0 if spec.granule_collisions else GRANULE_GROUP
    rigid = spec.soft is None  # soft granules and their wall live in perga.contact.soft, not here
    for index, g in enumerate(spec.granules if rigid else ()):
        body, shape = _build_granule(g)
        space.add(body)
        add_shape(shape, "granule", g.material, granule_group)
        granule_bodies.append(body)
        granule_shapes.append(shape)
        shape_owner[shape] = ("granule", index)

    wall_shapes: list[pymunk.Poly] = []
    if spec.chamber is not None and rigid:
        for shape in _build_chamber(spec.chamber, space.static_body):
            add_shape(shape, "wall", spec.chamber.material, HAMMER_GROUP)
            wall_shapes.append(shape)

    scene = Scene(
        spec=spec,
        space=space,
        rotor=rotor,
        hammer_bodies=hammer_bodies,
        hammer_shapes=hammer_shapes,
        hammer_outlines=hammer_outlines,
        joints=joints,
        granule_bodies=granule_bodies,
        granule_shapes=granule_shapes,
        shape_owner=shape_owner,
        collision_types=collision_types,
        wall_shapes=wall_shapes,
    )
    granule_keys = [k for k in collision_types if k[0] == "granule"]
    other_keys = [k for k in collision_types if k[0] != "granule"]
    candidate = [(g, h) for g in granule_keys for h in other_keys]
    if spec.granule_collisions:
        candidate += [(a, b) for i, a in enumerate(granule_keys) for b in granule_keys[i:]]
    for key_a, key_b in candidate:
        contact = spec.contact(key_a[1], key_b[1])
        type_a, type_b = collision_types[key_a], collision_types[key_b]
        scene.pairs.append((type_a, type_b))
        if contact.key in unsplit_e | unsplit_f:
            scene._listen_pair(
                type_a, type_b, "pre_solve", _pair_setter(contact.restitution, contact.friction)
            )
    scene.effects = build_effects(scene)
    if stops:
        scene.effects.append(SwingStops(stops))
    return scene


def _build_hammer(
    h: HammerSpec, rotor: pymunk.Body, omega: float
) -> tuple[pymunk.Body, Callable[[Vec2], Vec2], pymunk.Constraint | None]:
    """The hammer's body (the rotor for a welded one), the map of a hammer-frame point (m) to
    the body's frame (internal units), and its hinge joint (None unless hinged)."""
    hinge = u.vec_to_internal(h.hinge_position, u.LENGTH)
    axis_angle = h.angle_on_rotor + h.swing_angle
    if h.mount == "welded":

        def on_rotor(v: Vec2) -> Vec2:
            x, y = _rotate(*u.vec_to_internal(v, u.LENGTH), axis_angle)
            return (hinge[0] + x, hinge[1] + y)

        return rotor, on_rotor, None

    def on_hammer(v: Vec2) -> Vec2:
        return u.vec_to_internal(v, u.LENGTH)

    body = pymunk.Body(
        u.to_internal(h.mass, u.MASS), u.to_internal(h.moment_about_centre, u.MOMENT)
    )
    # order matters: centre of gravity, then angle, then position of the local origin (hinge)
    body.center_of_gravity = u.vec_to_internal(h.centre_of_mass, u.LENGTH)
    body.angle = axis_angle
    body.position = hinge
    if h.mount == "free":
        body.velocity = u.vec_to_internal(h.velocity, u.VELOCITY)
        body.angular_velocity = u.to_internal(h.angular_velocity, u.ANGULAR_VELOCITY)
        return body, on_hammer, None
    # hinged: co-rotate with the rotor (velocity of the centre of gravity = ω × r_cog)
    cog = body.local_to_world(body.center_of_gravity)
    body.velocity = (-omega * cog.y, omega * cog.x)
    body.angular_velocity = omega
    joint = pymunk.PivotJoint(rotor, body, hinge, (0.0, 0.0))
    joint.collide_bodies = False
    return body, on_hammer, joint


def _build_stops(h: HammerSpec, rotor: pymunk.Body, body: pymunk.Body) -> pymunk.RotaryLimitJoint:
    """Stops holding a hinged hammer's α in [−swing_limit, swing_limit]: the hammer's angle
    relative to the rotor is angle_on_rotor + α."""
    assert h.swing_limit is not None
    stops = pymunk.RotaryLimitJoint(
        rotor, body, h.angle_on_rotor - h.swing_limit, h.angle_on_rotor + h.swing_limit
    )
    stops.collide_bodies = False
    return stops


def _build_granule(g: GranuleSpec) -> tuple[pymunk.Body, pymunk.Circle]:
    mass = u.to_internal(g.mass, u.MASS)
    moment = u.to_internal(g.moment, u.MOMENT) if g.rolls else math.inf
    body = pymunk.Body(mass, moment)
    body.position = u.vec_to_internal(g.position, u.LENGTH)
    body.velocity = u.vec_to_internal(g.velocity, u.VELOCITY)
    body.angular_velocity = u.to_internal(g.angular_velocity, u.ANGULAR_VELOCITY)
    return body, pymunk.Circle(body, u.to_internal(g.radius, u.LENGTH))


def chamber_inner_outline(chamber: ChamberSpec) -> np.ndarray:
    """The wall's inner outline, m: the chamber's outline, or the circumscribed polygon of a
    round wall's circle."""
    if chamber.outline is not None:
        return np.array(chamber.outline, dtype=float)
    return circumscribed(chamber.radius, chamber.segments)


def chamber_pieces(chamber: ChamberSpec) -> tuple[list[np.ndarray], np.ndarray]:
    """The wall's convex pieces and its outer outline, m
    (:func:`perga.geometry.wall.wall_pieces`)."""
    return wall_pieces(chamber_inner_outline(chamber), chamber.wall_thickness)


def _build_chamber(chamber: ChamberSpec, static: pymunk.Body) -> list[pymunk.Poly]:
    """One quadrilateral per edge of the wall's inner outline, ``wall_thickness`` thick."""
    return [
        pymunk.Poly(static, [u.vec_to_internal(tuple(v), u.LENGTH) for v in piece])
        for piece in chamber_pieces(chamber)[0]
    ]
