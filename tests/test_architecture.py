"""The import rules of docs/architecture.md, read from the sources (every import, those inside
functions included), and the rules that keep the parts apart: no ``isinstance`` on a simulation or
contact-model class, no private member of another package read."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "perga"

ALLOWED: dict[str, set[str]] = {
    "analytic": {"analytic"},
    "geometry": {"geometry"},
    "case": {"case", "analytic", "geometry", "contact.laws"},
    "model": {"model", "case", "analytic", "geometry", "contact.laws"},
    "engine": {"engine", "model", "analytic", "geometry", "contact", "contact.protocol"},
    "contact": {"contact", "engine", "model", "analytic", "geometry", "cores"},
    "contact.laws": {"contact.laws", "analytic"},
    "output": {"output", "model", "geometry", "analytic"},
    "stats": {"stats", "case", "analytic", "model", "output"},
    "studies": {"studies", "stats", "case", "analytic", "model", "geometry", "engine", "output",
                "runner", "stopping", "cores", "__init__"},
    "runner": {"runner", "case", "model", "engine", "geometry", "output", "stopping",
               "checkpoints"},
    "checkpoints": {"checkpoints", "engine", "output", "__init__"},
    "cli": {"cli", "__init__", "case", "analytic", "model", "studies", "output", "runner", "stats",
            "stopping", "checkpoints", "progress"},
    "stopping": set(),
    "progress": set(),
    "cores": set(),
    "__init__": set(),
}  # fmt: skip
"""Part -> the parts it may import. ``engine`` may import the contact-model registry
(``perga.contact``) and its protocol, never a contact model; ``contact`` may import the engine's
machine; the contact laws (``contact.laws``) only the closed forms, so that ``case`` may ask them;
``case``, ``stats`` and ``output`` never import the engine or a contact model; nothing imports
the CLI."""


def part_of(module: str) -> str:
    """The part a module belongs to: perga.engine.machine -> engine, perga.cli -> cli,
    perga.contact.laws.hertz -> contact.laws (a part of its own inside contact)."""
    parts = module.split(".")
    if parts[1:3] == ["contact", "laws"]:
        return "contact.laws"
    return parts[1] if len(parts) > 1 else "__init__"


def module_named(name: str) -> str:
    """The module an imported name lives in: the longest prefix that is a file or package under
    src/perga (``perga.contact.contact_model`` is the registry's function, in perga.contact)."""
    parts = name.split(".")
    for k in range(len(parts), 1, -1):
        path = SRC.joinpath(*parts[1:k])
        if path.with_suffix(".py").is_file() or (path / "__init__.py").is_file():
            return ".".join(parts[:k])
    return "perga"


def imported_part(name: str) -> str:
    """The part an import reaches: perga.engine.units -> engine; inside perga.contact the
    registry (contact), its protocol (contact.protocol) and each model (contact.rigid,
    contact.soft) are told apart."""
    parts = module_named(name).split(".")[1:]
    if not parts:
        return "__init__"
    if parts[0] == "contact" and len(parts) > 1:
        return "contact." + parts[1]
    return parts[0]


def imports(path: Path, module: str) -> list[tuple[int, str]]:
    """(line, absolute name) of every perga import in the file, relative ones resolved."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names if a.name.startswith("perga")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                name = f"{base}.{node.module}" if node.module else base
            else:
                name = node.module or ""
            if name.startswith("perga"):
                out += [(node.lineno, f"{name}.{a.name}") for a in node.names]
    return out


def modules() -> list[tuple[Path, str]]:
    """Every source file and its module name."""
    out = []
    for path in sorted(SRC.rglob("*.py")):
        parts = ("perga", *path.relative_to(SRC).with_suffix("").parts)
        out.append((path, ".".join(parts).removesuffix(".__init__")))
    return out


def violations(found: list[tuple[str, int, str]]) -> list[str]:
    """The imports among (module, line, imported name) that break :data:`ALLOWED`. A part may
    always import itself; the engine only the contact registry and protocol by name, the
    other parts any of perga.contact where they may import "contact"."""
    bad = []
    for module, line, name in found:
        source, target = part_of(module), imported_part(name)
        allowed = ALLOWED[source]
        own = target.split(".")[0] == source
        by_prefix = source != "engine" and target.split(".")[0] in allowed
        if own or target in allowed or by_prefix:
            continue
        bad.append(f"{module}:{line} imports {name} ({source} may not import {target})")
    return bad


def test_import_rules_hold() -> None:
    found = [(m, line, name) for path, m in modules() for line, name in imports(path, m)]
    assert len(found) > 200  # the scan sees the package
    assert violations(found) == []


@pytest.mark.parametrize(
    ("module", "name"),
    [
        ("perga.analytic.paper", "perga.engine.simulation"),
        ("perga.engine.simulation", "perga.contact.soft.model"),
        ("perga.engine.simulation", "perga.contact.rigid.bodies"),
        ("perga.output.vtk", "perga.engine.machine"),
        ("perga.output.vtk", "perga.contact.soft.polygon_set"),
        ("perga.case.checks", "perga.model.spec"),
        ("perga.stats.energy", "perga.engine.energy"),
        ("perga.runner", "perga.contact.rigid.model"),
        ("perga.studies.compare", "perga.cli"),
        ("perga.model.frame", "perga.output.tables"),
        ("perga.contact.laws.hertz", "perga.contact.soft.laws"),
        ("perga.contact.laws.base", "perga.case.schema"),
        ("perga.case.timestep", "perga.contact.soft.laws"),
    ],
)
def test_the_rules_catch_a_forbidden_import(module: str, name: str) -> None:
    """Each rule is seen to fail: a forbidden import is reported."""
    assert violations([(module, 1, name)]), (module, name)


@pytest.mark.parametrize(
    ("module", "name"),
    [
        ("perga.engine.simulation", "perga.contact.contact_model"),
        ("perga.engine.simulation", "perga.contact.protocol.ContactModel"),
        ("perga.contact.soft.model", "perga.engine.machine.Machine"),
        ("perga.runner", "perga.engine.simulation"),
        ("perga.output.vtk", "perga.model.frame"),
        ("perga.case.timestep", "perga.contact.laws.contact_law"),
        ("perga.contact.laws.hertz", "perga.analytic.contact.HertzTsuji"),
        ("perga.contact.soft.laws", "perga.contact.laws.row.P_KN"),
    ],
)
def test_the_rules_allow_what_the_architecture_allows(module: str, name: str) -> None:
    assert violations([(module, 1, name)]) == []


def _calls(tree: ast.AST):
    return [n for n in ast.walk(tree) if isinstance(n, ast.Call)]


def test_no_isinstance_on_a_simulation_or_contact_model() -> None:
    """The choice of contact model is the registry's (perga.contact.MODELS), not an ``if``."""
    bad = []
    for path, module in modules():
        for call in _calls(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(call.func, ast.Name) and call.func.id == "isinstance":
                names = ast.unparse(call.args[1]) if len(call.args) > 1 else ""
                if any(k in names for k in ("Simulation", "Contacts", "SoftGranules", "Machine")):
                    bad.append(f"{module}:{call.lineno}: isinstance(..., {names})")
    assert bad == []


LAW_NAMES = frozenset({"linear", "hertz"})
"""The contact laws' names: only their registry and modules (perga.contact.laws) compare a
name with them or key a dict by them; everything else asks the law."""

NOT_YET_ASKING_THE_LAW = {
    ("perga.output.recorders", "model != 'hertz'"),
    ("perga.studies.accuracy_report", "{'rigid': 'o-', 'linear': 's--', 'hertz': '^:'}"),
    ("perga.studies.accuracy_scenes", "cm.kind == 'linear'"),
    ("perga.studies.accuracy_scenes", "setting.model == 'linear'"),
}
"""The places that still name a law, in parts being reworked apart from the laws: whether
impacts.csv has a peak pressure (Hertz's), and the accuracy study's families. Each entry must
still be found (remove it when its code asks the law)."""


def _names_a_law(node: ast.expr) -> bool:
    """Whether ``node`` is a law's name, or a tuple, list or set holding one."""
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_names_a_law(n) for n in node.elts)
    return isinstance(node, ast.Constant) and node.value in LAW_NAMES


def law_dispatch(tree: ast.AST) -> list[str]:
    """The comparisons with a law's name (``kind == "hertz"``, ``model in ("linear", …)``) and
    the dicts keyed by one, as source."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
        elif isinstance(node, ast.Dict):
            operands = [k for k in node.keys if k is not None]
        else:
            continue
        if any(_names_a_law(n) for n in operands):
            found.append(ast.unparse(node))
    return found


def test_only_the_laws_name_a_law() -> None:
    """No ``if kind == "hertz"`` outside perga.contact.laws: the callers ask the law."""
    found = [
        (module, source)
        for path, module in modules()
        if not module.startswith("perga.contact.laws")
        for source in law_dispatch(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert sorted(found) == sorted(NOT_YET_ASKING_THE_LAW)


@pytest.mark.parametrize(
    "code",
    [
        'if kind == "hertz":\n    pass',
        'damping = tsuji_alpha if cm.kind != "linear" else damping_ratio',
        'if model not in ("linear", "hertz"):\n    raise ValueError(model)',
        'FLAGS = {"linear": 0, "hertz": 1}',
    ],
)
def test_the_law_check_catches_a_planted_dispatch(code: str) -> None:
    assert len(law_dispatch(ast.parse(code))) == 1


def test_the_law_check_lets_the_law_be_asked() -> None:
    code = 'law = contact_law("hertz")\nif scale == "log" and law.from_materials:\n    pass'
    assert law_dispatch(ast.parse(code)) == []


RAW_C_POINTERS = {
    "perga.engine.chipmunk_state": {
        "_body", "_constraint", "_space", "_handlers", "_add_later", "_remove_later",
        "_post_step_callbacks", "_bodies_to_check",
    },
    "perga.engine.batch": {"_space", "_float_arr", "_int_arr"},
}  # fmt: skip
"""The two exceptions, pymunk's C pointers, which pymunk offers no public way to reach: the module
that reads what pymunk's pickle misses through the bodies' and joints' pointers (every read
checked against pymunk's getters) and steps the space from compiled code (``raw_space_step``:
the space's pointer, and the work of pymunk's ``Space.step`` besides ``cpSpaceStep``, which
must be none), and the batch reader, which calls pymunk.batch's C iterators with the space's
pointer and reads the buffer's C arrays in place (2.6 µs less a fetch; its layout checked
against the bodies' getters when it is built)."""


def test_no_private_member_of_another_package_is_read() -> None:
    """``x._name`` only on ``self``/``cls``, or on an object of the module's own package."""
    bad = []
    for path, module in modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
                and not (isinstance(node.value, ast.Name) and node.value.id in {"self", "cls"})
                and node.attr not in RAW_C_POINTERS.get(module, set())
            ):
                bad.append(f"{module}:{node.lineno}: {ast.unparse(node)}")
    assert bad == []


def test_a_run_does_not_load_the_mesh_libraries() -> None:
    """trimesh and scipy.stats are imported where a mesh is read or cut, or a size
    distribution drawn, not by the modules every run loads: together they cost 0.35-0.6 s of
    each run's start (docs/performance.md)."""
    code = (
        "import sys, perga.runner, perga.case, perga.output.vtk, perga.engine, perga.geometry;"
        "print(sorted(m for m in ('trimesh', 'scipy.stats') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"
