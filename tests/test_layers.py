"""The package's architecture, held: layers import only downward, modules stay small, importing changes nothing."""

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "colorsort"
# Lowest first; a module may import its own layer and those before it.
LAYERS = ("base", "executors", "shifts", "cell", "envs", "expert", "data", "benchmark", "batched", "training", "cli")
MAX_LINES = 400


def layer_of(module: str) -> int:
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 and parts[1] in LAYERS else 0


def modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).with_suffix("")
        out.append((".".join(rel.parts).removesuffix(".__init__"), path))
    return out


def runtime_imports(path: Path) -> set[str]:
    """Every colorsort module ``path`` imports when it runs (``if TYPE_CHECKING:`` blocks aside)."""
    tree = ast.parse(path.read_text())
    skip = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
            for n in ast.walk(node)}
    found = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("colorsort"):
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)  # `from colorsort.cell import cameras`
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("colorsort"))
    return found


def all_imports(path: Path) -> set[str]:
    """Every colorsort module ``path`` names in an import: at module level, in functions, and type-only."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("colorsort"):
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("colorsort"))
    return found


def import_cycles() -> list[list[str]]:
    """The import graph's cycles (strongly connected groups of modules), type-only and deferred imports included."""
    known = {name for name, _ in modules()}
    graph = {name: sorted(t for t in all_imports(path) if t in known and t != name) for name, path in modules()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups = []

    def visit(v: str) -> None:  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in graph:
        if v not in index:
            visit(v)
    return groups


def test_no_import_cycles_between_modules():
    """Not even through ``if TYPE_CHECKING:`` or an import inside a function: a cycle is a design to untangle."""
    assert import_cycles() == []


def test_every_import_points_down_the_layers():
    known = {name for name, _ in modules()}
    upward = []
    for name, path in modules():
        if name == "colorsort":
            continue  # the package's __init__ registers the task and the Gymnasium ids: it sits on top
        for target in runtime_imports(path):
            if target in known and layer_of(target) > layer_of(name):
                upward.append(f"{name} ({LAYERS[layer_of(name)]}) imports {target} ({LAYERS[layer_of(target)]})")
    assert not upward, "imports that run back up a layer:\n" + "\n".join(upward)


def test_the_physics_layer_names_no_env_even_for_types():
    """``cell`` is the plant; what it reads of a cell it takes as the plant, never the robosuite task above it."""
    named = {name: sorted(t for t in all_imports(path) if t.startswith("colorsort.envs"))
             for name, path in modules() if name.startswith("colorsort.cell")}
    assert {name: envs for name, envs in named.items() if envs} == {}


def test_no_module_imports_another_packages_private_modules():
    """Another package's ``_private`` modules are not its API (``mujoco_warp._src`` among them): none is imported, nor
    reached as an attribute."""
    private = [f"{name}: ._src" for name, path in modules() if "._src" in path.read_text()]
    for name, path in modules():
        for node in ast.walk(ast.parse(path.read_text())):
            names = [node.module or ""] if isinstance(node, ast.ImportFrom) else (
                [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            private += [f"{name}: {m}" for m in names
                        if not m.startswith("colorsort") and any(part.startswith("_") for part in m.split(".")[1:])]
    assert private == []


# an import's top-level name -> the distribution that provides it, where the two differ
DISTRIBUTION = {"cv2": "opencv-python-headless", "mujoco_warp": "mujoco-warp", "warp": "warp-lang"}


def test_every_package_imported_is_declared_with_bounds_in_setup_py():
    """A package ColorSort imports is one it declares (with a version range), never one it gets through another's
    requirements (torch through lerobot)."""
    setup_text = (PACKAGE.parent / "setup.py").read_text()
    declared = {name.lower(): spec for name, spec in re.findall(r'"([A-Za-z0-9_.-]+)(?:\[[^\]]*\])?([<>=][^"]*)"',
                                                                 setup_text)}
    imported: set[str] = set()
    for _, path in modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                imported.add(node.module.split(".")[0])
    third_party = {DISTRIBUTION.get(m, m).lower() for m in imported - set(sys.stdlib_module_names) - {"colorsort"}}
    assert sorted(third_party - set(declared)) == []
    unbounded = [f"{d}{declared[d]}" for d in third_party if "<" not in declared[d] and "==" not in declared[d]]
    assert unbounded == []


def test_no_function_grows_past_60_lines():
    long = set()
    for name, path in modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno - node.lineno >= 60:
                long.add(f"{name}.{node.name}")
    assert not long, f"over 60 lines: split where the split names a concept: {sorted(long)}"


def test_the_layers_are_the_packages_folders():
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").is_file()}
    assert folders == set(LAYERS[1:])


@pytest.mark.parametrize("name,path", modules(), ids=[n for n, _ in modules()])
def test_no_module_is_over_400_lines(name, path):
    assert len(path.read_text().splitlines()) <= MAX_LINES


def third_party_imports() -> set[str]:
    """The other packages colorsort's modules import at module level."""
    found = set()
    for _, path in modules():
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.Import):
                found.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                found.add(node.module)
    return {m for m in found if not m.startswith(("colorsort", "__future__"))}


@pytest.mark.slow
def test_importing_any_module_changes_no_environment_variable_or_warning_filter():
    names = [n for n, _ in modules() if n != "colorsort"]
    script = (
        "import os, sys, json, warnings, importlib\n"
        "import colorsort\n"  # the package itself defaults MUJOCO_GL before robosuite loads a renderer
        f"for name in {sorted(third_party_imports())!r}:\n"  # what other packages do at import is theirs
        "    importlib.import_module(name)\n"
        "env, filters = dict(os.environ), list(warnings.filters)\n"
        f"for name in {names!r}:\n"
        "    importlib.import_module(name)\n"
        "changed = sorted(k for k in set(env) | set(os.environ) if env.get(k) != os.environ.get(k))\n"
        "print(json.dumps({'env': changed, 'filters': len(warnings.filters) - len(filters)}))\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result == {"env": [], "filters": 0}


def test_no_private_name_crosses_a_module():
    """``from colorsort.x import _name`` would tie a module to another's internals: share it under a public name."""
    crossing = []
    for name, path in modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("colorsort"):
                crossing += [f"{name} imports {node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
    assert not crossing, "\n".join(crossing)


# names each console script or worker module defines for its own use, by one convention
PER_MODULE = {"main", "parse_args", "SPELLING", "PRELOAD"}
# public names still defined in two modules with two meanings ("one name per concept"): to be renamed; none may be
# added to this list
def test_a_public_name_is_defined_in_one_module():
    """A top-level public class, function or constant means one thing: defined in one module (console scripts'
    ``main`` and ``parse_args`` aside)."""
    defined: dict[str, list[str]] = {}
    for name, path in modules():
        for node in ast.parse(path.read_text()).body:
            names = [node.name] if isinstance(node, ast.ClassDef | ast.FunctionDef) else [
                t.id for t in getattr(node, "targets", [getattr(node, "target", None)]) if isinstance(t, ast.Name)]
            for found in names:
                if not found.startswith("_") and (isinstance(node, ast.ClassDef | ast.FunctionDef) or found.isupper()):
                    defined.setdefault(found, []).append(name)
    twice = {n: ms for n, ms in defined.items() if len(ms) > 1 and n not in PER_MODULE}
    assert not twice, f"public names defined in more than one module: {twice}"
