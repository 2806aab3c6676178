"""The ``studio`` command.

Each verb lives in its own module under :mod:`studio.commands` (``serve``, ``record``, ``reproduce``,
...). A verb module defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``;
this file only collects them, so adding a verb never touches another's code. With no verb,
``studio`` runs ``serve``.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import importlib
import os
import pkgutil
import re
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import ModuleType
from typing import NoReturn

from . import __version__, commands
from ._errors import StudioError
from ._json import unpaired_surrogate

DEFAULT_VERB = "serve"


def _verb_table() -> dict[str, tuple[str, str]]:
    """Each verb's name -> its module's name and its one-line help, read from the module's
    source without importing it: ``studio --help`` and a mistyped verb then cost none of the
    verbs' imports (Pinocchio, numba, SciPy: seconds), only the verb that runs is imported."""
    table: dict[str, tuple[str, str]] = {}
    folder = Path(commands.__path__[0])
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        found: dict[str, object] = {}
        for node in ast.parse((folder / f"{info.name}.py").read_text()).body:
            if isinstance(node, ast.Assign) and len(node.targets) == 1:
                target = node.targets[0]
                if isinstance(target, ast.Name) and target.id in ("NAME", "HELP"):
                    with contextlib.suppress(ValueError):
                        found[target.id] = ast.literal_eval(node.value)
        if not (isinstance(found.get("NAME"), str) and isinstance(found.get("HELP"), str)):
            module = _verb_module(info.name)  # not literal text: ask the module itself
            found = {"NAME": module.NAME, "HELP": module.HELP}
        table[str(found["NAME"])] = (info.name, str(found["HELP"]))
    return table


def _verb_module(name: str) -> ModuleType:
    return importlib.import_module(f"{commands.__name__}.{name}")


NUMBERS = re.compile(r"^-\.?\d[\d.,eE+\- ]*$")
"""A value that starts with a minus and holds only numbers: ``-30,45,-90``, ``-0.5``, ``-1e-3``."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line: the problem and where help is (not
    argparse's usage block, which buries the one line that matters).

    A value such as ``--goal-deg -30,45,-90`` is taken as the option's value, not as an unknown
    option: argparse itself only knows a lone negative number (``-30``) as a value.
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NUMBERS

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message}; see {self.prog} --help.\n")


def build_parser(
    verbs: Iterable[str] | None = None,
) -> tuple[argparse.ArgumentParser, dict[str, ModuleType]]:
    """The argument parser with one sub-parser per verb, and the verb modules it imported.

    Args:
        verbs: the verbs whose arguments are added (their modules imported); the others are
            listed with their help only. None: every verb.
    """
    parser = _Parser(
        prog="studio",
        description="Teach Studio: teach a robot arm by showing it a motion. "
        f"With no verb, runs `studio {DEFAULT_VERB}`.",
    )
    parser.add_argument("--version", action="version", version=f"teach-studio {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB")
    table = _verb_table()
    wanted = set(table) if verbs is None else set(verbs)
    modules: dict[str, ModuleType] = {}
    for name, (module_name, text) in table.items():
        verb_parser = sub.add_parser(name, help=text, description=text)
        if name in wanted:
            modules[name] = _verb_module(module_name)
            modules[name].add_arguments(verb_parser)
    return parser, modules


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``studio`` console script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0].startswith("-") and argv[0] not in ("-h", "--help", "--version")):
        argv = [DEFAULT_VERB, *argv]
    parser, modules = build_parser(argv[:1])
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        where = f"studio {args.verb}"
        parser.exit(
            2, f"{where}: unrecognized arguments: {' '.join(unknown)}; see {where} --help.\n"
        )
    broken = _broken_text(args)
    if broken is not None:
        parser.exit(2, f"studio {args.verb}: {broken}\n")
    try:
        return int(modules[args.verb].run(args) or 0)
    except StudioError as err:
        print(f"studio {args.verb}: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"studio {args.verb}: interrupted.", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader of our output went away (`studio info F | head`): not an error of ours.
        # Point stdout at /dev/null so the interpreter's final flush cannot fail again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


def _broken_text(args: argparse.Namespace) -> str | None:
    """The sentence refusing an argument that is not text (a shell's non-UTF-8 byte), or None.

    Such a name, stored in a run's or a recording's file, could never be shown as UTF-8. A path
    to an existing file is left alone: the operating system names it by those same bytes.
    """
    for dest, value in vars(args).items():
        found = unpaired_surrogate(value, "--" + dest.replace("_", "-"))
        if found is None or os.path.lexists(found[1]):
            continue
        option, text = found
        try:
            raw = text.encode("utf-8", errors="surrogateescape")
        except UnicodeEncodeError:  # a surrogate no shell byte stands for
            raw = text.encode("utf-8", errors="backslashreplace")
        given = raw.decode("ascii", "backslashreplace")
        return (
            f"{option.split('.')[0]} '{given}' is not UTF-8 text; type it again in a terminal set "
            "to UTF-8 (or with plain ASCII letters)."
        )
    return None


if __name__ == "__main__":
    raise SystemExit(main())
