"""The package's layers (docs/layout.md): every module imports only its own layer and the
layers above it, so that data flows one way. Read from the source of every module, the
imports inside functions included; the order is the one docs/layout.md states."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The order docs/layout.md gives (its sentence "each row imports only rows above it (...)").
SENTENCE = re.compile(r"each row imports only rows above it \((.*?)\)", re.S)


def _applications() -> set[str]:
    """The top row's modules, as docs/layout.md's table names them (its row of "the
    applications"), and the Python API."""
    text = (ROOT / "docs" / "layout.md").read_text()
    row = next(line for line in text.splitlines() if "the applications" in line)
    names = re.findall(r"`(?:tt_mujoco/)?(\w+)(?:\.py|/)?`", row.split("|")[1])
    assert "run" in names and "gym_env" in names, names
    return {*names, "api"}


#: The modules of the top row (the others outside ORDER: the package's own helpers).
APPLICATIONS = _applications()


def _order() -> list[str]:
    text = (ROOT / "docs" / "layout.md").read_text()
    rows = re.findall(r"`(\w+)`", SENTENCE.search(text).group(1))
    assert rows[:2] == ["vehicle", "reference"] and "sim" in rows, rows
    return rows


ORDER = _order()


def _layer(module: str) -> int | None:
    """0: the package's own helpers; 1..: the rows of ORDER; then the applications."""
    parts = module.split(".")
    if parts[0] != "tt_mujoco" or len(parts) == 1:
        return None
    if parts[1] in ORDER:
        return 1 + ORDER.index(parts[1])
    return len(ORDER) + 1 if parts[1] in APPLICATIONS else 0


def _modules():
    for path in sorted((ROOT / "tt_mujoco").rglob("*.py")):
        yield (
            path,
            "tt_mujoco." + ".".join(path.relative_to(ROOT / "tt_mujoco").with_suffix("").parts),
        )
    for path in sorted((ROOT / "controllers").rglob("*.py")):
        rel = ".".join(path.relative_to(ROOT / "controllers").with_suffix("").parts)
        yield path, f"tt_mujoco.controllers.{rel}"


def _imported(tree) -> set[str]:
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            if node.module == "tt_mujoco":
                names |= {f"tt_mujoco.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
    return names


def test_no_module_imports_a_layer_below_its_own():
    wrong = []
    for path, module in _modules():
        mine = _layer(module.removesuffix(".__init__"))
        for name in _imported(ast.parse(path.read_text())):
            theirs = _layer(name)
            if mine is not None and theirs is not None and theirs > mine:
                wrong.append(f"{module} imports {name}")
    assert not wrong, "\n".join(wrong)


def test_every_subpackage_has_a_layer():
    packages = {p.name for p in (ROOT / "tt_mujoco").iterdir() if (p / "__init__.py").exists()}
    assert packages <= {*ORDER, *APPLICATIONS}, packages - {*ORDER, *APPLICATIONS}


def test_the_simulated_parts_never_import_the_loop_or_the_run():
    # tt_mujoco/sim/parts/ holds the physical parts; the loop (sim/loop/) and the run's setup
    # (sim's top) compose them, never the other way round
    wrong = []
    for path, module in _modules():
        if not module.startswith("tt_mujoco.sim.parts."):
            continue
        tree = ast.parse(path.read_text())
        imported = _imported(tree)
        for node in ast.walk(tree):  # "from tt_mujoco.sim import scenario" names modules
            if isinstance(node, ast.ImportFrom) and node.module == "tt_mujoco.sim":
                imported |= {f"tt_mujoco.sim.{a.name}" for a in node.names}
        for name in imported:
            inside = name.startswith("tt_mujoco.sim.") and name != "tt_mujoco.sim.parts"
            if inside and not name.startswith("tt_mujoco.sim.parts."):
                wrong.append(f"{module} imports {name}")
    assert not wrong, "\n".join(wrong)
