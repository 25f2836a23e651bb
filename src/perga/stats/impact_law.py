"""Every recorded granule-hammer impact of a run against the impact law with Coulomb friction,
its sticking cap and the hammer's full effective mass (:mod:`perga.analytic.coupled_impact`),
predicted from the state the impact log recorded just before it.

An impact is **isolated** when nothing but the hammer touches the granule and nothing but the
granule touches the hammer while it lasts (the log's ``other_contacts`` is 0: rigid, in the
impact's step; soft, at its start and its end) and the granule is not held in a comb's cell;
then the law describes it exactly for rigid contacts, and to the contact's duration for soft
ones. Every other impact is given its regime: the reason it cannot
match (a held granule, other contacts, a hammer at its swing stop, a touch without approach).
The hammer's effective mass: hinged on a rotor of prescribed speed, pivoted about its hinge
(its position from the rotor angle at the impact); free, about its centre (recorded at the
impact); welded to such a rotor, immovable.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from perga.analytic.coupled_impact import (
    coupled_impact,
    free_compliance,
    granule_compliance,
    pivoted_compliance,
)
from perga.model.compile import compile_case
from perga.model.system import HammerSpec
from perga.stats.episodes import in_words
from perga.stats.tables import Run

ISOLATED = "isolated"


@dataclass(frozen=True)
class ImpactCheck:
    """One impact, simulated against the law (SI; errors dimensionless)."""

    index: int
    """Row of impacts.csv."""
    time: float
    granule: int
    hammer: int
    regime: str
    """``ISOLATED``, or why the law cannot describe this impact."""
    velocity_error: float
    """|v'_sim − v'_law| / |v'_law|: the granule's velocity after, fixed frame."""
    spin_error: float
    """|ω'_sim − ω'_law|·r / |v'_law|: the spin after, as a rim speed against the velocity."""
    normal_restitution: tuple[float, float]
    """−u_n'/u_n, simulated and law."""
    tangential_ratio: tuple[float, float]
    """u_t'/u_t of the contact point's slip, simulated and law (nan without slip)."""
    dissipated: tuple[float, float]
    """Energy lost in the contact, J, simulated and law."""
    granule_gain: tuple[float, float]
    """The granule's kinetic-energy change, J, simulated and law."""
    sticks: bool
    """The law stops the slip within its cap."""
    speed_after: tuple[float, float] = (math.nan, math.nan)
    """|v'|, m/s, simulated and law."""
    relative_energy: float = math.nan
    """½m|u|², the granule's kinetic energy relative to the hammer's point before, J: the scale
    of the energy lost."""
    lab_energy: float = math.nan
    """½m|v'_law|², the granule's kinetic energy after in the fixed frame, J: the scale of the
    energy given."""


def _unavailable(run: Run) -> str | None:
    """Why no impact of ``run`` can be predicted, or None."""
    if not run.impacts or not run.impacts["time"].size:
        return "no granule-hammer impact was recorded"
    if "hammer_x_before" not in run.impacts:
        return "the impact log lacks the state after and the hammer's centre (an older run)"
    if run.case.rotor.inertia is not None:
        return "a driven rotor of finite inertia (the law here takes the rotor's speed as given)"
    return None


def _regime(row: dict[str, float], hammer: HammerSpec) -> str:
    if row["held"]:
        return "the granule is held in the comb"
    limit = hammer.swing_limit
    if limit is not None and abs(row["hammer_swing_angle_before"]) >= limit - 1e-9:
        return "the hammer at its swing stop"
    if row["other_contacts"] < 0:
        return "its other contacts were not recorded"
    if row["other_contacts"] > 0:
        count = int(row["other_contacts"])
        return f"{count} other contact{'s' if count > 1 else ''} during the impact"
    return ISOLATED


def _touch(index: int, row: dict[str, float]) -> ImpactCheck:
    """A contact that began without approach (u_n >= 0: pushed into touch, not struck)."""
    nan2 = (math.nan, math.nan)
    return ImpactCheck(
        index, row["time"], int(row["granule"]), int(row["hammer"]),
        "no approach (u_n >= 0): a touch, not an impact",
        math.nan, math.nan, nan2, nan2, (row["dissipated"], 0.0), nan2, False,
    )  # fmt: skip


def check_impacts(run: Run) -> list[ImpactCheck]:
    """Every recorded impact of ``run`` against the law; ValueError (its reason) where none can
    be predicted."""
    if reason := _unavailable(run):
        raise ValueError(f"{run.name}: {reason}")
    system = compile_case(run.case)
    pair = run.case.granule_hammer_contact
    radius = dict(zip(run.granules["id"].astype(int), run.granules["radius"], strict=True))
    mass = dict(zip(run.granules["id"].astype(int), run.granules["mass"], strict=True))
    rolls = run.case.granules.rolls
    impacts = run.impacts
    rotor_angles = run.rotor_angle(impacts["time"])
    checks = []
    for i in range(impacts["time"].size):
        row = {k: float(v[i]) for k, v in impacts.items()}
        hammer = system.hammers[int(row["hammer"])]
        g = int(row["granule"])
        m, r = float(mass[g]), float(radius[g])
        inertia = 0.5 * m * r * r if rolls else math.inf
        n = np.array([row["nx"], row["ny"]])
        n /= np.hypot(*n)
        t = np.array([-n[1], n[0]])
        K = granule_compliance(m, r, inertia)
        if hammer.mount == "hinged":
            angle = float(rotor_angles[i]) + hammer.angle_on_rotor
            hinge = hammer.hinge_radius * np.array([math.cos(angle), math.sin(angle)])
            arm = np.array([row["x"], row["y"]]) - hinge
            K = K + pivoted_compliance(hammer.moment_about_hinge, arm, n)
        elif hammer.mount == "free":
            arm = np.array([row["x"] - row["hammer_x_before"], row["y"] - row["hammer_y_before"]])
            K = K + free_compliance(hammer.mass, hammer.moment_about_centre, arm, n)
        u_n, u_t = row["normal_velocity_before"], row["tangential_velocity_before"]
        if u_n >= 0.0:
            checks.append(_touch(i, row))
            continue
        law = coupled_impact(u_n, u_t, pair.restitution, pair.friction, K)
        impulse = law.normal_impulse * n + law.tangential_impulse * t
        v0 = np.array([row["vx_before"], row["vy_before"]])
        v1 = np.array([row["vx_after"], row["vy_after"]])
        v1_law = v0 + impulse / m
        w0, w1 = row["granule_spin_before"], row["granule_spin_after"]
        w1_law = w0 - (0.0 if math.isinf(inertia) else r * law.tangential_impulse / inertia)
        rolling = 0.0 if math.isinf(inertia) else inertia  # a sliding point holds no spin energy
        gain_law = 0.5 * (m * (v1_law @ v1_law - v0 @ v0) + rolling * (w1_law**2 - w0**2))
        lost = -0.5 * (
            law.normal_impulse * (u_n + law.normal_velocity)
            + law.tangential_impulse * (u_t + law.tangential_velocity)
        )
        speed = float(np.hypot(*v1_law))
        checks.append(
            ImpactCheck(
                index=i,
                time=row["time"],
                granule=g,
                hammer=int(row["hammer"]),
                regime=_regime(row, hammer),
                velocity_error=float(np.hypot(*(v1 - v1_law))) / speed,
                spin_error=abs(w1 - w1_law) * r / speed,
                normal_restitution=(-row["normal_velocity_after"] / u_n, pair.restitution),
                tangential_ratio=(
                    row["tangential_velocity_after"] / u_t if u_t else math.nan,
                    law.tangential_velocity / u_t if u_t else math.nan,
                ),
                dissipated=(row["dissipated"], lost),
                granule_gain=(row["granule_energy_gain"], gain_law),
                sticks=law.sticks,
                speed_after=(float(np.hypot(*v1)), speed),
                relative_energy=0.5 * m * (u_n * u_n + u_t * u_t),
                lab_energy=0.5 * m * speed * speed,
            )
        )
    return checks


@dataclass(frozen=True)
class ImpactSummary:
    """A run's checked impacts taken together (:func:`summarise`)."""

    checks: list[ImpactCheck]
    compared: list[ImpactCheck]
    """Those the law predicts (a touch without approach is not)."""
    isolated: list[ImpactCheck]
    energy_share_isolated: float
    """The isolated impacts' share of the energy lost in impacts (0 without a loss)."""
    regimes: Counter[str] = field(default_factory=Counter)
    """How many impacts are in each regime but ``ISOLATED``."""

    @property
    def others(self) -> str:
        """The regimes but ``ISOLATED`` in words, most frequent first."""
        return in_words(self.regimes)

    def worst(self, count: int) -> list[ImpactCheck]:
        """The ``count`` compared impacts with the largest velocity errors, largest first."""
        return sorted(self.compared, key=lambda c: -c.velocity_error)[:count]

    def statistics(self) -> dict[str, dict[str, float]]:
        """Median and 99th percentile of each compared statistic's error over the isolated
        impacts: the velocity and spin after (:class:`ImpactCheck`'s errors), the normal
        restitution (relative), the slip's ratio (absolute), the energy lost (over the relative
        kinetic energy before, ½m·u²) and given (over the kinetic energy after, ½m·v′²), and
        each granule's energy lost in its isolated impacts (relative to the law's sum)."""
        iso = self.isolated
        columns = {
            "velocity after (over the speed after)": [(c.velocity_error, 0.0, 1.0) for c in iso],
            "spin after (rim speed, over the speed after)": [(c.spin_error, 0.0, 1.0) for c in iso],
            "normal restitution (relative)": [
                (*c.normal_restitution, c.normal_restitution[1]) for c in iso
            ],
            "slip ratio u_t′/u_t (absolute)": [(*c.tangential_ratio, 1.0) for c in iso],
            "energy lost (over ½m·u² before)": [(*c.dissipated, c.relative_energy) for c in iso],
            "energy given (over ½m·v′² after)": [(*c.granule_gain, c.lab_energy) for c in iso],
        }
        granules = sorted({c.granule for c in iso})
        lost = {g: [0.0, 0.0] for g in granules}
        for c in iso:
            lost[c.granule][0] += c.dissipated[0]
            lost[c.granule][1] += c.dissipated[1]
        columns["energy lost per granule (relative)"] = [
            (sim, law, abs(law)) for sim, law in lost.values() if law
        ]
        out = {}
        for name, rows in columns.items():
            errors = np.array([abs(a - b) / scale for a, b, scale in rows if math.isfinite(b)])
            if errors.size:
                out[name] = {
                    "median": float(np.median(errors)),
                    "p99": float(np.quantile(errors, 0.99)),
                }
        return out


def summarise(checks: list[ImpactCheck]) -> ImpactSummary:
    """``checks`` taken together: which are compared and isolated, the isolated impacts'
    share of the energy lost in impacts, the other regimes."""
    compared = [c for c in checks if math.isfinite(c.velocity_error)]
    isolated = [c for c in compared if c.regime == ISOLATED]
    lost = sum(abs(c.dissipated[0]) for c in checks)
    share = sum(abs(c.dissipated[0]) for c in isolated) / lost if lost else 0.0
    regimes = Counter(c.regime for c in checks if c.regime != ISOLATED)
    return ImpactSummary(checks, compared, isolated, share, regimes)
