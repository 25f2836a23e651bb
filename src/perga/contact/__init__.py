"""Contact models: how granules touch each other, the hammers and the chamber wall.

The registry :data:`MODELS` maps a contact model's kind to the class that implements
:class:`~perga.contact.protocol.ContactModel`; a model is imported only when a simulation asks
for it, so a rigid run never loads the soft kernel. The soft model takes every contact law
(:data:`perga.contact.laws.LAWS`), which a case names as its kind. Adding a model is one module
that implements the protocol and one line here; adding a law, one module and one line there.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from perga.contact.laws import LAWS

if TYPE_CHECKING:
    from perga.contact.protocol import ContactModel

MODELS = {
    "rigid": "perga.contact.rigid.model:RigidContacts",
    "soft": "perga.contact.soft.model:SoftContacts",
}
"""Contact model kind -> "module:class" of its implementation."""


def contact_model(kind: str) -> type[ContactModel] | Any:
    """The class of contact model ``kind``: a key of :data:`MODELS`, or a contact law's name
    (the soft model); ValueError for an unknown kind."""
    model = "soft" if kind in LAWS else kind
    if model not in MODELS:
        known = ", ".join([*MODELS, *LAWS])
        raise ValueError(f"unknown contact model {kind!r}: one of {known}")
    module, name = MODELS[model].split(":")
    return getattr(import_module(module), name)
