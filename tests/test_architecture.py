"""docs/architecture.md names only what the packages really export, so it cannot drift silently."""

from __future__ import annotations

import ast
import importlib
import re
import types
from collections.abc import Iterator
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"
IMPORT_BLOCK = re.compile(r"from (studio(?:\.\w+)?) import \(([^)]*)\)")
PACKAGES = (
    "studio",
    "studio.kinematics",
    "studio.capture",
    "studio.learning",
    "studio.web",
    "studio.samples",
    "studio.export",
)
OWNER = re.compile(r"`(studio\.[a-z]+)(?:\.([\w.]+))?`(?: \(([^)|]*)\))?")


def _names(text: str) -> list[str]:
    return [n.strip().strip("`").split("(")[0] for n in text.split(",") if n.strip()]


def test_every_name_in_the_import_blocks_is_exported():
    blocks = IMPORT_BLOCK.findall(DOC.read_text())
    assert {module for module, _ in blocks} >= {
        "studio.kinematics",
        "studio.capture",
        "studio.learning",
    }
    for module, names in blocks:
        package = importlib.import_module(module)
        missing = [n for n in _names(names) if not hasattr(package, n)]
        assert not missing, f"{module} does not export {missing}"


def test_every_owner_named_in_the_concept_table_exists():
    text = DOC.read_text()
    table = text[text.index("## Where each concept lives") : text.index("## Runtime")]
    checked = 0
    for module, attribute, listed in OWNER.findall(table):
        package = importlib.import_module(module)
        for name in ([attribute] if attribute else []) + _names(listed):
            target = package
            for part in name.split("."):
                assert hasattr(target, part), f"{module} has no {name}"
                target = getattr(target, part)
            checked += 1
    assert checked >= 10


def _exports(module: str) -> list[str]:
    """The public names a package's ``__init__`` makes (not submodules, not third-party helpers
    such as ``Path`` that it merely imports)."""
    names = []
    for name, value in vars(importlib.import_module(module)).items():
        if name.startswith("_") or name == "annotations" or isinstance(value, types.ModuleType):
            continue
        owner = getattr(value, "__module__", None)
        if (
            (isinstance(value, type) or callable(value))
            and owner
            and not owner.startswith("studio")
        ):
            continue
        names.append(name)
    return names


def test_every_exported_name_is_in_its_import_block():
    """The import blocks list every public name, so a newcomer sees the whole surface."""
    blocks = dict(IMPORT_BLOCK.findall(DOC.read_text()))
    for module in PACKAGES:
        assert module in blocks, f"docs/architecture.md has no import block for {module}"
        listed = set(_names(blocks[module]))
        missing = [name for name in _exports(module) if name not in listed]
        assert not missing, f"docs/architecture.md does not list {module}'s {missing}"


STUDIO = Path(__file__).resolve().parents[1] / "studio"
LATE_CYCLES_TO_BREAK = (
    {"studio.capture._network", "studio.capture._source_spec"},
    {"studio.learning._prepare", "studio.learning._runs"},
)
"""Cycles closed only by an import inside a function, still to be broken (drop each when it is)."""
DEFS = ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef


def _module_name(path: Path) -> str:
    parts = path.relative_to(STUDIO.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(body: list[ast.stmt], late: bool) -> Iterator[ast.Import | ast.ImportFrom]:
    """The imports that run when a module is imported (in its body, and inside its top-level
    ``if``/``try``/``with``/loops) and, if ``late``, those in its functions and classes, which run when
    called. Never those under ``if TYPE_CHECKING:``, which never run."""
    pending = list(body)
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif isinstance(node, ast.If):
            if not (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"):
                pending.extend(node.body)
            pending.extend(node.orelse)
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody, *(h.body for h in node.handlers)):
                pending.extend(block)
        elif isinstance(node, ast.With | ast.For | ast.While) or (late and isinstance(node, DEFS)):
            pending.extend([*node.body, *getattr(node, "orelse", [])])


def _import_graph(late: bool) -> dict[str, set[str]]:
    """Each module of ``studio`` and the modules of ``studio`` it imports."""
    paths = {_module_name(p): p for p in STUDIO.rglob("*.py")}
    graph: dict[str, set[str]] = {name: set() for name in paths}
    for name, path in paths.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in _imports(ast.parse(path.read_text(), str(path)).body, late):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    anchor = ".".join(parts[: len(parts) - node.level + 1])
                    base = f"{anchor}.{base}" if base else anchor
                targets = [base] + [f"{base}.{alias.name}" for alias in node.names]
            graph[name] |= {t for t in targets if t in paths and t != name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The sets of modules that import each other (strongly connected components, Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[set[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = {stack.pop()}
            while node not in component:
                component.add(stack.pop())
            if len(component) > 1:
                cycles.append(component)

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return cycles


def test_no_import_cycle_between_studio_modules():
    """No module of ``studio`` imports, while it is imported, one that imports it back (directly
    or through others): such modules load in one order only."""
    graph = _import_graph(late=False)
    assert {"studio.learning._dynaq", "studio.learning._linear"} <= graph["studio.learning"]
    assert _cycles(graph) == []


def test_no_import_cycle_through_late_imports():
    """Nor through an import inside a function (the learners' dispatcher once reached the linear
    learner so): a late import that closes a cycle hides the layering, it does not fix it."""
    graph = _import_graph(late=True)
    assert "studio.learning._linear" in graph["studio.learning._beyond"]
    cycles = _cycles(graph)
    assert [c for c in cycles if c not in LATE_CYCLES_TO_BREAK] == []
