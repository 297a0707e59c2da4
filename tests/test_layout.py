"""The package's import structure: no cycles, no private names across modules, layering.

Every module under ``src/baseparams`` is parsed with :mod:`ast`; imports anywhere in a module
(module level and inside functions) are edges of the graph of ``baseparams.*`` modules.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "baseparams"

#: floor of each top-level part (a package or a module of ``baseparams``): a module may import only from its
#: own part or from parts on lower floors. No exception: a part is one floor, and an import that runs back up
#: or sideways (another part on the same floor) fails :func:`test_layering`.
LAYERS = {
    "errors": 0, "enums": 0, "pga": 0, "version": 0, "startup": 0,
    "files": 1, "display": 1, "arguments": 1, "interrupts": 1,
    "schema": 2, "tables": 2,
    "model": 3,
    "kinematics": 4,
    "regressor": 5, "jointlog": 5,
    "numerics": 6, "io": 6,
    "nullspace": 7,
    "base": 8, "report": 8,
    "analysis": 9,
    "robots": 10, "symbolic": 10, "ident": 10,
    "loading": 11, "fleet": 11, "excitation": 11,
    "sweep": 12, "workflow": 12,
    "cli": 13,
    "__main__": 14, "__init__": 14,
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def _is_package(name: str) -> bool:
    return MODULES.get(name) is not None and MODULES[name].name == "__init__.py"


def _imports(name: str) -> list[tuple[str, str | None, bool]]:
    """``(target module, imported name or None, at module level)`` for every import of ours."""
    tree = ast.parse(MODULES[name].read_text())
    base = name if _is_package(name) else name.rpartition(".")[0]
    top = {id(n) for n in tree.body}
    out = []
    for node in ast.walk(tree):
        level = id(node) in top
        if isinstance(node, ast.Import):
            out += [(a.name, None, level) for a in node.names if a.name.split(".")[0] == "baseparams"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                pkg = base.split(".")
                pkg = pkg[: len(pkg) - (node.level - 1)]
                mod = ".".join(pkg + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.split(".")[0] != "baseparams":
                continue
            for a in node.names:
                sub = f"{mod}.{a.name}"
                out.append((sub, None, level) if sub in MODULES else (mod, a.name, level))
    return out


def _graph(module_level_only: bool) -> dict[str, set[str]]:
    return {m: {t for t, _, lvl in _imports(m) if t in MODULES and t != m and (lvl or not module_level_only)}
            for m in MODULES}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for t in sorted(graph[m]):
            if state.get(t) == 1:
                return stack[stack.index(t):] + [t]
            if t not in state and (c := visit(t)):
                return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (c := visit(m)):
            return c
    return None


def _part(module: str) -> str:
    """The top-level part of ``baseparams.<part>...`` (``__init__`` for the package itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_every_module_is_found():
    assert {"baseparams.pga.core", "baseparams.nullspace.drng", "baseparams.io.urdf"} <= set(MODULES)


@pytest.mark.parametrize("module_level_only", [True, False], ids=["module-level", "with-function-imports"])
def test_no_import_cycles(module_level_only):
    assert _cycle(_graph(module_level_only)) is None


def test_no_cycles_between_parts():
    parts: dict[str, set[str]] = {}
    for m, targets in _graph(False).items():
        parts.setdefault(_part(m), set()).update(_part(t) for t in targets if _part(t) != _part(m))
    assert _cycle(parts) is None


def test_no_private_names_across_modules():
    bad = [f"{m} imports {t}.{n}" for m in MODULES for t, n, _ in _imports(m)
           if t != m and n is not None and n.startswith("_") and not n.startswith("__")]
    bad += [f"{m} imports module {t}" for m in MODULES for t, _, _ in _imports(m)
            if t != m and t.rpartition(".")[2].startswith("_") and t.rpartition(".")[2] != "__init__"]
    assert not bad


def test_no_private_attributes_of_other_modules():
    """``alias._name`` where ``alias`` is a module of ours imported as a name."""
    bad = []
    for m, path in MODULES.items():
        tree = ast.parse(path.read_text())
        aliases = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                aliases |= {a.asname or a.name for a in node.names}
        mods = {a for a in aliases}
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in mods
                    and node.attr.startswith("_") and not node.attr.startswith("__")):
                bad.append(f"{m}: {node.value.id}.{node.attr}")
    assert not bad


def _against_the_floors(graph: dict[str, set[str]], layers: dict[str, float]) -> list[str]:
    """``module -> target`` for every import into another part that is not on a lower floor."""
    return sorted(f"{m} -> {t}" for m, targets in graph.items() for t in targets
                  if _part(m) != _part(t) and layers[_part(t)] >= layers[_part(m)])


def test_layering():
    """pga, errors and enums import nothing of ours; each part imports only its own or lower floors."""
    assert _against_the_floors(_graph(False), LAYERS) == []
    assert set(LAYERS) >= {_part(m) for m in MODULES}
    assert not set(LAYERS) - {_part(m) for m in MODULES}, "a floor for a part that does not exist"


def test_layering_check_sees_arrows_up_and_sideways():
    """The check itself: an import up a floor or to another part on the same floor is reported."""
    layers = {"low": 0, "mid": 1, "side": 1, "high": 2}
    graph = {"baseparams.mid.a": {"baseparams.low", "baseparams.mid.b"}, "baseparams.low": {"baseparams.high.x"},
             "baseparams.side": {"baseparams.mid.a"}, "baseparams.mid.b": set()}
    assert _against_the_floors(graph, layers) == ["baseparams.low -> baseparams.high.x",
                                                  "baseparams.side -> baseparams.mid.a"]


@pytest.mark.parametrize("part, allowed", [
    ("pga", set()),
    ("errors", set()),
    ("enums", set()),
    ("model", {"pga", "errors", "enums", "display"}),
    ("kinematics", {"pga", "errors", "enums", "display", "model"}),
    ("regressor", {"pga", "errors", "enums", "display", "model", "kinematics"}),
])
def test_inner_parts_import_only_inner_parts(part, allowed):
    used = {_part(t) for m, ts in _graph(False).items() if _part(m) == part for t in ts} - {part}
    assert used <= allowed


def test_no_submodule_shadows_a_public_name():
    """Importing a submodule binds it as an attribute of its package: a module named like a
    front-door function (``baseparams.load``) would replace the function once imported. Only
    ``regressor`` is both, and ``__init__`` imports the subpackage before binding the function."""
    import importlib

    import baseparams

    public = set(baseparams.__all__)
    subs = {name.split(".")[1] for name in MODULES if name.count(".") >= 1}
    assert subs & public <= {"regressor"}
    for name in sorted(MODULES):
        importlib.import_module(name)
    assert callable(baseparams.load) and callable(baseparams.regressor) and callable(baseparams.analyze)


#: the longest a function may be (lines from ``def`` to its last line, decorators and the
#: docstring excluded: documenting a function never makes it "long")
MAX_FUNCTION_LINES = 60


def _long_functions(modules: dict[str, Path] = MODULES) -> list[str]:
    """``module:line name (lines)`` for every function over :data:`MAX_FUNCTION_LINES` lines
    whose docstring has no line starting with ``Long:`` (the reason it is not split)."""
    out = []
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            length = node.end_lineno - node.lineno + 1
            doc = ast.get_docstring(node) or ""
            if doc:
                first = node.body[0]
                length -= first.end_lineno - first.lineno + 1
            if length > MAX_FUNCTION_LINES and not any(ln.strip().startswith("Long:") for ln in doc.splitlines()):
                out.append(f"{name}:{node.lineno} {node.name} ({length} lines)")
    return out


def test_functions_are_short():
    """Every function is at most 60 lines, split into named steps, unless its docstring says
    why not on a line starting with ``Long:``."""
    assert _long_functions() == []


def test_function_length_check_sees_long_functions(tmp_path):
    """The check itself: a long function is reported, and a ``Long:`` reason silences it."""
    body = "\n".join(f"    x{k} = {k}" for k in range(MAX_FUNCTION_LINES))
    (tmp_path / "long.py").write_text(f'def f():\n    """Doc."""\n{body}\n\n\n'
                                      f'def g():\n    """Doc.\n\n    Long: a reason.\n    """\n{body}\n')
    assert _long_functions({"long": tmp_path / "long.py"}) == ["long:1 f (61 lines)"]


#: the most parameters a function may take ("about ten"), ``self``/``cls`` not counted, ``*args``/``**kw`` one each:
#: options travel as one checked object (``IdentOptions``, ``DesignOptions``), not as argument lists
MAX_PARAMETERS = 11

#: the public front door: one keyword per flag of the command line (``baseparams.identify`` is
#: ``baseparams.workflow.identify.identify``); nothing else may take more than :data:`MAX_PARAMETERS`
FRONT_DOOR = {"baseparams.workflow.identify.identify", "baseparams.workflow.excite.excite",
              "baseparams.workflow.simulate.simulate", "baseparams.workflow.payload.identify_payload"}


def _compiled(node) -> bool:
    """A compiled kernel (``@njit(...)``, ``@numba.jit``): its arguments are arrays the compiler needs flat."""
    names = [ast.unparse(d.func if isinstance(d, ast.Call) else d) for d in node.decorator_list]
    return any(n.rsplit(".", 1)[-1] in ("njit", "jit") for n in names)


def _many_parameters(modules: dict[str, Path] = MODULES, front_door=frozenset(FRONT_DOOR)) -> list[str]:
    """``module:line name (count)`` for every function with more than :data:`MAX_PARAMETERS` parameters."""
    out = []
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) or _compiled(node):
                continue
            a = node.args
            params = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs if x.arg not in ("self", "cls")]
            count = len(params) + (a.vararg is not None) + (a.kwarg is not None)
            if count > MAX_PARAMETERS and f"{name}.{node.name}" not in front_door:
                out.append(f"{name}:{node.lineno} {node.name} ({count})")
    return out


def test_functions_take_few_parameters():
    """Outside the front door and the compiled kernels no function takes more than about ten parameters."""
    assert _many_parameters() == []
    assert all(p.rsplit(".", 1)[0] in MODULES for p in FRONT_DOOR)
    import baseparams

    assert {f.rsplit(".", 1)[1] for f in FRONT_DOOR} <= set(baseparams.__all__)


def test_parameter_count_check_sees_long_signatures(tmp_path):
    """The check itself: a long signature is reported, the front door and a compiled kernel are not."""
    args = ", ".join(f"a{k}" for k in range(MAX_PARAMETERS + 1))
    (tmp_path / "m.py").write_text(f"def f({args}):\n    pass\n\n\ndef door({args}):\n    pass\n\n\n"
                                   f"@njit(cache=True)\ndef kernel({args}):\n    pass\n\n\n"
                                   f"def ok(self, {', '.join(f'b{k}' for k in range(MAX_PARAMETERS))}):\n    pass\n")
    assert _many_parameters({"m": tmp_path / "m.py"}, {"m.door"}) == [f"m:1 f ({MAX_PARAMETERS + 1})"]


#: what the repository's root holds (tracked): anything else there is a stray file (a report written by hand,
#: a log) and belongs in a folder, in .gitignore, or nowhere
ROOT_ENTRIES = {".ci", ".gitignore", "README.md", "benchmarks", "docs", "pyproject.toml", "src", "tests"}
#: untracked entries the tools make at the root (.gitignore's, caches): left out when git cannot be asked
GENERATED = {".git", ".venv", ".venv-ci", "build", "dist", "__pycache__", ".pytest_cache", ".hypothesis", ".ruff_cache",
             "MUJOCO_LOG.TXT"}


def _root_entries(root: Path) -> set[str]:
    """The first path component of every file git tracks under ``root`` (its listing without git)."""
    import shutil
    import subprocess

    if shutil.which("git") and (root / ".git").exists():
        out = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True, text=True, check=True).stdout
        return {p.split("/")[0] for p in out.split("\0") if p}
    return {p.name for p in root.iterdir() if p.name not in GENERATED and not p.name.endswith(".egg-info")}


def test_the_root_holds_only_its_files():
    root = SRC.parent
    assert _root_entries(root) - ROOT_ENTRIES == set(), "stray files at the repository's root"
    assert ROOT_ENTRIES - {"docs", ".ci"} <= _root_entries(root)


def test_root_check_sees_a_stray_file(tmp_path):
    """The check itself, on a folder without git: a stray file is seen, the tools' caches are not."""
    for name in (*ROOT_ENTRIES, ".pytest_cache", "x"):
        (tmp_path / name).write_text("")
    assert _root_entries(tmp_path) - ROOT_ENTRIES == {"x"}
