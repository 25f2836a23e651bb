"""The contact-model registry (perga.contact): 'rigid' and 'soft', a contact law's name (a case's
``contact_model.kind``) taken to the soft model, anything else refused."""

import pytest

from perga.contact import contact_model
from perga.contact.laws import LAWS
from perga.contact.rigid.model import RigidContacts
from perga.contact.soft.model import SoftContacts


def test_each_kind_names_its_model() -> None:
    assert contact_model("rigid") is RigidContacts
    assert all(contact_model(kind) is SoftContacts for kind in ("soft", *LAWS))


def test_an_unknown_kind_is_refused_with_the_known_ones_named() -> None:
    with pytest.raises(ValueError, match="'cohesive': one of rigid, soft, linear, hertz"):
        contact_model("cohesive")
