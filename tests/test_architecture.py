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
    "studio.motion",
    "studio.web",
    "studio.samples",
    "studio.export",
    "studio.physics",
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
    package = importlib.import_module(module)
    for name in dir(package):  # a lazy package's too (studio/_lazy.py): all it lists
        value = getattr(package, name)
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


ROOT = Path(__file__).resolve().parents[1]
NARROW = ("studio.kinematics", "studio.capture", "studio.learning", "studio.motion")
"""Packages that export only what is used outside them: by the other packages, the commands,
the web layer, the benchmarks, ``recordings/make_samples.py``, or users' scripts as the READMEs
and ``docs/`` show them."""
FOR_USERS = {
    **dict.fromkeys(
        (
            "studio.learning.DEFAULT_GOAL_DEG",
            "studio.learning.MAX_TABLE_ENTRIES",
            "studio.learning.MAX_EPISODE_RUNS",
            "studio.learning.MAX_EPISODES",
            "studio.learning.MAX_EXPERIMENTS",
            "studio.learning.check_budget",
            "studio.learning.FIGURE_POINTS",
            "studio.learning.curve_plot",
            "studio.learning.curve_statistics",
            "studio.learning.downsample_curve",
            "studio.learning.grid_for_goal",
            "studio.learning.check_goal_deg",
            "studio.learning.TabularMDP",
            "studio.learning.load_dmp_policy",
            "studio.learning.save_dmp_policy",
            "studio.learning.likeness_card",
            "studio.learning.LikenessCard",
            "studio.learning.load_policy",
            "studio.learning.rollout",
            "studio.learning.greedy_path",
            "studio.learning.rollout_tile_policy",
            "studio.learning.DmpPolicyFile",
            "studio.learning.PolicyFile",
            "studio.learning.default_goal",
        ),
        "a user's script calls it as studio/learning/README.md or docs/sweeps.md shows",
    ),
    "studio.learning.policy_likeness_card": "issue 21: the likeness card of any policy kind",
    **dict.fromkeys(
        (
            "studio.learning.Learner",
            "studio.learning.Rollout",
            "studio.learning.Evaluation",
            "studio.learning.learner",
            "studio.learning.register_learner",
        ),
        "issue 37: one learner interface, registered by kind, that issue 40's baselines implement",
    ),
    "studio.kinematics.PoseFit": "issue 19: fit_pose_landmarks(landmarks, side) -> PoseFit",
    **dict.fromkeys(
        (
            "studio.kinematics.IKConfig",
            "studio.kinematics.FitConfig",
            "studio.kinematics.RetargetConfig",
            "studio.kinematics.HandIKConfig",
            "studio.kinematics.PoseConfig",
            "studio.kinematics.StreamConfig",
            "studio.capture.OperatorConfig",
            "studio.capture.Calibration",
        ),
        "the settings a public constructor or function takes (config=, ik=, fit=, operator=, calibration=)",
    ),
}
"""Public names that no code outside their package calls, and why each stays public. (Every
``StudioError`` subclass stays public too: users catch them.)"""


def _outside_uses() -> dict[str, set[str]]:
    """For each package of ``NARROW``, the names that code outside it takes from it."""
    uses: dict[str, set[str]] = {package: set() for package in NARROW}
    files = [
        *STUDIO.rglob("*.py"),
        *(ROOT / "benchmarks").glob("*.py"),
        *(ROOT / "recordings").glob("*.py"),
    ]
    for path in files:
        package = _module_name(path) if path.is_relative_to(STUDIO) else ""
        own = next((n for n in NARROW if package == n or package.startswith(f"{n}.")), None)
        tree = ast.parse(path.read_text(), str(path))
        bound: dict[str, str] = {}  # local name -> package of NARROW
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                module = node.module or ""
                if node.level:  # studio/ itself: resolve against the importing module
                    parts = package.split(".")
                    anchor = ".".join(
                        parts[: len(parts) - node.level + (path.name == "__init__.py")]
                    )
                    module = f"{anchor}.{module}" if module else anchor
                for alias in node.names:
                    if module in uses and module != own:
                        uses[module].add(alias.name)
                    elif f"{module}.{alias.name}" in uses:
                        bound[alias.asname or alias.name] = f"{module}.{alias.name}"
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in uses:
                        bound[alias.asname or alias.name] = alias.name
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute):
                owner = ast.unparse(node.value)
                owner = bound.get(owner, owner)
                if owner in uses and owner != own:
                    uses[owner].add(node.attr)
    return uses


CODE = ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
"""What runs only when called: an import inside it is late."""


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _module_name(path: Path) -> str:
    parts = path.relative_to(STUDIO.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(
    body: list[ast.stmt], late: bool, typing: bool = False, lazy: bool = False
) -> Iterator[ast.Import | ast.ImportFrom | str]:
    """The imports that run when a module is imported (anywhere in its body and in its class
    bodies, which run then too, inside any ``if``/``try``/``with``/loop/``match``) and, if
    ``late``, also those in its functions, methods and lambdas, which run when called. Those
    under ``if TYPE_CHECKING:``, which never run, only if ``typing``: the module still depends
    on what they name. ``importlib.import_module("studio....")`` with a literal name counts as an
    import of that module (yielded as its name). In a ``lazy`` package's ``__init__``
    (``studio/_lazy.py``) those under ``if TYPE_CHECKING:`` do run, late: when a name is first
    used."""
    pending: list[ast.AST] = list(body)
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
            continue
        if isinstance(node, CODE) and not late:
            runs_now = [
                *getattr(node, "decorator_list", []),
                *node.args.defaults,
                *node.args.kw_defaults,
            ]
            pending.extend(n for n in runs_now if n is not None)
            continue
        if isinstance(node, ast.If) and _is_type_checking(node.test) and not typing:
            pending.extend(node.orelse + (node.body if lazy and late else []))
            continue
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute | ast.Name)
            and (getattr(node.func, "attr", None) or getattr(node.func, "id", None))
            in ("import_module", "__import__")
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            yield node.args[0].value
        pending.extend(n for n in ast.iter_child_nodes(node) if n is not None)


def _import_graph(late: bool, typing: bool = False) -> dict[str, set[str]]:
    """Each module of ``studio`` and the modules of ``studio`` it imports (with ``typing``, also
    those it imports for type checking only)."""
    paths = {_module_name(p): p for p in STUDIO.rglob("*.py")}
    graph: dict[str, set[str]] = {name: set() for name in paths}
    for name, path in paths.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        text = path.read_text()
        lazy = path.name == "__init__.py" and "lazy_exports(" in text
        for node in _imports(ast.parse(text, str(path)).body, late, typing, lazy):
            if isinstance(node, str):
                targets = [node]
            elif isinstance(node, ast.Import):
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
    assert "studio.learning.tabular._dynaq" in graph["studio.learning.tabular._learner"]
    assert {"studio.learning.tabular._dynaq", "studio.learning.linear._linear"} <= _import_graph(
        late=True
    )["studio.learning"], "a lazy package's names are late imports of its __init__"
    assert _cycles(graph) == []


def test_no_import_cycle_through_late_imports():
    """Nor through an import inside a function (the learners' dispatcher once reached the linear
    learner so): a late import that closes a cycle hides the layering, it does not fix it."""
    graph = _import_graph(late=True)
    assert "studio.learning.linear._linear" in graph["studio.learning.paper._beyond"]
    assert _cycles(graph) == []


LAYERS = {
    "studio.kinematics": set(),
    "studio.capture": {"studio.kinematics"},
    "studio.learning": {"studio.kinematics"},
    "studio.physics": {"studio.kinematics"},
    "studio.samples": set(),
    "studio.motion": {"studio.kinematics", "studio.capture", "studio.learning"},
    "studio.export": {
        "studio.kinematics",
        "studio.capture",
        "studio.learning",
        "studio.physics",
        "studio.samples",
        "studio.motion",
    },
}
"""The packages of ``studio`` each package may import. Data flows from capture to learning
through ``studio.motion``: capture stores observations and joints and knows no learning task,
learning knows no recording, and neither knows the motion package that joins them. The web
layer and the commands sit on top."""


def _every_import(body: list[ast.stmt]) -> Iterator[ast.Import | ast.ImportFrom | str]:
    """Every import in a module, type-only ones and late ones included."""
    for node in ast.walk(ast.Module(body=body, type_ignores=[])):
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node


def _package_imports() -> dict[str, set[str]]:
    """For each package of ``LAYERS``, the other packages of ``studio`` its modules import (any
    import: at import time, late, or under ``TYPE_CHECKING``)."""
    found: dict[str, set[str]] = {package: set() for package in LAYERS}
    tops = {f"studio.{p.name}" for p in STUDIO.iterdir() if (p / "__init__.py").is_file()}
    for path in STUDIO.rglob("*.py"):
        name = _module_name(path)
        own = next((p for p in LAYERS if name == p or name.startswith(f"{p}.")), None)
        if own is None:
            continue
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in _every_import(ast.parse(path.read_text(), str(path)).body):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                targets = [node.module or ""]
                if node.level:
                    parts = package.split(".")
                    anchor = ".".join(parts[: len(parts) - node.level + 1])
                    targets = [f"{anchor}.{node.module}" if node.module else anchor]
                    targets += [f"{targets[0]}.{alias.name}" for alias in node.names]
            for target in targets:
                top = ".".join(target.split(".")[:2])
                if top in tops and top != own:
                    found[own].add(top)
    return found


def test_each_package_imports_only_the_layers_below_it():
    """Capture imports nothing from learning (nor learning from capture, nor either from the
    motion package above them), not even for a type annotation."""
    found = _package_imports()
    assert found["studio.motion"] >= {"studio.capture", "studio.learning"}
    assert {"studio.kinematics"} <= found["studio.capture"]
    wrong = {p: sorted(found[p] - allowed) for p, allowed in LAYERS.items() if found[p] - allowed}
    assert wrong == {}, "a package imports one above it or beside it: move the code up a layer"


def test_the_layer_scan_counts_type_only_and_late_imports():
    source = """
from typing import TYPE_CHECKING
if TYPE_CHECKING:
    from studio.learning import ArmGrid
def f():
    import studio.web
"""
    names = set()
    for node in _every_import(ast.parse(source).body):
        names |= {a.name for a in node.names} if isinstance(node, ast.Import) else {node.module}
    assert {"studio.learning", "studio.web"} <= names


def test_no_import_cycle_through_type_only_imports():
    """Nor through an import under ``if TYPE_CHECKING:``: it never runs, but the two modules
    still depend on each other (``learning/tasks/_follow.py`` once named ``ArmReach`` so, while
    ``_reach.py`` imported it); name what the other offers with a ``Protocol`` instead."""
    graph = _import_graph(late=True, typing=True)
    assert "studio.learning._tiles" in graph["studio.learning.tasks._follow"]
    assert _cycles(graph) == []


LATE_AND_EARLY = """
from typing import TYPE_CHECKING
import studio.a
if TYPE_CHECKING:
    import studio.never
else:
    import studio.b
try:
    from studio import c
except ImportError:
    pass
class Box:
    import studio.d
    def method(self):
        import studio.late_method
    async def pump(self):
        async with x:
            from studio import late_async
def outer():
    def inner():
        match y:
            case 1:
                import studio.late_nested
    return importlib.import_module("studio.late_dynamic")
f = lambda: __import__("studio.late_lambda")
"""


def _imported(source: str, late: bool, typing: bool = False, lazy: bool = False) -> set[str]:
    names = set()
    for node in _imports(ast.parse(source).body, late, typing, lazy):
        if isinstance(node, str):
            names.add(node)
        elif isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        else:
            names |= {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def test_the_import_scan_finds_every_import_that_runs():
    """Imports at import time include class bodies and both branches of a runtime ``if``; late
    ones include methods, async blocks, nested functions, ``match`` arms, lambdas and
    ``importlib.import_module``; ``if TYPE_CHECKING:`` imports are never counted."""
    early = {"typing.TYPE_CHECKING", "studio.a", "studio.b", "studio.c", "studio.d"}
    late = {
        "studio.late_method",
        "studio.late_async",
        "studio.late_nested",
        "studio.late_dynamic",
        "studio.late_lambda",
    }
    assert _imported(LATE_AND_EARLY, late=False) == early
    assert _imported(LATE_AND_EARLY, late=True) == early | late
    assert _imported(LATE_AND_EARLY, late=True, typing=True) == early | late | {"studio.never"}
    # a lazy package's TYPE_CHECKING names load when first used: late imports
    assert _imported(LATE_AND_EARLY, late=False, lazy=True) == early
    assert _imported(LATE_AND_EARLY, late=True, lazy=True) == early | late | {"studio.never"}


MAX_FILE_LINES = 800
MAX_FOLDER_MODULES = 20
"""The most modules (its ``__init__`` counted) one folder of ``studio`` holds: a fuller folder
hides its parts in name prefixes; give them a subpackage."""
MAX_FUNCTION_LINES = 100
MAX_PAGE_SCRIPT_LINES = 600
MAX_ANY_LINES = 115
"""The size budget: a file, a function and a page script a newcomer can read whole, and few
``Any`` (lines naming it, as ``grep -rw Any studio --include=*.py | wc -l`` counts them)."""
LONG_FUNCTIONS = {
    "studio/learning/tabular/_dynaq.py::_run_experiment": (
        "the tabular numba kernel: with its action choice, model update and planning loops in "
        "inlined helpers a real step took twice as long (1.4 -> 3.0 ms CPU per zero-planning "
        "experiment on the arm grid), see its docstring"
    ),
}
"""Functions allowed over the budget, each with the measured reason."""


def _python_files() -> list[Path]:
    return sorted(STUDIO.rglob("*.py"))


def test_no_python_file_in_studio_is_over_the_budget():
    long_files = {
        str(path.relative_to(STUDIO.parent)): lines
        for path in _python_files()
        if (lines := len(path.read_text().splitlines())) > MAX_FILE_LINES
    }
    assert long_files == {}, f"over {MAX_FILE_LINES} lines: split by responsibility"


def test_no_folder_of_studio_holds_more_than_its_share_of_modules():
    full = {
        str(folder.relative_to(STUDIO.parent)): count
        for folder in sorted({path.parent for path in _python_files()})
        if (count := len(list(folder.glob("*.py")))) > MAX_FOLDER_MODULES
    }
    assert full == {}, f"over {MAX_FOLDER_MODULES} modules: group their parts in subpackages"


def test_no_function_in_studio_is_over_the_budget_but_the_named_ones():
    long_functions = {}
    for path in _python_files():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long_functions[f"{path.relative_to(STUDIO.parent)}::{node.name}"] = lines
    assert set(long_functions) == set(LONG_FUNCTIONS), (
        f"functions over {MAX_FUNCTION_LINES} lines: {long_functions}; split them, or name a "
        "measured reason in LONG_FUNCTIONS (and drop a name that no longer needs it)"
    )


def test_no_page_script_is_over_the_budget():
    static = STUDIO / "web" / "static"
    scripts = [p for p in static.rglob("*.js") if "vendor" not in p.relative_to(static).parts]
    assert len(scripts) >= 10
    long_scripts = {
        p.name: lines
        for p in scripts
        if (lines := len(p.read_text().splitlines())) > MAX_PAGE_SCRIPT_LINES
    }
    assert long_scripts == {}, f"page scripts over {MAX_PAGE_SCRIPT_LINES} lines: split them"


def test_any_stays_rare_in_studio():
    word = re.compile(r"\bAny\b")
    lines = sum(
        1 for path in _python_files() for line in path.read_text().splitlines() if word.search(line)
    )
    assert lines <= MAX_ANY_LINES, f"{lines} lines name Any; type them with protocols or TypedDicts"


def test_the_narrow_packages_export_only_what_is_used_outside_them():
    """A name only its own package uses stays in its private module (a test reaches it there),
    so ``import studio.learning`` shows a newcomer the surface, not the insides."""
    from studio import StudioError

    uses = _outside_uses()
    assert {"ArmGrid", "RunFolder", "resolve_run"} <= uses["studio.learning"]
    assert {"source_from_spec", "load_demonstration"} <= uses["studio.capture"]
    assert {"TapeConfig", "load_robot"} <= uses["studio.kinematics"]
    assert {"training_demonstration", "checked_demonstration"} <= uses["studio.motion"]
    unused = []
    for package in NARROW:
        module = importlib.import_module(package)
        for name in _exports(package):
            value = getattr(module, name)
            error = isinstance(value, type) and issubclass(value, StudioError)
            if name not in uses[package] and f"{package}.{name}" not in FOR_USERS and not error:
                unused.append(f"{package}.{name}")
    assert unused == [], (
        "exported but used only inside their package: import them from their private module, "
        "or name in FOR_USERS the user who needs them"
    )
    stale = [k for k in FOR_USERS if k.rpartition(".")[2] not in _exports(k.rpartition(".")[0])]
    assert stale == [], "FOR_USERS names what is no longer exported"


def test_the_data_flow_diagram_names_every_teacher_package_and_file_format():
    """The diagram once showed tape sources and a six-joint robot only (issue 37): it names each
    teacher, each package a motion passes through, and each export format."""
    text = DOC.read_text()
    diagram = text[text.index("## Data flow") : text.index("## What a newcomer reads first")]
    for word in ("tape", "camera", "hand guide", "q_robot(n)", "motion", "learning", "physics",
                 "MCAP", "LeRobot", "CSV", "studio evaluate"):  # fmt: skip
        assert word in diagram, f"the data-flow diagram does not mention {word!r}"
    assert "q_robot(6)" not in diagram
