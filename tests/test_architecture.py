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
    "machine": {"machine", "model", "analytic", "geometry"},
    "contact": {"contact", "machine", "model", "analytic", "geometry", "cores"},
    "contact.laws": {"contact.laws", "analytic"},
    "engine": {"engine", "machine", "model", "analytic", "geometry", "contact", "contact.protocol"},
    "output": {"output", "model", "geometry", "analytic", "contact.laws"},
    "stats": {"stats", "case", "analytic", "model", "output"},
    "studies": {"studies", "stats", "case", "analytic", "model", "geometry", "engine", "output",
                "contact.laws",
                "run", "stopping", "cores", "__init__"},
    "run": {"run", "case", "model", "engine", "geometry", "output", "stopping", "__init__"},
    "cli": {"cli", "__init__", "case", "analytic", "model", "studies", "output", "run", "stats",
            "stopping", "progress"},
    "stopping": set(),
    "progress": set(),
    "cores": set(),
    "__init__": set(),
}  # fmt: skip
"""Part -> the parts it may import. The machine (rotor, hammers, joints, effects, the meter) is
below the contact models: it never imports a contact model or the simulation; a contact model
imports the machine, never the simulation (``engine``) and never another contact model
(:data:`CONTACT_MODELS`); the contact laws (``contact.laws``) import only the closed forms, so
that ``case`` and ``model`` may ask them; the ``engine`` (the simulation) imports the machine
and the contact registry (``perga.contact``) and its protocol, never a contact model; ``case``,
``stats`` and ``output`` never import the machine, the engine or a contact model; nothing
imports the CLI."""

CONTACT_MODELS = {"contact.rigid", "contact.soft"}
"""The contact models (:data:`perga.contact.MODELS`' implementations): none imports another."""


def part_of(module: str) -> str:
    """The part a module belongs to: perga.machine.machine -> machine, perga.cli -> cli,
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
    """The part an import reaches: perga.machine.units -> engine; inside perga.contact the
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
    """The imports among (module, line, imported name) that break :data:`ALLOWED` or
    :data:`CONTACT_MODELS`. A part may always import itself but a contact model another; the
    engine only the contact registry and protocol by name, the other parts any of
    perga.contact where they may import "contact"."""
    bad = []
    for module, line, name in found:
        source, target = part_of(module), imported_part(name)
        allowed = ALLOWED[source]
        model = imported_part(module)
        if model in CONTACT_MODELS and target in CONTACT_MODELS - {model}:
            bad.append(f"{module}:{line} imports {name} (a contact model imports another)")
            continue
        own = target.split(".")[0] == source
        by_prefix = source != "engine" and target.split(".")[0] in allowed
        if own or target in allowed or by_prefix:
            continue
        bad.append(f"{module}:{line} imports {name} ({source} may not import {target})")
    return bad


def cycles(found: list[tuple[str, int, str]]) -> list[list[str]]:
    """The import circles between parts (a contact model, the contact registry and its
    protocol each a part of its own), from (module, line, imported name): each circle once, as
    the parts in order, the first again at the end."""
    graph: dict[str, set[str]] = {}
    for module, _, name in found:
        source, target = imported_part(module), imported_part(name)
        if source != target:
            graph.setdefault(source, set()).add(target)
    out, seen = [], set()

    def walk(node: str, path: list[str]) -> None:
        for nxt in sorted(graph.get(node, ())):
            if nxt in path:
                circle = path[path.index(nxt) :]
                key = frozenset(circle)
                if key not in seen:
                    seen.add(key)
                    out.append([*circle, nxt])
            elif len(path) < len(graph) + 1:
                walk(nxt, [*path, nxt])

    for start in sorted(graph):
        walk(start, [start])
    return out


def every_import() -> list[tuple[str, int, str]]:
    """(module, line, imported name) of every perga import in the package."""
    return [(m, line, name) for path, m in modules() for line, name in imports(path, m)]


def test_import_rules_hold() -> None:
    found = every_import()
    assert len(found) > 200  # the scan sees the package
    assert violations(found) == []


def test_no_import_circle_between_parts() -> None:
    assert cycles(every_import()) == []


def test_a_circle_is_seen() -> None:
    """The circle check fails where there is one: the engine's imports of the machine, and a
    machine module importing the simulation back (through a third part, too)."""
    found = [
        ("perga.engine.simulation", 1, "perga.machine.machine.Machine"),
        ("perga.machine.energy", 1, "perga.engine.simulation.Simulation"),
        ("perga.model.frame", 1, "perga.case.schema.Case"),
    ]
    assert cycles(found) == [["engine", "machine", "engine"]]
    found += [("perga.case.load", 1, "perga.output.tables.read_columns"),
              ("perga.output.tables", 1, "perga.model.frame.Frame")]  # fmt: skip
    assert ["case", "output", "model", "case"] in cycles(found)


@pytest.mark.parametrize(
    ("module", "name"),
    [
        ("perga.analytic.paper", "perga.engine.simulation"),
        ("perga.engine.simulation", "perga.contact.soft.model"),
        ("perga.engine.simulation", "perga.contact.rigid.bodies"),
        ("perga.output.vtk", "perga.machine.machine"),
        ("perga.machine.effects", "perga.contact.protocol.GranuleState"),
        ("perga.machine.machine", "perga.engine.simulation.Simulation"),
        ("perga.contact.rigid.outline", "perga.contact.soft.polygon_set"),
        ("perga.contact.soft.model", "perga.contact.rigid.bodies"),
        ("perga.contact.soft.model", "perga.engine.simulation.Simulation"),
        ("perga.output.vtk", "perga.contact.soft.polygon_set"),
        ("perga.case.load", "perga.model.system"),
        ("perga.stats.energy", "perga.machine.energy"),
        ("perga.run", "perga.contact.rigid.model"),
        ("perga.studies.compare", "perga.cli"),
        ("perga.model.frame", "perga.output.tables"),
        ("perga.contact.laws.hertz", "perga.contact.soft.laws"),
        ("perga.contact.laws.base", "perga.case.schema"),
        ("perga.model.plan", "perga.contact.soft.laws"),
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
        ("perga.contact.soft.model", "perga.machine.machine.Machine"),
        ("perga.contact.soft.model", "perga.contact.protocol.GranuleState"),
        ("perga.engine.simulation", "perga.machine.compiled.compiled_machine"),
        ("perga.run", "perga.engine.simulation"),
        ("perga.output.vtk", "perga.model.frame"),
        ("perga.model.plan", "perga.contact.laws.contact_law"),
        ("perga.contact.laws.hertz", "perga.analytic.contact.HertzTsuji"),
        ("perga.contact.soft.laws", "perga.contact.laws.row.P_KN"),
    ],
)
def test_the_rules_allow_what_the_architecture_allows(module: str, name: str) -> None:
    assert violations([(module, 1, name)]) == []


def report_violations(found: list[tuple[str, int, str]]) -> list[str]:
    """The imports among (module, line, imported name) of a report module
    (``perga.studies.*_report``) by a study module (any other module of ``perga.studies``): a
    study returns its results and the caller hands them to the report (a report may import
    its study's types)."""
    bad = []
    for module, line, name in found:
        target = module_named(name)
        study = module.startswith("perga.studies.") and not module.endswith("_report")
        if study and target.startswith("perga.studies.") and target.endswith("_report"):
            bad.append(f"{module}:{line} imports {name} (a study never imports a report)")
    return bad


def test_no_study_module_imports_a_report() -> None:
    found = [(m, line, name) for path, m in modules() for line, name in imports(path, m)]
    assert any(module_named(n).endswith("_report") for _, _, n in found)  # reports are seen
    assert report_violations(found) == []


@pytest.mark.parametrize(
    ("module", "name"),
    [
        ("perga.studies.calibrate", "perga.studies.calibrate_report.write_plots"),
        ("perga.studies.window", "perga.studies.window_report.write_maps"),
        ("perga.studies.compare", "perga.studies.compare_report.write_report"),
        ("perga.studies.sweep", "perga.studies.sweep_report.write_plots"),
    ],
)
def test_the_report_rule_catches_a_study_importing_its_report(module: str, name: str) -> None:
    assert report_violations([(module, 1, name)]), (module, name)


def test_the_report_rule_sees_an_import_inside_a_function(tmp_path: Path) -> None:
    """The form the rule replaced: calibrate imported its report lazily, in a function."""
    source = tmp_path / "calibrate.py"
    source.write_text("def calibrate():\n    from perga.studies.calibrate_report import x\n")
    found = [
        ("perga.studies.calibrate", line, n)
        for line, n in imports(source, "perga.studies.calibrate")
    ]
    assert report_violations(found) == [
        "perga.studies.calibrate:2 imports perga.studies.calibrate_report.x "
        "(a study never imports a report)"
    ]


def test_a_report_may_import_its_study() -> None:
    assert (
        report_violations([("perga.studies.window_report", 1, "perga.studies.window.Point")]) == []
    )


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
    assert found == []


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
    "perga.machine.chipmunk_state": {
        "_body", "_constraint", "_space", "_handlers", "_add_later", "_remove_later",
        "_post_step_callbacks", "_bodies_to_check",
    },
    "perga.machine.batch": {"_space", "_float_arr", "_int_arr"},
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
                and ast.unparse(node) != "os._exit"  # public: a forked child's way out
            ):
                bad.append(f"{module}:{node.lineno}: {ast.unparse(node)}")
    assert bad == []


def test_a_run_does_not_load_the_mesh_libraries() -> None:
    """trimesh and scipy.stats are imported where a mesh is read or cut, or a size
    distribution drawn, not by the modules every run loads: together they cost 0.35-0.6 s of
    each run's start (docs/dev/performance.md)."""
    code = (
        "import sys, perga.run, perga.case, perga.output.vtk, perga.engine, perga.geometry;"
        "print(sorted(m for m in ('trimesh', 'scipy.stats') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"


def contact_parts_loaded(case: Path) -> list[str]:
    """The parts of perga.contact a fresh interpreter has loaded after building ``case``'s
    simulation and stepping it three times."""
    code = (
        "import sys; from perga.case import load_case; from perga.engine import Simulation;"
        "from perga.model.compile import compile_case;"
        f"sim = Simulation(compile_case(load_case({str(case)!r}))); sim.run(3 * sim.dt);"
        "print(' '.join(sorted({m.split('.')[2] for m in sys.modules"
        " if m.startswith('perga.contact.')})))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_a_rigid_run_does_not_load_the_kernel() -> None:
    """A rigid simulation loads the rigid model, the protocol and the (pure) contact laws the
    case schema asks, never perga.contact.soft (the numba kernel); a soft one is seen to load
    it (the check can fail)."""
    cases = Path(__file__).resolve().parents[1] / "cases"
    assert contact_parts_loaded(cases / "separator.toml") == ["laws", "protocol", "rigid"]
    assert "soft" in contact_parts_loaded(cases / "soft-separator.toml")
