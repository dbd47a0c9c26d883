"""The layers of ARCHITECTURE.md hold: the mechanics crate (`crates/stewart-core`) depends on no
FMI, FFI or packaging crate of the workspace, the FMU crate does not link the build program or
the master, and inside each crate no two modules import each other, directly or round a
circle (a `use` or a path naming another module's item is an import; a `mod` line is not);
nor do the Python package's modules (an import inside a function counts too). A circle or a
wrong dependency makes the test fail and names it."""

import ast
import json
import re
import subprocess
from pathlib import Path

import pytest

from stewart_fmu import ROOT

pytestmark = pytest.mark.quick

CRATES = {"stewart-core": ROOT / "crates" / "stewart-core" / "src", "stewart_fmu": ROOT / "src"}


def file_modules(src: Path) -> dict:
    """Module path (a tuple of names) -> its file, for every file module of a crate but the
    unit tests' own files (`tests.rs`)."""
    modules = {}
    for f in src.rglob("*.rs"):
        if f.name == "tests.rs":
            continue
        parts = list(f.relative_to(src).with_suffix("").parts)
        if parts[-1] in ("mod", "lib"):
            parts = parts[:-1]
        modules[tuple(parts)] = f
    return modules


def code(text: str) -> str:
    """The text without comments and without the unit tests written at a file's end (an
    inline `#[cfg(test)] mod name { ... }`; a `mod tests;` line only names a file, left out)."""
    text = re.sub(r"/\*.*?\*/", "", re.sub(r"//[^\n]*", "", text), flags=re.S)
    return re.split(r"#\[cfg\(test\)\]\s*mod \w+\s*\{", text)[0]


def imports(src: Path) -> dict:
    """Module -> the other file modules it names by `crate::` or `super::` paths, leaving out
    its own ancestors (a module's `mod.rs` holds shared items such as `LEG_COUNT`)."""
    modules = file_modules(src)

    def owner(path):
        for n in range(len(path), 0, -1):
            if tuple(path[:n]) in modules:
                return tuple(path[:n])
        return None

    graph = {}
    for module, f in modules.items():
        named = set()
        for hit in re.finditer(r"\b(crate|super)((?:::\w+)+)", code(f.read_text())):
            rest = hit.group(2).split("::")[1:]
            if hit.group(1) == "crate":
                base = []
            else:
                base = list(module[:-1])
                while rest and rest[0] == "super":
                    base, rest = base[:-1], rest[1:]
            target = owner(base + rest)
            if target and target != module and module[: len(target)] != target:
                named.add(target)
        graph[module] = named
    return graph


def circles(graph: dict) -> list:
    """The strongly connected groups of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append("::".join(w))
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_no_module_imports_round_a_circle():
    for name, src in CRATES.items():
        graph = imports(src)
        assert len(graph) > 20 and sum(map(len, graph.values())) > 50, f"{name}: the import graph was not read"
        assert circles(graph) == [], f"{name}: modules importing each other round a circle"


def python_imports(package: Path) -> dict:
    """Module -> the package's modules it imports (`from . import x`, `from .x import y`),
    wherever in the file the import stands."""
    graph = {(f.stem,): set() for f in package.glob("*.py")}
    for f in package.glob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                names = [node.module.split(".")[0]] if node.module else [a.name for a in node.names]
                graph[(f.stem,)] |= {(n,) for n in names if (n,) in graph and n != f.stem}
    return graph


def test_no_python_module_imports_round_a_circle():
    graph = python_imports(ROOT / "python" / "stewart_fmu")
    assert len(graph) > 15 and sum(map(len, graph.values())) > 30, "the package's imports were not read"
    assert circles(graph) == [], "modules of stewart_fmu importing each other round a circle"


def test_the_circle_finder_finds_a_circle():
    # The finder itself can fail: two modules naming each other are one circle.
    graph = {("a",): {("b",)}, ("b",): {("a",)}, ("c",): {("a",)}}
    assert circles(graph) == [["a", "b"]]


def test_the_mechanics_crate_depends_on_no_fmi_layer():
    metadata = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"], cwd=ROOT,
                                         capture_output=True, text=True, check=True).stdout)
    depends = {p["name"]: {d["name"] for d in p["dependencies"] if d["kind"] is None} for p in metadata["packages"]}
    assert depends["stewart-core"] <= {"nalgebra", "libm", "num-traits"}, depends["stewart-core"]
    assert "stewart-core" in depends["stewart_fmu"]
    assert not depends["stewart_fmu"] & {"build-fmu", "stewart-master", "stewart-master-py"}
    # Its sources name no FMI layer, no C boundary, no files, sockets or processes.
    for f in file_modules(CRATES["stewart-core"]).values():
        text = code(f.read_text())
        for banned in (r"\bstewart_fmu\b", r'extern\s+"C"', r"\bstd::(fs|io|net|process)\b", r"\blibc\b"):
            assert not re.search(banned, text), f"{f.relative_to(ROOT)} has {banned}"
