"""The machine's construction (and the system spec's validation): filters,
only-what-is-asked-for, unit round trips."""

from __future__ import annotations

import math

import pytest

from perga.engine import Simulation
from perga.geometry.polygon import is_convex, signed_area
from perga.model import ContactSpec, GranuleSpec, HammerSpec, RotorSpec, System
from tests.engine.helpers import plate, rectangle


def _head_on(granule_collisions: bool, contacts: tuple[ContactSpec, ...]) -> Simulation:
    r = 0.002
    granules = tuple(
        GranuleSpec(position=(x, 0.0), velocity=(v, 0.0), radius=r, mass=50e-6, material="bb")
        for x, v in ((-0.005, 5.0), (0.005, -5.0))
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(),
        granules=granules,
        contacts=contacts,
        granule_dt=1e-5,
        granule_collisions=granule_collisions,
    )
    sim = Simulation(spec)
    sim.run(2e-3)
    return sim


def test_granule_collisions_off_leaves_no_handler_and_granules_pass() -> None:
    sim = _head_on(False, ())
    assert sim.contacts.bodies.pairs == []
    # exact: no contact ever touches them, velocities are untouched
    assert sim.frame().granules.velocities[:, 0].tolist() == [5.0, -5.0]


def test_granule_collisions_on_bounce_with_pair_restitution() -> None:
    sim = _head_on(True, (ContactSpec("bb", "bb", restitution=0.5, friction=0.2),))
    # equal masses, e = 0.5: each leaves at e·5 m/s backwards (exact to rounding)
    assert sim.frame().granules.velocities[:, 0] == pytest.approx([-2.5, 2.5], rel=1e-12)


def test_missing_and_unused_pairs_are_errors() -> None:
    granule = GranuleSpec(
        position=(0.1, 0.0), velocity=(0, 0), radius=0.002, mass=1e-5, material="bb"
    )
    hammer = plate(0, 0.1, -0.01, 0.01, 0.05, hinge_radius=0.1, angle_on_rotor=0.0,
                   mount="hinged", material="steel")  # fmt: skip
    with pytest.raises(ValueError, match=r"no contact parameters for materials \['bb', 'steel'\]"):
        System(RotorSpec(10.0, 0.2), (hammer,), (granule,), (), granule_dt=1e-5)
    with pytest.raises(ValueError, match="unused"):
        System(
            RotorSpec(10.0, 0.2), (hammer,), (granule,),
            (ContactSpec("bb", "steel", 0.5, 0.3), ContactSpec("bb", "bb", 0.5, 0.3)),
            granule_dt=1e-5,
        )  # fmt: skip


def test_invalid_hammer_lists_every_problem() -> None:
    with pytest.raises(ValueError) as info:
        HammerSpec(
            outline=rectangle(0, 0.1, -0.01, 0.01), mass=-1.0, moment_about_hinge=1e-4,
            centre_of_mass=(0.05, 0.0), hinge_radius=-0.1, angle_on_rotor=0.0,
            mount="glued", material="steel",  # type: ignore[arg-type]
        )  # fmt: skip
    message = str(info.value)
    for part in ("mass", "hinge_radius", "mount"):
        assert part in message


def test_hinged_hammer_pose_and_mass_properties() -> None:
    """The body's mass, moment about its centre of mass (I_A − M|c|²), hinge position and
    initial co-rotation come out in SI as given (exact to rounding)."""
    omega, R, phi = 50.0, 0.1, 0.7
    hammer = plate(-0.01, 0.09, -0.01, 0.01, 0.078, hinge_radius=R, angle_on_rotor=phi,
                   mount="hinged", material="steel", swing_angle=0.1)  # fmt: skip
    spec = System(RotorSpec(omega, 0.2), (hammer,), (), (), granule_dt=1e-5)
    sim = Simulation(spec)
    body = sim.machine.hammer_bodies[0]
    assert body.mass * 1e-3 == pytest.approx(0.078, rel=1e-12)
    assert body.moment * 1e-9 == pytest.approx(hammer.moment_about_centre, rel=1e-12)
    assert tuple(body.position * 1e-3) == pytest.approx((R * math.cos(phi), R * math.sin(phi)))
    assert body.angular_velocity * 1e3 == pytest.approx(omega, rel=1e-12)
    assert sim.frame().machine.swing_angles[0] == pytest.approx(0.1, rel=1e-12)
    # the pivot joint is in the space, and there are no collision handlers without granules
    assert len(sim.machine.hinges) == 1
    assert sim.contacts.bodies.pairs == []  # type: ignore[attr-defined]


def _notched(outline) -> HammerSpec:
    return HammerSpec(
        outline=outline, mass=0.05, moment_about_hinge=1e-3, centre_of_mass=(0.05, 0.0),
        hinge_radius=0.1, angle_on_rotor=0.0, mount="hinged", material="steel",
    )  # fmt: skip


def test_concave_outline_becomes_convex_pieces_on_one_body() -> None:
    """Chipmunk would silently use the hull of a concave polygon; the spec splits it into
    convex pieces (their areas add up to the outline's to round-off) and the scene puts one
    Poly per piece on the hammer's body."""
    notch = ((0.0, -0.01), (0.1, -0.01), (0.1, 0.01), (0.05, 0.0), (0.0, 0.01))
    hammer = _notched(notch)
    assert len(hammer.pieces) == 2
    assert all(is_convex(p) for p in hammer.pieces)
    assert sum(signed_area(p) for p in hammer.pieces) == pytest.approx(
        signed_area(notch), rel=1e-12
    )
    sim = Simulation(System(RotorSpec(10.0, 0.2), (hammer,), (), (), granule_dt=1e-5))
    shapes = sim.machine.hammer_shapes[0]
    assert len(shapes) == 2
    assert all(s.body is sim.machine.hammer_bodies[0] for s in shapes)
    owner = sim.contacts.bodies.shape_owner  # type: ignore[attr-defined]
    assert all(owner[s] == ("hammer", 0) for s in shapes)
    assert len(sim.machine.hammer_outlines[0]) == 5


def test_self_intersecting_outline_is_refused() -> None:
    bow_tie = ((0.0, -0.01), (0.1, 0.01), (0.1, -0.01), (0.0, 0.01))
    with pytest.raises(ValueError, match="cross"):
        _notched(bow_tie)
