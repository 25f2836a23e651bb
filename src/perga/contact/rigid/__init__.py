"""Rigid contacts: Pymunk's impulses (:class:`~perga.contact.rigid.model.RigidContacts`)."""
