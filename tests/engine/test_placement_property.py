"""No granule starts, or is fed in, overlapping another granule, a hammer or the chamber wall:
a property test over random machines, packs and feeds (Hypothesis, seeded in CI by its
database-free derandomised profile). The check is independent of perga's own
(:mod:`perga.geometry.clearance`): hammers are asked through Chipmunk's ``point_query`` on the
machine's real collision shapes, granule pairs by brute force."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from perga.case import CaseError, load_case
from perga.engine import Simulation
from perga.machine import units as u
from perga.model.compile import compile_case

CASE = """
[rotor]
plane = "horizontal"
rpm = {rpm}
radius = 0.03

[hammers]
count = {hammers}
mass = 0.03
hinge_radius = {hinge}
material = "steel"
shape = {{ kind = "plate", length = {length}, width = {width}, hinge_offset = 0.005 }}

[granules]
count = {count}
radius = {radius}
thickness = 0.006
placement = {{ kind = "random", inner_radius = 0.005, outer_radius = {outer} }}

[chamber]
radius = {chamber}
wall_thickness = 0.02

[materials.beebread]
density = 1400.0

[materials.steel]
density = 7850.0

[[contacts]]
pair = ["beebread", "steel"]
restitution = 0.7
friction = 0.35

[[contacts]]
pair = ["beebread", "beebread"]
restitution = 0.6
friction = 0.5

[effects.granule_collisions]

[feed]
rate = 3000.0
region = {{ centre = [{fx}, {fy}], size = [{fw}, {fw}] }}

[solver]
duration = 0.01
seed = {seed}
"""


def _overlaps(sim: Simulation, first: int = 0) -> list[str]:
    """Granules numbered from ``first`` on that overlap a hammer's collision shape, another
    granule, or the wall (1e-12 m rounding allowed). Granules already in play may overlap a
    little in a contact (Chipmunk's slop); those just put in may not."""
    state = sim.contacts.granule_state()
    p, r = state.positions, state.radii
    new = state.ids >= first
    found = []
    for shapes in sim.machine.hammer_shapes:
        for shape in shapes:
            for i in np.flatnonzero(new):
                d = shape.point_query(tuple(p[i] / u.LENGTH)).distance * u.LENGTH
                if d < r[i] - 1e-12:
                    found.append(f"granule {state.ids[i]} in a hammer ({d:.3g} < {r[i]:.3g} m)")
    gap = np.linalg.norm(p[:, None] - p[None], axis=2) - (r[:, None] + r[None])
    i, j = np.nonzero(np.triu(gap < -1e-12, 1) & (new[:, None] | new[None]))
    found += [
        f"granules {state.ids[a]} and {state.ids[b]} overlap" for a, b in zip(i, j, strict=True)
    ]
    outside = new & (np.hypot(*p.T) + r > sim.spec.chamber.radius)
    found += [f"granule {k} outside the wall" for k in state.ids[outside]]
    return found


@settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    rpm=st.floats(100.0, 3000.0),
    hammers=st.integers(1, 6),
    hinge=st.floats(0.04, 0.08),
    length=st.floats(0.03, 0.07),
    width=st.floats(0.01, 0.03),
    count=st.integers(1, 120),
    radius=st.floats(0.0015, 0.003),
    fill=st.floats(0.3, 1.0),
    feed_at=st.tuples(st.floats(0.0, 2 * math.pi), st.floats(0.0, 0.7), st.floats(0.005, 0.03)),
    seed=st.integers(0, 2**16),
)
def test_nothing_starts_or_is_fed_inside_anything(
    tmp_path_factory, rpm, hammers, hinge, length, width, count, radius, fill, feed_at, seed
):
    chamber = hinge + length + 0.03
    angle, where, size = feed_at
    centre = where * (chamber - size)
    text = CASE.format(
        rpm=rpm, hammers=hammers, hinge=hinge, length=length, width=width, count=count,
        radius=radius, outer=0.005 + fill * (chamber - 0.006), chamber=chamber,
        fx=centre * math.cos(angle), fy=centre * math.sin(angle), fw=size, seed=seed,
    )  # fmt: skip
    path = Path(tmp_path_factory.mktemp("case")) / "case.toml"
    path.write_text(text)
    try:
        case = load_case(path)
    except CaseError as refused:  # a pack that does not fit is refused, naming the key
        assert all("granules" in p or "feed" in p for p in refused.problems), refused.problems
        return
    sim = Simulation(compile_case(case))
    assert _overlaps(sim) == []
    for _ in range(20):
        before = sim.fed
        sim.step()
        if sim.fed > before:
            assert _overlaps(sim, before) == [], f"after feeding at t = {sim.time:g} s"
