"""docs/architecture.md names only what the packages really export, so it cannot drift silently."""

from __future__ import annotations

import importlib
import re
import types
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
