"""The one bounded JSON reader: every JSON text the studio reads goes through :func:`loads_json`
(and every TOML file through :func:`read_toml`).

Python's ``json`` parser recurses once per nesting level, so ``[[[...]]]`` 50,000 deep raises a
``RecursionError`` (a 500 in the API, a traceback in the CLI), and a file of any size is parsed
whole. Before parsing, this module refuses a text longer than its limit and measures the nesting
depth without recursion (strings blanked out by one regular expression, then a running count of
brackets in numpy), so a hostile file costs one linear scan and one clear sentence.

No studio file nests deeper than a handful of levels (a recording header's ``tape.base`` 4x4
matrix is the deepest, at four), so :data:`MAX_JSON_DEPTH` leaves ample room.
"""

from __future__ import annotations

import functools
import json
import os
import re
import tomllib
from pathlib import Path
from typing import TYPE_CHECKING

from ._errors import StudioError
from ._files import human_size, read_bytes_bounded

if TYPE_CHECKING:
    import numpy as np

MAX_JSON_BYTES = 64 * 1024 * 1024
"""Largest JSON file read (a demonstration of a long recording is a few MB)."""
MAX_JSON_DEPTH = 64
"""Deepest nesting of arrays and objects accepted (studio files use at most four or five)."""
MAX_TOML_BYTES = 1024 * 1024
"""Largest TOML file read (sweep specs are a few hundred bytes)."""

_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
"""A JSON string literal (escapes included), blanked before brackets are counted."""
_SURROGATE_ESCAPE = re.compile(rb"\\u[dD][89a-fA-F]")
"""A JSON escape of a UTF-16 surrogate: the only way a JSON text can hold an unpaired one."""
_SURROGATE = re.compile("[\ud800-\udfff]")
"""An unpaired surrogate in a Python string (a shell's non-UTF-8 byte, or a lone JSON escape)."""


class JSONFileError(StudioError, ValueError):
    """JSON that is too large, nested too deeply, or not valid; the message names the file.

    It is also a :class:`ValueError` (as ``json.JSONDecodeError`` is), so existing handlers of
    bad JSON keep working.
    """


class TOMLFileError(StudioError, ValueError):
    """A TOML file that is nested too deeply or not valid; the message names the file."""


@functools.cache
def _bracket_steps() -> np.ndarray:
    """Each byte's step in nesting depth: +1 for ``[`` and ``{``, -1 for ``]`` and ``}``, else 0."""
    import numpy as np

    steps = np.zeros(256, dtype=np.int8)
    steps[[ord("["), ord("{")]] = 1
    steps[[ord("]"), ord("}")]] = -1
    return steps


def nesting_depth(text: str | bytes) -> int:
    """The deepest nesting of ``[]``/``{}`` in a JSON text, outside string literals, without recursion."""
    # numpy is imported here, not with the module: every `studio` command imports this module
    # (through `studio`), and its --help and usage errors must not wait for numpy.
    import numpy as np

    data = text.encode("utf-8", errors="surrogatepass") if isinstance(text, str) else bytes(text)
    steps = _bracket_steps()[np.frombuffer(_STRING.sub(b'""', data), dtype=np.uint8)]
    moves = steps[np.flatnonzero(steps)]
    if moves.size == 0:
        return 0
    return int(np.cumsum(moves, dtype=np.int64).max())


def loads_json(
    text: str | bytes,
    what: str = "the JSON text",
    *,
    max_bytes: int = MAX_JSON_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
) -> object:
    """Parse JSON after checking its size and nesting depth.

    Args:
        text: the JSON text (``bytes`` are decoded as UTF-8).
        what: what the text is (``"recording x.tape.csv, line 1"``), for the error sentence.
        max_bytes: the longest text accepted.
        max_depth: the deepest nesting accepted.

    Returns:
        The parsed value (a dict, list, str, int, float, bool or None: the caller checks which).

    Raises:
        JSONFileError: the text is too long, too deeply nested, not UTF-8 or not valid JSON.
    """
    if len(text) > max_bytes:
        raise JSONFileError(
            f"{what} holds {human_size(len(text))} of JSON, more than the {human_size(max_bytes)} "
            "allowed; check that it is the right file."
        )
    depth = nesting_depth(text)
    if depth > max_depth:
        raise JSONFileError(
            f"{what} nests JSON {depth} levels deep, more than the {max_depth} allowed; it is "
            "damaged or not a Teach Studio file."
        )
    try:
        value = json.loads(text)
    except UnicodeDecodeError:
        raise JSONFileError(f"{what} is not UTF-8 text; it is damaged or not JSON.") from None
    except json.JSONDecodeError as err:
        raise JSONFileError(
            f"{what} is not valid JSON ({err.msg} at line {err.lineno} column {err.colno}); "
            "fix or re-export it."
        ) from None
    except (ValueError, RecursionError) as err:  # e.g. an integer of more than 4300 digits
        raise JSONFileError(f"{what} is not usable JSON ({err}); fix or re-export it.") from None
    raw = text.encode("utf-8", errors="surrogatepass") if isinstance(text, str) else bytes(text)
    if _SURROGATE_ESCAPE.search(raw):  # a text stored before such names were refused
        value = _replace_surrogates(value)
    return value


def unpaired_surrogate(value: object, where: str = "") -> tuple[str, str] | None:
    """Where a parsed value holds a string that is not text: ``(path, string)`` or None.

    An unpaired UTF-16 surrogate (a byte a non-UTF-8 shell passed, or a lone ``\\udce9`` escape in
    JSON) cannot be written as UTF-8, so a name holding one would break every answer that lists it.

    Args:
        value: a string, or parsed JSON (lists and dicts, keys included).
        where: the path of ``value`` (``"name"``, ``"tags.2"``), for the caller's sentence.
    """
    stack = [(value, where)]
    while stack:
        item, path = stack.pop()
        if isinstance(item, str):
            if _SURROGATE.search(item):
                return path, item
        elif isinstance(item, dict):
            for key, child in item.items():
                inner = f"{path}.{key}" if path else str(key)
                stack.extend([(child, inner), (key, inner)])
        elif isinstance(item, list | tuple):
            stack.extend((child, f"{path}.{i}" if path else str(i)) for i, child in enumerate(item))
    return None


def _replace_surrogates(value: object) -> object:
    """``value`` with each unpaired surrogate replaced by U+FFFD, so it can be shown and saved."""
    if isinstance(value, str):
        return _SURROGATE.sub("\ufffd", value)
    if isinstance(value, dict):
        return {_replace_surrogates(k): _replace_surrogates(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_replace_surrogates(item) for item in value]
    return value


def read_json(
    path: str | os.PathLike[str],
    what: str | None = None,
    *,
    max_bytes: int = MAX_JSON_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
) -> object:
    """Read a JSON file: a regular file of at most ``max_bytes``, nested at most ``max_depth`` deep.

    Args:
        path: the file.
        what: what the file is, for error sentences (default: its path).
        max_bytes: the largest file accepted.
        max_depth: the deepest nesting accepted.

    Raises:
        FileLimitError: missing, not a regular file, or too large (nothing is read then).
        JSONFileError: not UTF-8, too deep or not valid JSON.
    """
    label = what or str(Path(path))
    return loads_json(
        read_bytes_bounded(path, max_bytes, label),
        label,
        max_bytes=max_bytes,
        max_depth=max_depth,
    )


def read_toml(
    path: str | os.PathLike[str],
    what: str | None = None,
    *,
    max_bytes: int = MAX_TOML_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
) -> dict[str, object]:
    """Read a TOML file: a regular file of at most ``max_bytes``, tables nested at most ``max_depth``.

    ``tomllib`` recurses on nested inline arrays and tables (a ``RecursionError`` on hostile
    input), and dotted keys can build arbitrarily deep tables without recursing; both are refused.

    Raises:
        FileLimitError: missing, not a regular file, or too large (nothing is read then).
        TOMLFileError: not UTF-8, not valid TOML, or nested too deeply.
    """
    label = what or str(Path(path))
    data = read_bytes_bounded(path, max_bytes, label)
    try:
        value = tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise TOMLFileError(f"{label} is not UTF-8 text; it is damaged or not TOML.") from None
    except tomllib.TOMLDecodeError as err:
        raise TOMLFileError(f"{label} is not valid TOML ({err}); fix it.") from None
    except RecursionError:
        value = None
    if value is None or value_depth(value, max_depth + 1) > max_depth:
        raise TOMLFileError(
            f"{label} nests tables or arrays more than {max_depth} levels deep; it is damaged or "
            "not a Teach Studio file."
        )
    return value


def value_depth(value: object, stop: int | None = None) -> int:
    """Nesting depth of parsed lists and dicts (a scalar is 0), without recursion.

    Args:
        value: a parsed JSON or TOML value.
        stop: give up (returning ``stop``) once this depth is reached.
    """
    deepest = 0
    stack = [(value, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            children = list(item.values())
        elif isinstance(item, list | tuple):
            children = list(item)
        else:
            continue
        deepest = max(deepest, depth + 1)
        if stop is not None and deepest >= stop:
            return stop
        stack.extend((child, depth + 1) for child in children)
    return deepest
