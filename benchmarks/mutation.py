"""Mutation testing of perga's pure-Python physics with cosmic-ray (docs/dev/testing.md).

Each module of ``MODULES`` is mutated by cosmic-ray (one mutant at a time, the file rewritten in
place and restored, the module's fast tests run in a fresh process, sequentially on one core),
with the operator set of ``EXCLUDED_OPERATORS`` and numba's JIT off (``NUMBA_DISABLE_JIT=1``:
a jitted law is then plain Python, so every mutant is seen by every caller, with no stale numba
cache of an inlining caller). Sessions are kept in ``build/mutation/`` (git-ignored); the
report counts killed, timed-out, survived and known-equivalent mutants (``EQUIVALENT``) and the
score killed/(run − equivalent), timeouts counted as killed.

    pip install -e '.[test,mutation]'
    python benchmarks/mutation.py                 # every module (about 2 h on one core)
    python benchmarks/mutation.py impact contact  # some modules
    python benchmarks/mutation.py --report        # the report of the kept sessions only
    python benchmarks/mutation.py --show impact   # the surviving mutants' diffs
    python benchmarks/mutation.py --sample contact 18 10 40  # timeouts re-checked on a sample
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WORK = ROOT / "build" / "mutation"
TIMEOUT = 30.0
"""Seconds a mutant's tests may run (each module's tests take 2-6 s unmutated; a mutant of the
Hertz-Tsuji integration can integrate for ever)."""


@dataclass(frozen=True)
class Module:
    """A source file to mutate and the test files that cover it (paths from the repo root)."""

    source: str
    tests: tuple[str, ...]
    timeout: float = TIMEOUT
    """Seconds a mutant's tests may run."""


MODULES = {
    "impact": Module("src/perga/analytic/impact.py", ("tests/analytic/test_impact.py",)),
    # 60 s, 16x the unmutated run (3.3-3.8 s): at 10 s, 141 mutants timed out unchecked
    # (docs/dev/testing.md); many mutants of the Hertz-Tsuji integration never end
    "contact": Module("src/perga/analytic/contact.py", ("tests/analytic/test_contact.py",), 60.0),
    "laws": Module(
        "src/perga/contact/soft/laws.py",
        ("tests/contact/soft/test_restitution.py", "tests/contact/soft/test_chung_ooi.py"),
    ),
    "timestep": Module(
        "src/perga/model/plan.py",
        (
            "tests/model/test_plan.py",
            "tests/model/test_pair_stiffness.py",
            "tests/model/test_materials.py",
            "tests/model/test_tangential_stiffness.py",
        ),
    ),
    "records": Module(
        "src/perga/model/records.py",
        (
            "tests/machine/test_energy.py",
            "tests/engine/test_process.py::test_an_impact_carries_its_specific_energy",
        ),
    ),
    "energy": Module("src/perga/machine/energy.py", ("tests/machine/test_energy.py",)),
}

# Operators (cosmic-ray's names, regexes matched at the start): the arithmetic operator replaced
# by its inverse (+ ↔ −, × ↔ ÷) and ** by ×, comparisons moved across their boundary (< ↔ <=,
# > ↔ >=, == ↔ !=, is ↔ is not), and all of cosmic-ray's other operators (numbers ±1, not
# added or removed, True/False, and/or, unary signs, exceptions, loops). Left out: the other
# arithmetic pairs and the integer/bitwise operators (//, %, <<, >>, |, &, ^: on floats they
# raise TypeError or repeat an inverse; the only |, & here are in annotations), comparisons
# turned into identity tests, and RemoveDecorator (removing @njit leaves the same function).
_KEPT_BINARY = "Add_Sub|Sub_Add|Mul_Div|Div_Mul|Pow_Mul"
_KEPT_COMPARISON = "Lt_LtE|LtE_Lt|Gt_GtE|GtE_Gt|Eq_NotEq|NotEq_Eq|Is_IsNot|IsNot_Is"
EXCLUDED_OPERATORS = (
    rf"core/ReplaceBinaryOperator_(?!(?:{_KEPT_BINARY})$)",
    rf"core/ReplaceComparisonOperator_(?!(?:{_KEPT_COMPARISON})$)",
    r"core/RemoveDecorator",
)

_CHECK_INERTIA = (
    "if not (lower * (1.0 - _PARALLEL_AXIS_TOLERANCE) <= I_A < math.inf and I_A > 0.0):"
)
_LEDGER_DEFAULT = "an EnergyLedger default: its one maker, LedgerTerms.close, passes every field"
_NUMBA_CACHE = "numba's on-disk cache of the compiled function, not its results"
_STATIC_NEGATIVE = (
    "any value that is not a row marks the static body: STATIC is only compared with itself "
    "(rows are >= 0)"
)
_STATIC_ZERO = (
    "row 0 is the rotor (after_step reads its ω there), never a pin's body b (hinges join the"
    " rotor a to a hammer b, the axis pin the rotor to the static body): 0 marks the static "
    "body as well"
)
_RESHAPE = "numpy (2.4) takes any negative size as the one to infer: the same (k, 2) shape"
_INFINITE_MOMENT = (
    "no metered body has an infinite moment: the meter keeps the dynamic bodies, whose "
    "moments (a hammer's I_C, a driven rotor's inertia) the spec checks finite; the kinematic"
    " rotor is not metered"
)
_DRIVE_TERM = (
    'terms["drive"] is never read: the drive\'s work comes from the moment balance '
    "(Drive.removed stays 0)"
)
_ZIP_BODIES = "both lists zipped are made from self._bodies: equal lengths"
_ZETA_T_CHECKED = (
    "ζ_t < 0 and ζ_t = 1 are refused where rows are made (contact_parameters, polygon_set, "
    "the spec); at ζ_t = 0 2ζ_t√(k_t m) is the shortcut's 0"
)
_DEAD_SLID = (
    "the else branch is dead: sliding needs |F_t| > f|F_n| >= 0, so F_t != 0 and k_t > 0 (k_t"
    " = 0 makes c_t = 0 and F_t = 0)"
)


def _cache_flags(
    module: str, decorator: str, column: int, lines: tuple[int, ...], first: int = 0
) -> dict[tuple[str, int, int, str], tuple[str, str]]:
    """EQUIVALENT entries for ``cache=True`` turned False in ``decorator`` at each of ``lines``
    (cosmic-ray numbers these mutants ReplaceTrueWithFalse#k in line order, from ``first``)."""
    return {
        (module, line, column, f"ReplaceTrueWithFalse#{first + k}"): (decorator, _NUMBA_CACHE)
        for k, line in enumerate(lines)
    }


_THIRD_TOTAL = (
    "a third total is never touched: meter_step adds to totals[0] and [1], the ledger reads those"
)
_NO_CONSTRAINTS = (
    "_NO_LOSSES has no constraint rows: constraint_losses reads energy[0] and writes it back "
    "unchanged, and reads none of its other arrays"
)
_IDLE_METER = (
    "IDLE_METER goes only to compiled steps without a meter. Its terms flag is False, so "
    "meter_step reads nothing of it past the losses; flagged True, its no pins and no bodies "
    "add zero to totals of its own that nothing reads"
)
_THIRD_DOUBLE = (
    "reads one more double of the pivot's struct (its bias, after jAcc); only j[0], j[1] are used"
)


def _same_reason(
    module: str, line: int, text: str, reason: str, mutants: tuple[tuple[int, str], ...]
) -> dict[tuple[str, int, int, str], tuple[str, str]]:
    """EQUIVALENT entries for the ``mutants`` (column, operator#occurrence) of one line."""
    return {(module, line, column, operator): (text, reason) for column, operator in mutants}


_CACHE_FLAGS_LAWS = _cache_flags(
    "laws",
    '@njit(cache=True, inline="always", fastmath=FASTMATH)',
    12,
    (44, 55, 90, 110, 145, 152, 162, 172, 185, 218),
)
_CACHE_FLAGS_ENERGY = _cache_flags("energy", "@numba.njit(cache=True)", 18, (196, 217, 240, 263), 2)
EQUIVALENT: dict[tuple[str, int, int, str], tuple[str, str]] = {
    ("impact", 55, 53, "ReplaceComparisonOperator_LtE_Lt#0"): (
        _CHECK_INERTIA,
        "differs only at I_A = M·r²·(1 − 1e-12) to the last bit, the edge of a round-off allowance",
    ),
    ("impact", 55, 79, "ReplaceComparisonOperator_Gt_GtE#1"): (
        _CHECK_INERTIA,
        "I_A = 0 passes only with r_c = 0 (hinged_impact), and hinged_effective_mass then "
        "rejects it: ValueError either way",
    ),
    ("impact", 55, 81, "NumberReplacer#15"): (
        _CHECK_INERTIA,
        "I_A > -1: a negative I_A already fails M·r² <= I_A; I_A = 0 as for the >= mutant",
    ),
    ("impact", 146, 52, "ReplaceComparisonOperator_Gt_GtE#2"): (
        "impulse = mu * (1.0 + e) * approach if approach > 0.0 else 0.0",
        "at approach = 0 both branches give a zero impulse",
    ),
    ("impact", 259, 23, "ReplaceComparisonOperator_Gt_GtE#5"): (
        "if abs(norm - 1.0) > _UNIT_NORMAL_TOLERANCE:",
        "differs only at | |n| − 1 | = 1e-9 exactly, the edge of a round-off allowance",
    ),
    ("contact", 67, 4, "ReplaceBinaryOperator_Mul_Div#3"): (
        "*,",
        "_check_in's keyword-only marker made positional-only: every call passes name … high "
        "by position and the flags by keyword, accepted either way",
    ),
    ("contact", 290, 25, "NumberReplacer#109"): (
        "return max(y[0], 0.0) ** 1.25 + alpha * y[1]",
        "the force-end event is terminal and F returns to 0 while u > 0 (α > 0): it never sees "
        "u < 0",
    ),
    ("contact", 296, 26, "NumberReplacer#119"): (
        "u, du = max(y[0], 0.0), y[1]",
        "u < 0 only at the step ending the contact, after the force peak; the first peak event "
        "is the one taken",
    ),
    ("contact", 308, 13, "NumberReplacer#137"): (
        "rtol=1e-12,",
        "scipy raises an rtol below 100 eps to 100 eps (with a warning): a tighter integration, "
        "results change below its 1e-9 accuracy",
    ),
    ("contact", 319, 48, "NumberReplacer#155"): (
        "peak_overlap_time=float(sol.t_events[1][0]),",
        "the overlap has one maximum per contact: one event, [0] is [-1]",
    ),
    ("contact", 314, 59, "NumberReplacer#145"): (
        "u_force, du_force = (float(x) for x in sol.y_events[2][0])",
        "the force has one maximum per contact (after it, a minimum at most): one event, [0] "
        "is [-1]",
    ),
    ("contact", 398, 78, "ReplaceTrueWithFalse#11"): (
        "compliance = sum((1.0 - nu_i**2) / E_i for E_i, nu_i in zip(E, nu, strict=True))",
        "the loop just above zips E and nu strictly and raises first on unequal lengths",
    ),
    ("contact", 316, 11, "NumberReplacer#146"): (
        "v0=1.0,",
        "the dimensionless response's v0 is never read: HertzTsuji.impact sets its own",
    ),
    ("contact", 264, 19, "NumberReplacer#72"): (
        "@lru_cache(maxsize=512)",
        "the cache's capacity, not its values",
    ),
    ("contact", 264, 19, "NumberReplacer#73"): (
        "@lru_cache(maxsize=512)",
        "the cache's capacity, not its values",
    ),
    ("contact", 278, 30, "NumberReplacer#86"): (
        "return ImpactResponse(1.0, 2.0 * half, u_max, half, u_max**1.5, half)",
        "the dimensionless response's v0 is never read: HertzTsuji.impact sets its own",
    ),
    ("contact", 278, 30, "NumberReplacer#87"): (
        "return ImpactResponse(1.0, 2.0 * half, u_max, half, u_max**1.5, half)",
        "the dimensionless response's v0 is never read: HertzTsuji.impact sets its own",
    ),
    ("contact", 321, 46, "NumberReplacer#159"): (
        "peak_force_time=float(sol.t_events[2][0]),",
        "the force has one maximum per contact: one event, [0] is [-1]",
    ),
    ("contact", 58, 38, "NumberReplacer#17"): (
        "_ZETA_BELOW_ONE = math.nextafter(1.0, 0.0)",
        "nextafter(1, -1) is nextafter(1, 0): the same double",
    ),
    ("contact", 302, 27, "NumberReplacer#128"): (
        "event.direction = -1.0",
        "scipy reads only the sign of an event's direction",
    ),
    ("contact", 395, 54, "ReplaceTrueWithFalse#8"): (
        "for i, (E_i, nu_i) in enumerate(zip(E, nu, strict=True)):",
        "the sum just below zips E and nu strictly: unequal lengths still raise",
    ),
    ("contact", 316, 11, "NumberReplacer#147"): (
        "v0=1.0,",
        "the dimensionless response's v0 is never read: HertzTsuji.impact sets its own",
    ),
    ("contact", 317, 39, "NumberReplacer#151"): (
        "duration=float(sol.t_events[0][0]),",
        "the end event is terminal: one event, [0] is [-1]",
    ),
    ("records", 143, 21, "NumberReplacer#6"): (
        "elastic: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 143, 21, "NumberReplacer#7"): (
        "elastic: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 145, 29, "NumberReplacer#8"): (
        "elastic_initial: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 145, 29, "NumberReplacer#9"): (
        "elastic_initial: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 147, 20, "NumberReplacer#10"): (
        "inflow: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 147, 20, "NumberReplacer#11"): (
        "inflow: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 149, 21, "NumberReplacer#12"): (
        "outflow: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 149, 21, "NumberReplacer#13"): (
        "outflow: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 151, 30, "NumberReplacer#14"): (
        "joint_correction: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("records", 151, 30, "NumberReplacer#15"): (
        "joint_correction: float = 0.0",
        _LEDGER_DEFAULT,
    ),
    ("energy", 76, 9, "ReplaceUnaryOperator_USub_Invert#0"): (
        "STATIC = -1",
        _STATIC_NEGATIVE,
    ),
    ("energy", 76, 10, "NumberReplacer#0"): (
        "STATIC = -1",
        _STATIC_NEGATIVE,
    ),
    ("energy", 76, 9, "ReplaceUnaryOperator_USub_Not#0"): (
        "STATIC = -1",
        _STATIC_ZERO,
    ),
    ("energy", 76, 10, "NumberReplacer#1"): (
        "STATIC = -1",
        _STATIC_ZERO,
    ),
    ("energy", 82, 11, "NumberReplacer#2"): (
        ('spin = 0.0 if body.moment == float("inf") else body.moment * body.angular_velocity**2'),
        _INFINITE_MOMENT,
    ),
    ("energy", 82, 11, "NumberReplacer#3"): (
        ('spin = 0.0 if body.moment == float("inf") else body.moment * body.angular_velocity**2'),
        _INFINITE_MOMENT,
    ),
    ("energy", 120, 18, "ReplaceUnaryOperator_USub_Invert#1"): (
        ").reshape(-1, 2)",
        _RESHAPE,
    ),
    ("energy", 120, 19, "NumberReplacer#8"): (
        ").reshape(-1, 2)",
        _RESHAPE,
    ),
    ("energy", 124, 18, "ReplaceUnaryOperator_USub_Invert#2"): (
        ").reshape(-1, 2)",
        _RESHAPE,
    ),
    ("energy", 124, 19, "NumberReplacer#12"): (
        ").reshape(-1, 2)",
        _RESHAPE,
    ),
    ("energy", 160, 56, "NumberReplacer#22"): (
        'terms = {"friction": 0.0, "drag": 0.0, "drive": 0.0, "contact": 0.0}',
        _DRIVE_TERM,
    ),
    ("energy", 160, 56, "NumberReplacer#23"): (
        'terms = {"friction": 0.0, "drag": 0.0, "drive": 0.0, "contact": 0.0}',
        _DRIVE_TERM,
    ),
    ("energy", 169, 81, "ReplaceTrueWithFalse#0"): (
        "* sum(abs(k - k0) for k, k0 in zip(kinetics, self._kinetics0, strict=True))",
        _ZIP_BODIES,
    ),
    ("energy", 174, 70, "ReplaceTrueWithFalse#1"): (
        "for b, r0 in zip(self._bodies, self._centres0, strict=True)",
        _ZIP_BODIES,
    ),
    **_CACHE_FLAGS_ENERGY,
    **_same_reason(
        "energy",
        127,
        "self._totals = np.zeros(2)",
        _THIRD_TOTAL,
        ((32, "NumberReplacer#16"),),
    ),
    **_same_reason(
        "energy",
        184,
        (
            "_NO_LOSSES = ((np.zeros(2), np.zeros(0,"
            " dtype=np.uint64), np.zeros((0, 2), dtype=np.int64)),)"
        ),
        _NO_CONSTRAINTS,
        (
            (24, "NumberReplacer#34"),
            (24, "NumberReplacer#35"),
            (37, "NumberReplacer#36"),
            (71, "NumberReplacer#40"),
            (71, "NumberReplacer#41"),
        ),
    ),
    **_same_reason(
        "energy",
        189,
        (
            "_NO_LOSSES, np.zeros((0, 2), dtype=np.int64),"
            " np.zeros((0, 2)), np.zeros(0, dtype=np.uint64),"
        ),
        _IDLE_METER,
        (
            (26, "NumberReplacer#42"),
            (29, "NumberReplacer#44"),
            (29, "NumberReplacer#45"),
            (60, "NumberReplacer#46"),
            (63, "NumberReplacer#48"),
            (63, "NumberReplacer#49"),
            (77, "NumberReplacer#50"),
        ),
    ),
    **_same_reason(
        "energy",
        190,
        (
            "np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0),"
            " 0.0, 0.0, False, False, np.zeros(2),"
        ),
        _IDLE_METER,
        (
            (13, "NumberReplacer#52"),
            (42, "NumberReplacer#54"),
            (55, "NumberReplacer#56"),
            (59, "NumberReplacer#58"),
            (59, "NumberReplacer#59"),
            (64, "NumberReplacer#60"),
            (64, "NumberReplacer#61"),
            (69, "ReplaceFalseWithTrue#0"),
            (76, "ReplaceFalseWithTrue#1"),
            (92, "NumberReplacer#62"),
            (92, "NumberReplacer#63"),
        ),
    ),
    **_same_reason(
        "energy",
        297,
        "j = doubles_at(impulses[k], 2)",
        _THIRD_DOUBLE,
        ((36, "NumberReplacer#170"),),
    ),
    **_CACHE_FLAGS_LAWS,
    ("laws", 52, 42, "ReplaceComparisonOperator_Gt_GtE#0"): (
        "return delta + 0.5 * dt * abs(ddelta) > 0.0",
        (
            "differs only at δ = −½dt|δ̇| exactly, the edge of the kick interval, where the "
            "law's normal force is 0"
        ),
    ),
    ("laws", 105, 10, "ReplaceComparisonOperator_Lt_LtE#0"): (
        "if fn < 0.0 and clamp != 0.0:",
        ("sets F_n = 0 where it is ±0 already: the cap f|F_n| and the force sums are the same"),
    ),
    ("laws", 130, 57, "NumberReplacer#32"): (
        "ct = 2.0 * dampt * math.sqrt(kt * m_eff) if dampt != 0.0 else 0.0",
        _ZETA_T_CHECKED,
    ),
    ("laws", 130, 57, "NumberReplacer#33"): (
        "ct = 2.0 * dampt * math.sqrt(kt * m_eff) if dampt != 0.0 else 0.0",
        _ZETA_T_CHECKED,
    ),
    ("laws", 134, 15, "ReplaceComparisonOperator_Gt_GtE#1"): (
        "if abs(ft) > cap:",
        (
            "at |F_t| = cap both branches give the same force and stretch, and losses equal "
            "algebraically"
        ),
    ),
    ("laws", 136, 42, "ReplaceComparisonOperator_Gt_GtE#2"): (
        "slid = -(ft + ct * vt) / kt if kt > 0.0 else 0.0",
        _DEAD_SLID,
    ),
    ("laws", 136, 44, "NumberReplacer#37"): (
        "slid = -(ft + ct * vt) / kt if kt > 0.0 else 0.0",
        _DEAD_SLID,
    ),
    ("laws", 136, 53, "NumberReplacer#38"): (
        "slid = -(ft + ct * vt) / kt if kt > 0.0 else 0.0",
        _DEAD_SLID,
    ),
    ("laws", 136, 53, "NumberReplacer#39"): (
        "slid = -(ft + ct * vt) / kt if kt > 0.0 else 0.0",
        _DEAD_SLID,
    ),
    ("laws", 229, 14, "NumberReplacer#59"): (
        "if mur == 0.0 or w_rel == 0.0:",
        ("μ_r >= 0 is checked where rows are made; at μ_r = 0 the formula's torque is ±0 anyway"),
    ),
    ("laws", 229, 18, "ReplaceOrWithAnd#0"): (
        "if mur == 0.0 or w_rel == 0.0:",
        (
            "min(μ_r R|F_n|, |w| I/dt) is 0 when μ_r = 0 or w = 0: the early return only "
            "saves work (a −0.0 torque adds nothing)"
        ),
    ),
    ("laws", 238, 4, "ReplaceBinaryOperator_Mul_Div#47"): (
        "*,",
        (
            "contact_parameters' keyword-only marker made positional-only: every call passes "
            "the law and e by position and the rest by keyword"
        ),
    ),
    ("timestep", 78, 42, "NumberReplacer#13"): (
        "m = float(masses(case, np.array([r]))[0]) if case.granules.size else case.granule_mass",
        "a one-element array: [-1] is [0]",
    ),
}
"""Surviving mutants that cannot change any result, keyed by (module, line, column, operator):
(the source line's text, stripped, to catch a stale entry; why it is equivalent)."""


def _test_command(module: Module) -> list[str]:
    """The command a mutant of ``module`` is tested with."""
    pytest = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-x"]
    return [*pytest, "--hypothesis-seed=0", *module.tests]


def _config(name: str, module: Module) -> Path:
    command = " ".join(_test_command(module))
    excluded = ", ".join(json.dumps(e) for e in EXCLUDED_OPERATORS)
    path = WORK / f"{name}.toml"
    path.write_text(
        "[cosmic-ray]\n"
        f'module-path = "{module.source}"\n'
        f"timeout = {module.timeout}\n"
        "excluded-modules = []\n"
        f"test-command = {json.dumps(command)}\n"
        "[cosmic-ray.distributor]\n"
        'name = "local"\n'
        "[cosmic-ray.filters.operators-filter]\n"
        f"exclude-operators = [{excluded}]\n"
    )
    return path


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(ROOT)])
    env["NUMBA_DISABLE_JIT"] = "1"
    return env


def init(name: str) -> None:
    """Create a fresh session for module ``name``: its mutants, the excluded operators' marked
    skipped, none executed."""
    WORK.mkdir(parents=True, exist_ok=True)
    config, session = _config(name, MODULES[name]), WORK / f"{name}.sqlite"
    session.unlink(missing_ok=True)
    bindir = Path(sys.executable).parent
    for cmd in (
        [bindir / "cosmic-ray", "init", config, session],
        [bindir / "cr-filter-operators", session, config],
    ):
        subprocess.run([str(c) for c in cmd], cwd=ROOT, env=_env(), check=True)


def run(name: str) -> None:
    """Create a fresh session for module ``name`` and execute every mutant of it."""
    init(name)
    resume(name)


def resume(name: str) -> None:
    """Execute the pending mutants of the kept session of module ``name``, once its tests are
    seen to pass unmutated (else every mutant would count as killed)."""
    unmutated = subprocess.run(
        _test_command(MODULES[name]), cwd=ROOT, env=_env(), capture_output=True, text=True
    )
    if unmutated.returncode != 0:
        sys.exit(
            f"{name}: the tests fail unmutated (numba's JIT off), so no mutant can be judged:\n"
            + unmutated.stdout[-2000:]
        )
    bindir = Path(sys.executable).parent
    config, session = _config(name, MODULES[name]), WORK / f"{name}.sqlite"
    subprocess.run(
        [str(bindir / "cosmic-ray"), "exec", str(config), str(session)],
        cwd=ROOT,
        env=_env(),
        check=True,
    )


def rerun(name: str, outcome: str) -> None:
    """Run again the mutants of ``name`` that survived (``outcome`` "survived": after tests were
    added, a mutant the unchanged old tests killed stays killed) or timed out ("timeout": with
    a longer ``timeout`` in ``MODULES``)."""
    from cosmic_ray.work_db import WorkDB, WorkResultStorage, use_db
    from cosmic_ray.work_item import TestOutcome

    with use_db(str(WORK / f"{name}.sqlite"), WorkDB.Mode.open) as db:
        again = [
            item.job_id
            for item, result in db.completed_work_items
            if (outcome == "survived" and result.test_outcome == TestOutcome.SURVIVED)
            or (outcome == "timeout" and result.output == "timeout")
        ]
        with db._session_maker.begin() as s:
            s.query(WorkResultStorage).filter(WorkResultStorage.job_id.in_(again)).delete()
    resume(name)


def _tree(tmp: Path, archive: bytes, source: str, mutation=None) -> dict[str, str]:
    """Extract ``archive`` (``src/`` as committed, ``git archive HEAD src``) into ``tmp``,
    apply ``mutation`` (a cosmic-ray mutation spec, None: none) to its ``source``, and return
    the environment whose imports come from that copy."""
    import cosmic_ray.plugins
    from cosmic_ray.mutating import apply_mutation

    subprocess.run(["tar", "-x", "-C", str(tmp)], input=archive, check=True)
    if mutation is not None:
        operator = cosmic_ray.plugins.get_operator(mutation.operator_name)()
        apply_mutation(tmp / source, operator, mutation.occurrence)
    return _env() | {"PYTHONPATH": os.pathsep.join([str(tmp / "src"), str(ROOT)])}


def _committed_src() -> bytes:
    """``src/`` as committed, a tar archive (a session may be mutating the work tree's)."""
    return subprocess.run(
        ["git", "archive", "HEAD", "src"], cwd=ROOT, capture_output=True, check=True
    ).stdout


def check(name: str, where: str, tests: list[str]) -> bool:
    """Whether ``tests`` (pytest node ids) pass unmutated and fail with the mutant ``where`` of
    module ``name`` (``LINE:COLUMN:OPERATOR#OCCURRENCE`` as the report prints it) applied to a
    temporary copy of ``src/`` (the kept session and the work tree are left alone)."""
    from cosmic_ray.work_db import WorkDB, use_db

    line, column, operator = where.split(":", 2)
    operator, occurrence = operator.split("#")
    with use_db(str(WORK / f"{name}.sqlite"), WorkDB.Mode.open) as db:
        (mutation,) = [
            m
            for item in db.work_items
            for m in item.mutations
            if m.start_pos == (int(line), int(column))
            and m.operator_name == f"core/{operator}"
            and m.occurrence == int(occurrence)
        ]
    command = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", *tests]
    archive, outcomes = _committed_src(), []
    for applied in (None, mutation):
        with tempfile.TemporaryDirectory() as tmp:
            env = _tree(Path(tmp), archive, MODULES[name].source, applied)
            outcomes.append(subprocess.run(command, cwd=ROOT, env=env, capture_output=True))
    passed, failed = (o.returncode for o in outcomes)
    print(
        f"{name}:{where}: unmutated {'pass' if passed == 0 else 'FAIL'}, "
        f"mutant {'killed' if failed else 'NOT KILLED'}"
    )
    return passed == 0 and failed != 0


def sample(name: str, seed: int, slow: float, wanted: int) -> None:
    """Run module ``name``'s mutants in an order shuffled with ``seed``, each as ``check`` runs
    one (a temporary copy of ``src/`` as committed) with the module's test command and
    ``timeout``, timing each, until ``wanted`` of them have run longer than ``slow`` seconds;
    print one JSON line per mutant. For timeouts counted at a shorter limit whose session was
    not kept (docs/dev/testing.md: contact's). Makes a fresh session if none is kept."""
    import random
    import time

    from cosmic_ray.work_db import WorkDB, use_db

    if not (WORK / f"{name}.sqlite").exists():
        init(name)
    with use_db(str(WORK / f"{name}.sqlite"), WorkDB.Mode.open) as db:
        skipped = {item.job_id for item, _ in db.completed_work_items}
        specs = [i.mutations[0] for i in db.work_items if i.job_id not in skipped]
    specs.sort(key=lambda m: (m.start_pos, m.operator_name, m.occurrence))
    random.Random(seed).shuffle(specs)
    module = MODULES[name]
    command = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-x"]
    command += ["--hypothesis-seed=0", *module.tests]
    archive, count = _committed_src(), 0
    for mutation in specs:
        if count >= wanted:
            break
        with tempfile.TemporaryDirectory() as tmp:
            env = _tree(Path(tmp), archive, module.source, mutation)
            start = time.monotonic()
            tests = subprocess.Popen(
                command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, start_new_session=True
            )
            try:
                outcome = "survived" if tests.wait(module.timeout) == 0 else "killed"
            except subprocess.TimeoutExpired:
                os.killpg(tests.pid, 9)
                tests.wait()
                outcome = "timeout"
            elapsed = time.monotonic() - start
        count += elapsed > slow
        line, column = mutation.start_pos
        where = f"{line}:{column}:{mutation.operator_name.removeprefix('core/')}"
        record = {"mutant": f"{where}#{mutation.occurrence}", "seconds": round(elapsed, 1)}
        print(json.dumps(record | {"outcome": outcome}), flush=True)


@dataclass(frozen=True)
class Mutant:
    """One executed mutant: where, which operator, and what became of it."""

    module: str
    line: int
    column: int
    operator: str
    outcome: str  # killed, timeout, survived, equivalent, incompetent
    text: str

    @property
    def key(self) -> tuple[str, int, int, str]:
        return (self.module, self.line, self.column, self.operator)


def mutants(name: str) -> list[Mutant]:
    """The executed mutants of a module's kept session (filtered ones left out)."""
    from cosmic_ray.work_db import WorkDB, use_db
    from cosmic_ray.work_item import TestOutcome, WorkerOutcome

    source = MODULES[name].source  # as committed: a session may be mutating the tree's
    lines = subprocess.run(
        ["git", "show", f"HEAD:{source}"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.splitlines()
    out = []
    with use_db(str(WORK / f"{name}.sqlite"), WorkDB.Mode.open) as db:
        for item, result in db.completed_work_items:
            if result.worker_outcome == WorkerOutcome.SKIPPED:
                continue
            (mutation,) = item.mutations
            line, col = mutation.start_pos
            operator = mutation.operator_name.removeprefix("core/")
            if result.worker_outcome != WorkerOutcome.NORMAL:
                outcome = "incompetent"
            elif result.test_outcome == TestOutcome.SURVIVED:
                outcome = "survived"
            elif result.output == "timeout":
                outcome = "timeout"
            else:
                outcome = "killed"
            text = lines[line - 1].strip()
            m = Mutant(name, line, col, f"{operator}#{mutation.occurrence}", outcome, text)
            if outcome == "survived" and m.key in EQUIVALENT:
                outcome = "equivalent"
                if EQUIVALENT[m.key][0] != text:
                    print(f"stale EQUIVALENT entry {m.key}: {text!r}", file=sys.stderr)
            out.append(Mutant(name, line, col, m.operator, outcome, text))
    return out


def report(names: list[str]) -> None:
    """Counts and score per module, and every unexplained survivor."""
    header = "| module | mutants | killed | timeouts | survived | equivalent | score |"
    print(header + "\n|" + "---|" * 7)
    for name in names:
        if not (WORK / f"{name}.sqlite").exists():
            continue
        ms = mutants(name)
        count = {k: sum(m.outcome == k for m in ms) for k in ("killed", "timeout", "survived")}
        equivalent = sum(m.outcome == "equivalent" for m in ms)
        incompetent = sum(m.outcome == "incompetent" for m in ms)
        caught = count["killed"] + count["timeout"]
        score = caught / max(len(ms) - equivalent - incompetent, 1)
        print(
            f"| {MODULES[name].source.removeprefix('src/')} | {len(ms)} | {count['killed']} "
            f"| {count['timeout']} | {count['survived']} | {equivalent} | {100 * score:.1f} % |"
        )
        if incompetent:
            print(f"  ({incompetent} incompetent mutants of {name} not counted)")
    for name in names:
        if (WORK / f"{name}.sqlite").exists():
            for m in mutants(name):
                if m.outcome == "survived":
                    print(f"SURVIVED {name}:{m.line}:{m.column} {m.operator}  {m.text}")


def show(name: str) -> None:
    """Print the diff of every survivor of a module (cosmic-ray's own report)."""
    bindir = Path(sys.executable).parent
    out = subprocess.run(
        [str(bindir / "cr-report"), "--show-output", str(WORK / f"{name}.sqlite")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    for block in re.split(r"\n(?=\[job-id\])", out):
        if "test outcome: TestOutcome.SURVIVED" in block:
            print(block.split("test outcome")[0] + block.split("diff:")[-1][:2000])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("modules", nargs="*", help=f"some of {', '.join(MODULES)} (all)")
    parser.add_argument("--report", action="store_true", help="only report the kept sessions")
    parser.add_argument("--show", metavar="MODULE", help="diffs of a module's survivors")
    parser.add_argument(
        "--check",
        nargs="+",
        metavar="ARG",
        help="MODULE LINE:COLUMN:OPERATOR#OCCURRENCE TEST...: tests pass, and fail on the mutant",
    )
    parser.add_argument(
        "--sample",
        nargs=4,
        metavar=("MODULE", "SEED", "SLOW", "WANTED"),
        help="time shuffled mutants at the module's timeout until WANTED ran over SLOW s",
    )
    parser.add_argument(
        "--resume", action="store_true", help="run only the kept sessions' pending mutants"
    )
    parser.add_argument(
        "--rerun-survivors", action="store_true", help="run only the kept sessions' survivors"
    )
    parser.add_argument(
        "--rerun-timeouts", action="store_true", help="run only the kept sessions' timeouts"
    )
    args = parser.parse_args()
    if args.show:
        show(args.show)
        return
    if args.check:
        sys.exit(0 if check(args.check[0], args.check[1], args.check[2:]) else 1)
    if args.sample:
        name, seed, slow, wanted = args.sample
        sample(name, int(seed), float(slow), int(wanted))
        return
    names = args.modules or list(MODULES)
    unknown = set(names) - set(MODULES)
    if unknown:
        parser.error(f"unknown modules {sorted(unknown)}")
    if not args.report:
        for name in names:
            if args.rerun_survivors or args.rerun_timeouts:
                rerun(name, "survived" if args.rerun_survivors else "timeout")
            elif args.resume:
                resume(name)
            else:
                run(name)
    report(names)


if __name__ == "__main__":
    main()
