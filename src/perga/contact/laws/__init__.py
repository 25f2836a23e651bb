"""Normal contact laws of the soft contacts, one object each (as MercuryDPM's species).

The registry :data:`LAWS` maps a law's name (a case's ``contact_model.kind`` other than
'rigid') to the class that implements :class:`~perga.contact.laws.base.ContactLaw`; a law's
module is imported when it is asked for. A law knows its damping from e, its stiffness from a
contact duration or from the materials, its contact duration, its k_t/k_n and the row it hands
the kernel, on the closed forms of :mod:`perga.analytic.contact`. This package imports
``perga.analytic`` and numpy only, never the kernel: the case, the system and the kernel all ask
it. Adding a law is one module that implements the interface and one line here.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from perga.contact.laws.base import ContactLaw

LAWS = {
    "linear": "perga.contact.laws.linear:Linear",
    "hertz": "perga.contact.laws.hertz:Hertz",
}
"""Contact law name -> "module:class" of its implementation."""


def contact_law(name: str) -> ContactLaw:
    """The contact law ``name`` (ValueError naming the known laws for an unknown one)."""
    if name not in LAWS:
        raise ValueError(f"unknown contact law {name!r}: one of {', '.join(LAWS)}")
    module, cls = LAWS[name].split(":")
    law: ContactLaw = getattr(import_module(module), cls)()
    return law
