"""The rigid contact model's Pymunk objects: granule bodies, the chamber wall, the contact values
of every shape and the collision handlers, added to a machine's space.

* Granules: dynamic bodies with one ``Circle`` each; moment m r²/2 or ``inf`` (sliding point).
* Chamber: one convex quadrilateral per edge of the wall's inner outline on the space's static
  body, ``wall_thickness`` thick (:meth:`perga.model.system.ChamberSpec.pieces`). A round wall's
  inner outline is the polygon of ``segments`` sides circumscribing the circle (at most
  R(1/cos(π/N) − 1) outside it); a chamber from a file has its own outline. The wall shares the
  hammers' filter group.
* Contacts: Chipmunk multiplies the two shapes' elasticity and friction. Each material gets
  factors whose products equal the pair table (:func:`factor_pair_table`: one granule material
  gives 1 on it and the pair value on the others; granule-granule pairs take √), to within
  1 ulp; only a pair the table cannot split this way gets a ``pre_solve`` handler that sets
  ``arbiter.restitution`` and ``arbiter.friction`` (Chipmunk resets them to the product every
  step, so it must be ``pre_solve``, not ``begin``; docs/dev/performance.md has its cost).
  Collision types are one per (kind, material). Each handler phase runs a list of listeners
  (:meth:`RigidBodies.listen`), so that the pair setter and the impact recorder can share one
  handler.
* Filters: when ``granule_collisions`` is False all granules share a filter group, which
  removes granule pairs before the narrow phase.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import pymunk

from perga.machine import units as u
from perga.machine.machine import HAMMER_GROUP, Machine
from perga.model.system import GranuleSpec

Kind = Literal["granule", "hammer", "wall"]
Phase = Literal["begin", "pre_solve", "post_solve", "separate"]
Callback = Callable[[pymunk.Arbiter, pymunk.Space, Any], None]

GRANULE_GROUP = 2
"""Shape filter group of the granules when they do not collide with each other."""


@dataclass
class RigidBodies:
    """The rigid model's objects in a machine's space.

    ``shape_owner`` maps every granule shape to ("granule", its id) and every hammer shape to
    ("hammer", its index in the spec's list); ``granule_bodies`` and ``granule_shapes`` are in
    the contact model's row order;
    ``wall_shapes`` are the chamber's. ``collision_types`` maps (kind, material) to the Chipmunk
    collision type; ``pairs`` lists the (type_a, type_b) handlers installed, type_a being a
    granule type.
    """

    machine: Machine
    granule_bodies: list[pymunk.Body]
    granule_shapes: list[pymunk.Circle]
    wall_shapes: list[pymunk.Poly]
    shape_owner: dict[pymunk.Shape, tuple[Kind, int]]
    collision_types: dict[tuple[Kind, str], int]
    elasticity: dict[str, float] = field(default_factory=dict)
    friction: dict[str, float] = field(default_factory=dict)
    granule_group: int = 0
    pairs: list[tuple[int, int]] = field(default_factory=list)
    handlers: dict[tuple[int, int, Phase], _Listeners] = field(default_factory=dict)
    errors: list[BaseException] = field(default_factory=list)
    """Errors raised in listeners during a step (Chipmunk's callbacks cannot raise): the contact
    model raises the first after the step (:meth:`raise_errors`)."""

    def raise_errors(self) -> None:
        """Raise the first error a listener raised since the last call, if any."""
        if self.errors:
            error, self.errors[:] = self.errors[0], []
            raise error

    @property
    def space(self) -> pymunk.Space:
        """The machine's space, which holds them."""
        return self.machine.space

    def add_granule(self, g: GranuleSpec, id_: int) -> pymunk.Body:
        """Add granule ``g``, numbered ``id_``, to the space; returns its body."""
        body, shape = _build_granule(g)
        shape.filter = pymunk.ShapeFilter(group=self.granule_group)
        shape.elasticity = self.elasticity.get(g.material, 1.0)
        shape.friction = self.friction.get(g.material, 1.0)
        shape.collision_type = self.collision_types[("granule", g.material)]
        self.machine.space.add(body, shape)
        self.granule_bodies.append(body)
        self.granule_shapes.append(shape)
        self.shape_owner[shape] = ("granule", id_)
        return body

    def remove_granules(self, rows: list[int]) -> None:
        """Take the granules at ``rows`` (of ``granule_bodies``) out of the space."""
        gone = set(rows)
        for row in sorted(gone):
            body, shape = self.granule_bodies[row], self.granule_shapes[row]
            self.machine.space.remove(body, shape)
            del self.shape_owner[shape]
        keep = [i for i in range(len(self.granule_bodies)) if i not in gone]
        self.granule_bodies = [self.granule_bodies[i] for i in keep]
        self.granule_shapes = [self.granule_shapes[i] for i in keep]

    def listen(
        self, phase: Phase, callback: Callback, kinds: tuple[Kind, Kind] | None = None
    ) -> None:
        """Run ``callback(arbiter, space, None)`` in ``phase`` of every installed pair handler
        (shapes ordered granule first), or only of pairs of ``kinds`` (granule kind first)."""
        for kind_a, kind_b, type_a, type_b in self._typed_pairs():
            if kinds is None or (kind_a, kind_b) == kinds:
                self.listen_pair(type_a, type_b, phase, callback)

    def listen_pair(self, type_a: int, type_b: int, phase: Phase, callback: Callback) -> None:
        """Run ``callback`` in ``phase`` of the handler of collision types (type_a, type_b)."""
        key = (type_a, type_b, phase)
        if key not in self.handlers:
            self.handlers[key] = _Listeners(self.errors)
            self.machine.space.on_collision(
                type_a, type_b, data=self.handlers[key], **{phase: _dispatch}
            )
        self.handlers[key].append(callback)

    def _typed_pairs(self) -> list[tuple[Kind, Kind, int, int]]:
        kind_of = {t: k for (k, _), t in self.collision_types.items()}
        return [(kind_of[a], kind_of[b], a, b) for a, b in self.pairs]


class _Listeners(list):
    """The callbacks of one handler phase, and where their errors go."""

    def __init__(self, errors: list[BaseException]) -> None:
        super().__init__()
        self.errors = errors


def _dispatch(arbiter: pymunk.Arbiter, space: pymunk.Space, callbacks: _Listeners) -> None:
    try:
        for callback in callbacks:
            callback(arbiter, space, None)
    except Exception as error:  # Chipmunk's C caller would print it and go on
        callbacks.errors.append(error)


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


def _build_granule(g: GranuleSpec) -> tuple[pymunk.Body, pymunk.Circle]:
    mass = u.to_internal(g.mass, u.MASS)
    moment = u.to_internal(g.moment, u.MOMENT) if g.rolls else math.inf
    body = pymunk.Body(mass, moment)
    body.position = u.vec_to_internal(g.position, u.LENGTH)
    body.velocity = u.vec_to_internal(g.velocity, u.VELOCITY)
    body.angular_velocity = u.to_internal(g.angular_velocity, u.ANGULAR_VELOCITY)
    return body, pymunk.Circle(body, u.to_internal(g.radius, u.LENGTH))


def attach_bodies(machine: Machine, materials: set[str] | None = None) -> RigidBodies:
    """Add the granules, the chamber wall, every shape's contact values and the pair handlers
    to ``machine``'s space (module doc); ``materials``: granule materials that may come later
    (a feed), besides those present."""
    spec, space = machine.spec, machine.space
    collision_types: dict[tuple[Kind, str], int] = {}

    def ctype(kind: Kind, material: str) -> int:
        return collision_types.setdefault((kind, material), len(collision_types) + 1)

    contacts = {c.key: c for c in spec.contacts}
    elasticity, unsplit_e = factor_pair_table({k: c.restitution for k, c in contacts.items()})
    friction, unsplit_f = factor_pair_table({k: c.friction for k, c in contacts.items()})
    for h, shapes in zip(spec.hammers, machine.hammer_shapes, strict=True):
        for shape in shapes:
            shape.elasticity = elasticity.get(h.material, 1.0)
            shape.friction = friction.get(h.material, 1.0)
            shape.collision_type = ctype("hammer", h.material)
    for material in sorted({g.material for g in spec.granules} | (materials or set())):
        ctype("granule", material)
    bodies = RigidBodies(
        machine=machine,
        granule_bodies=[],
        granule_shapes=[],
        wall_shapes=[],
        shape_owner={
            s: ("hammer", k) for k, shapes in enumerate(machine.hammer_shapes) for s in shapes
        },
        collision_types=collision_types,
        elasticity=elasticity,
        friction=friction,
        granule_group=0 if spec.granule_collisions else GRANULE_GROUP,
    )
    for index, g in enumerate(spec.granules):
        bodies.add_granule(g, index)
    if spec.chamber is not None:
        static = space.static_body
        for piece in spec.chamber.pieces()[0]:
            shape = pymunk.Poly(static, [u.vec_to_internal(tuple(v), u.LENGTH) for v in piece])
            shape.filter = pymunk.ShapeFilter(group=HAMMER_GROUP)
            shape.elasticity = elasticity.get(spec.chamber.material, 1.0)
            shape.friction = friction.get(spec.chamber.material, 1.0)
            shape.collision_type = ctype("wall", spec.chamber.material)
            space.add(shape)
            bodies.wall_shapes.append(shape)
    granule_keys = [k for k in collision_types if k[0] == "granule"]
    other_keys = [k for k in collision_types if k[0] != "granule"]
    candidate = [(g, h) for g in granule_keys for h in other_keys]
    if spec.granule_collisions:
        candidate += [(a, b) for i, a in enumerate(granule_keys) for b in granule_keys[i:]]
    for key_a, key_b in candidate:
        contact = spec.contact(key_a[1], key_b[1])
        type_a, type_b = collision_types[key_a], collision_types[key_b]
        bodies.pairs.append((type_a, type_b))
        if contact.key in unsplit_e | unsplit_f:
            bodies.listen_pair(
                type_a, type_b, "pre_solve", _pair_setter(contact.restitution, contact.friction)
            )
    return bodies
