"""The impact log's count of a struck granule's other contacts (``impacts._other_contacts``,
the ``other_contacts`` column of impacts.csv), on a scene built so that each kind of contact is
counted, or left out, by construction."""

from __future__ import annotations

import numpy as np

from perga.contact.soft import chamber, plane
from perga.contact.soft.impacts import _other_contacts

R = 1e-3  # m: every granule's radius


def test_each_kind_of_contact_is_counted_once_and_the_struck_hammer_is_left_out() -> None:
    """Four granules of r = 1 mm in a chamber of 10 mm with a floor at y = −8.5 mm; polygons 0
    and 1 are two pieces of a hammer that moves under contacts, polygon 2 is a welded one.

    - granule 0 at (9.5, 0) mm overlaps the chamber wall and granule 1 at (7.6, 0) mm; it
      touches both pieces of the hammer and polygon 2;
    - granule 2 at (0, −8) mm overlaps the floor (0.5 mm) and touches polygon 2 alone;
    - granule 3 at (0, 5) mm touches nothing but piece 0.

    Struck by piece 0, granule 0 counts granule 1, the wall and polygon 2, not its own hammer's
    pieces, and, the hammer being movable, the other granules' contacts with its pieces
    (granule 1 on piece 1, granule 3 on piece 0): 5. Granule 2 struck by the welded polygon
    counts the floor alone: 1 (granule 0's contact with the welded polygon is not its own). Granule
    3 struck by piece 0 counts the three contacts of granules 0 and 1 with the movable
    hammer's pieces: 3. Granule 1, struck alone by piece 1, counts granule 0 (before it in the
    neighbour list) and the three contacts of granules 0 and 3 with the hammer's pieces: 4."""
    x = np.array([[9.5e-3, 0.0], [7.6e-3, 0.0], [0.0, -8e-3], [0.0, 5e-3]])
    r = np.full(4, R)
    start = np.array([0, 1, 2, 3, 3])  # the half list: (0, 1), (1, 2), (2, 3)
    nbr = np.array([1, 2, 3])
    active = np.zeros((4, 3))
    active[0, [0, 1, 2]] = 1.0
    active[1, 1] = 1.0
    active[2, 2] = 1.0
    active[3, 0] = 1.0
    hammer_of = np.array([0, 0, 1])
    movable = np.array([True, False])
    walls = np.array([chamber(10e-3), plane((0.0, -8.5e-3), (0.0, 1.0))])
    pairs = np.array([[0, 0], [2, 2], [3, 0]])

    counts = _other_contacts(pairs, hammer_of, movable, x, r, start, nbr, True, active, walls)

    assert counts.tolist() == [5, 1, 3]
    alone = np.array([[1, 1]])  # granule 1 is only the second of its pair in the half list
    counts = _other_contacts(alone, hammer_of, movable, x, r, start, nbr, True, active, walls)
    assert counts.tolist() == [4]


def test_without_pair_forces_the_granules_do_not_count() -> None:
    """The same granule 0 in a case without granule collisions (no neighbour list of pairs):
    the wall alone."""
    x = np.array([[9.5e-3, 0.0], [7.6e-3, 0.0]])
    active = np.zeros((2, 1))
    active[0, 0] = 1.0
    counts = _other_contacts(
        np.array([[0, 0]]), np.array([0]), np.array([False]), x, np.full(2, R),
        np.array([0, 1, 1]), np.array([1]), False, active, np.array([chamber(10e-3)]),
    )  # fmt: skip
    assert counts.tolist() == [1]
