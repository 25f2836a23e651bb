"""System -> the soft granules of a scene: arrays, contact tables, chamber wall, hammers.

Materials: the granules' and the chamber's share the kernel's pair table (:mod:`perga.contact.soft.
laws`); the hammers' materials index the columns of the granule-polygon table
(:mod:`perga.contact.soft.polygon_set`). Each pair's row is calibrated to the pair's
restitution, uses its friction and its normal stiffness k_n (:attr:`ContactSpec.stiffness`: N/m
linear, (4/3)E* Pa Hertz; the kernel multiplies a Hertz k_n by √R* of each contact's own radii).
Pairs that never touch (wall-wall) get an inert placeholder row, which the kernel never reads.
"""

from __future__ import annotations

import math

import numpy as np

from perga.contact.soft import SoftGranules, chamber, contact_parameters, pair_table
from perga.contact.soft.polygon_set import ContactTable, PolygonSet, contact_table
from perga.model.system import SoftContactSpec, System


def granule_table_materials(spec: System) -> list[str]:
    """The granule table's materials: those of the granules present and fed, sorted, then a
    round chamber's."""
    materials = sorted(spec.granule_materials)
    chamber_wall = spec.chamber is not None and spec.chamber.outline is None
    if chamber_wall and spec.chamber.material not in materials:
        materials.append(spec.chamber.material)
    return materials


def kernel_table(spec: System, materials: list[str]) -> np.ndarray:
    """The kernel's (n_mat, n_mat, N_PARAMS) table over ``materials`` (granules and wall)."""
    soft = spec.contact_model
    assert isinstance(soft, SoftContactSpec)
    pairs = spec.touching_pairs()
    rows = {}
    for i, a in enumerate(materials):
        for j in range(i, len(materials)):
            b = materials[j]
            if frozenset((a, b)) in pairs:
                c = spec.contact(a, b)
                assert c.stiffness is not None
                k, ratio, e, f = c.stiffness, c.tangential_ratio, c.restitution, c.friction
                rolling = soft.rolling
            else:  # never touch: a valid row that is never read
                k, ratio, e, f, rolling = 1.0, 0.0, 1.0, 0.0, 0.0
            rows[(i, j)] = contact_parameters(
                soft.model,
                e,
                k_n=k,
                friction=f,
                rolling=rolling,
                kt_ratio=ratio,
                zeta_t=soft.tangential_damping,
                end=soft.end,
            )
    return pair_table(len(materials), rows)


def polygon_table(spec: System, materials: list[str], polygon_materials: list[str]) -> ContactTable:
    """The granule-polygon table: rows ``materials`` (granules' used), columns the polygons'."""
    soft = spec.contact_model
    assert isinstance(soft, SoftContactSpec)
    shape = (len(materials), len(polygon_materials))
    k_n, k_t = np.ones(shape), np.zeros(shape)
    e, f = np.ones(shape), np.zeros(shape)
    granule_materials = spec.granule_materials
    for i, a in enumerate(materials):
        for j, b in enumerate(polygon_materials):
            if a in granule_materials:
                c = spec.contact(a, b)
                assert c.stiffness is not None
                k_n[i, j], e[i, j], f[i, j] = c.stiffness, c.restitution, c.friction
                k_t[i, j] = c.tangential_ratio * c.stiffness
    return contact_table(k_n, k_t, e, f, soft.model, soft.end, soft.tangential_damping)


def soft_granules(
    spec: System,
    polygons: PolygonSet,
    polygon_materials: list[str],
    threads: int,
    chunks: int,
) -> SoftGranules:
    """The system's granules as :class:`~perga.contact.soft.SoftGranules` at step
    ``spec.granule_dt``, with a round chamber wall (the kernel's circle) and the ``polygons``
    (hammers and a drawn wall: a posed :class:`~perga.contact.soft.polygon_set.PolygonSet` whose
    ``mat`` indexes ``polygon_materials``), its pair forces in ``chunks`` chunks computed on
    ``threads`` threads."""
    materials = granule_table_materials(spec)
    walls = []
    if spec.chamber is not None and spec.chamber.outline is None:
        walls.append(chamber(spec.chamber.radius, mat=materials.index(spec.chamber.material)))
    g = spec.granules
    return SoftGranules(
        np.array([x.position for x in g], dtype=float).reshape(-1, 2),
        np.array([x.radius for x in g], dtype=float),
        np.array([x.mass for x in g], dtype=float),
        kernel_table(spec, materials),
        v=np.array([x.velocity for x in g], dtype=float).reshape(-1, 2),
        w=np.array([x.angular_velocity for x in g], dtype=float),
        mat=np.array([materials.index(x.material) for x in g], dtype=np.int32),
        walls=walls,
        gravity=spec.gravity,
        dt=spec.granule_dt,
        polygons=polygons,
        polygon_table=polygon_table(spec, materials, polygon_materials),
        threads=threads,
        chunks=chunks,
        pairs=spec.granule_collisions,
        held=np.array([x.bond_force is not None for x in g], dtype=bool),
        bond_force=np.array([math.inf if x.bond_force is None else x.bond_force for x in g]),
        bond_energy=np.array([x.bond_energy for x in g], dtype=float),
    )
