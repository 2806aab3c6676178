"""No code outside the robot registry branches on a robot's name.

What differs between robots is a property of the robot (its :class:`RobotSpec` in
``studio/kinematics``: joint mode, its default goal, the grid's range, ...) or of its model
(its limits, its forward kinematics), so adding an arm to the registry never needs a branch
elsewhere. A comparison with a registry name written as a string (``robot == "puma560"``), or
with a constant holding one (``PUMA = "puma560"``; ``robot != PUMA``; the registry's
``DEFAULT_ROBOT``), or a table keyed by one, is such a branch; the page's scripts are held to the same. As
``tests/learning/test_learners.py`` does for ``isinstance`` on policy classes.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from studio.kinematics import robot_names

ROOT = Path(__file__).resolve().parents[1]
STUDIO = ROOT / "studio"
REGISTRY = STUDIO / "kinematics"
NAMES = frozenset(robot_names())


def _sources() -> dict[str, str]:
    """Every Python module of studio outside the registry, by its path."""
    return {
        str(p.relative_to(ROOT)): p.read_text()
        for p in sorted(STUDIO.rglob("*.py"))
        if REGISTRY not in p.parents
    }


def _aliases(trees: dict[str, ast.Module]) -> set[str]:
    """Constants (upper-case names) bound, at a module's top, to a registry name or to another
    such constant (also when imported under another name), and the registry's ``DEFAULT_ROBOT``:
    "is it the default robot?" is a branch on its name too."""
    aliases = {"DEFAULT_ROBOT"}
    while True:
        found = set(aliases)
        for tree in trees.values():
            for node in tree.body:
                value = getattr(node, "value", None)
                targets = (
                    node.targets
                    if isinstance(node, ast.Assign)
                    else [getattr(node, "target", None)]
                )
                if isinstance(node, ast.Assign | ast.AnnAssign) and _names_in(value, found):
                    found |= {t.id for t in targets if isinstance(t, ast.Name) and t.id.isupper()}
                if isinstance(node, ast.ImportFrom):
                    found |= {a.asname for a in node.names if a.asname and a.name in found}
        if found == aliases:
            return aliases
        aliases = found


def _names_in(node: ast.AST | None, aliases: set[str]) -> bool:
    """Whether ``node`` is a registry name: a string, an alias, or a tuple, list or set of them."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str) and node.value in NAMES
    if isinstance(node, ast.Name):
        return node.id in aliases
    if isinstance(node, ast.Attribute):
        return node.attr in aliases
    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return any(_names_in(e, aliases) for e in node.elts)
    return False


def name_branches(sources: dict[str, str]) -> list[str]:
    """``path:line`` of every comparison with a registry name, match case on one, or table
    keyed by one, in the Python ``sources``."""
    trees = {path: ast.parse(text) for path, text in sources.items()}
    aliases = _aliases(trees)
    found = []
    for path, tree in trees.items():
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                hit = any(_names_in(n, aliases) for n in (node.left, *node.comparators))
            elif isinstance(node, ast.MatchValue):
                hit = _names_in(node.value, aliases)
            elif isinstance(node, ast.Dict):
                hit = any(_names_in(k, aliases) for k in node.keys if k is not None)
            else:
                continue
            if hit:
                found.append(f"{path}:{node.lineno}: {ast.unparse(node)[:80]}")
    return found


def script_branches(scripts: dict[str, str]) -> list[str]:
    """``path:line`` of every comparison with, or ``case`` on, a registry name in the page's
    ``scripts``."""
    names = "|".join(re.escape(n) for n in sorted(NAMES))
    quoted = rf"""["'`](?:{names})["'`]"""
    pattern = re.compile(rf"(?:[=!]==?\s*{quoted})|(?:{quoted}\s*[=!]==?)|(?:case\s+{quoted})")
    return [
        f"{path}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
        for path, text in scripts.items()
        for m in pattern.finditer(text)
    ]


def test_no_python_module_outside_the_registry_branches_on_a_robot_name() -> None:
    found = name_branches(_sources())
    assert not found, (
        "branch on a robot's name; make it a property of the robot's spec or model:\n"
        + "\n".join(found)
    )


def test_no_page_script_branches_on_a_robot_name() -> None:
    scripts = {
        str(p.relative_to(ROOT)): p.read_text()
        for p in sorted((STUDIO / "web" / "static").glob("*.js"))
    }
    assert scripts
    found = script_branches(scripts)
    assert not found, (
        "branch on a robot's name; send the robot's property with GET /api/robots:\n"
        + "\n".join(found)
    )


def test_the_scans_find_every_form_of_a_name_branch() -> None:
    """The scans themselves: each form of a branch is found, and a default or a message that
    only mentions a name is not."""
    branches = {
        "a.py": 'if robot == "puma560":\n    pass\n',
        "b.py": 'PUMA = "puma560"\nOTHER = PUMA\n',
        "c.py": "from b import OTHER as MINE\nok = name != MINE\n",
        "d.py": 'ok = name in ("ur5", "ur10")\n',
        "e.py": 'match name:\n    case "panda":\n        pass\n',
        "f.py": 'GOALS = {"panda": 1}\n',
        "g.py": "import b\nok = b.PUMA == name\n",
        "k.py": "from studio.kinematics import DEFAULT_ROBOT\nPAPER = DEFAULT_ROBOT\nok = r == PAPER\n",
    }
    found = name_branches(branches)
    assert [f.split(":")[0] for f in found] == [
        "a.py",
        "c.py",
        "d.py",
        "e.py",
        "f.py",
        "g.py",
        "k.py",
    ]
    fine = {
        "h.py": 'robot = "puma560"\nsay = f"the {robot}"\nok = robot == other\n',
        "j.py": 'class Form:\n    ROBOT: str = "panda"\n\nok = ROBOT == other\n',
        "i.py": 'def f(robot="panda"):\n    return robot == other\n',
    }
    assert name_branches(fine) == []
    scripts = {
        "a.js": 'if (s.robot !== "puma560") x();\n',
        "b.js": "const y = 'panda' === r.name;\n",
        "c.js": "switch (r) { case `ur5`: break; }\n",
        "d.js": 'const label = "puma560 is the default";\n',
    }
    assert [f.split(":")[0] for f in script_branches(scripts)] == ["a.js", "b.js", "c.js"]
