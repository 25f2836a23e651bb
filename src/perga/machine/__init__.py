"""The machine in Pymunk, below the contact models: rotor, hammers and joints (:mod:`.machine`),
the effects (:mod:`.effects`: drive, hinge friction, swing stops, the kicks of floor friction
and air drag), the energy meter (:mod:`.energy`), Chipmunk's raw state and its step from
compiled code (:mod:`.chipmunk_state`, :mod:`.compiled`), and Chipmunk's internal units
(:mod:`.units`). It never imports a contact model or the simulation."""

from perga.machine.machine import Machine, build_machine

__all__ = ["Machine", "build_machine"]
