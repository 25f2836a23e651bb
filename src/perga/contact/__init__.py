"""Contact models: how granules touch each other, the hammers and the chamber wall.

The registry :data:`MODELS` maps a case's ``contact_model.kind`` to the class that implements
:class:`~perga.contact.protocol.ContactModel`; a model is imported only when a simulation asks
for it, so a rigid run never loads the soft kernel. Adding a model is one module that
implements the protocol and one line here.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from perga.contact.protocol import ContactModel

MODELS = {
    "rigid": "perga.contact.rigid.model:RigidContacts",
    "linear": "perga.contact.soft.model:SoftContacts",
    "hertz": "perga.contact.soft.model:SoftContacts",
}
"""Contact model kind -> "module:class" of its implementation."""


def contact_model(kind: str) -> type[ContactModel] | Any:
    """The class of contact model ``kind`` (ValueError for an unknown kind)."""
    if kind not in MODELS:
        raise ValueError(f"unknown contact model {kind!r}: one of {', '.join(MODELS)}")
    module, name = MODELS[kind].split(":")
    return getattr(import_module(module), name)
