"""Packages whose public names load when first used.

Such a package's ``__init__`` lists its public names, as usual, one ``from ._module import Name as
Name`` each, but under ``if typing.TYPE_CHECKING:`` (readers and type checkers see them there), and
ends with::

    __getattr__, __dir__, __all__ = lazy_exports(__name__, __file__)

Importing the package then imports none of its modules; a name's module is imported when the name
is first used. ``studio train --help`` so reads a default of ``studio.learning`` without loading
numba, SciPy or Pinocchio (seconds of CPU), and a script pays only for the names it uses.
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable
from pathlib import Path


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def listed_names(init_file: str | Path) -> dict[str, tuple[str, str]]:
    """Each public name an ``__init__`` lists under ``if TYPE_CHECKING:`` -> the module it comes
    from (``._config``, or another package such as ``studio.motion``) and its name there."""
    found: dict[str, tuple[str, str]] = {}
    for node in ast.parse(Path(init_file).read_text()).body:
        if not (isinstance(node, ast.If) and _is_type_checking(node.test)):
            continue
        for statement in node.body:
            if isinstance(statement, ast.ImportFrom):
                module = "." * statement.level + (statement.module or "")
                for alias in statement.names:
                    found[alias.asname or alias.name] = (module, alias.name)
    return found


def lazy_exports(
    package: str, init_file: str
) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """The ``__getattr__``, ``__dir__`` and ``__all__`` of a package whose ``__init__`` lists its
    public names under ``if TYPE_CHECKING:`` (see the module docstring).

    Args:
        package: the package's ``__name__``.
        init_file: its ``__init__``'s ``__file__``, read for the list.
    """
    origins = listed_names(init_file)

    def __getattr__(name: str) -> object:
        if name not in origins:  # also how `from package import submodule` finds a submodule
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module, attribute = origins[name]
        value = getattr(importlib.import_module(module, package), attribute)
        setattr(sys.modules[package], name, value)  # found directly from now on
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *origins})

    return __getattr__, __dir__, sorted(origins)
