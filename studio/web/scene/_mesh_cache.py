"""The drawn robots' simplified meshes, kept under the data folder so that a robot is read and
simplified once, not at every start.

Reading a robot's URDF meshes (``.dae`` and ``.stl``, through trimesh) and simplifying them takes
0.1-2 s per robot; the simplified parts are small (a few thousand vertices), so they are kept in
``<data>/cache/meshes/<robot>-<key>.npz``, an uncompressed archive. The key is a hash of what the
parts are made from (each mesh file's path, size and modification time, the simplification and
the scale, and the model whose frames the parts are attached to), so an updated mesh package,
another model or another setting is read afresh. A cache file is only ever a copy: one that is
damaged, too large or compressed, malformed, holding NaN, or attaching a part to a frame the model
does not have is ignored and written again.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import os
import zipfile
from collections.abc import Callable, Collection, Sequence
from pathlib import Path

import numpy as np

from studio import read_bytes_bounded
from studio._files import atomic_write
from studio.kinematics import MeshPart

log = logging.getLogger(__name__)

CACHE_VERSION = 2
"""Bumped when the parts' layout in a cache file, or what its key covers, changes."""
MAX_CACHE_BYTES = 32 * 1024 * 1024
"""The largest cache file read (the biggest robot's simplified parts take well under 1 MB)."""


def mesh_key(files: Sequence[str], *settings: object) -> str:
    """A hash of the mesh files (path, size, modification time) and the ``settings``."""
    stamp: list[object] = [CACHE_VERSION, *settings]
    for name in files:
        try:
            st = os.stat(name)
            stamp.append((name, st.st_size, st.st_mtime_ns))
        except OSError:
            stamp.append((name, None))
    return hashlib.sha256(json.dumps(stamp, default=str).encode()).hexdigest()[:20]


def cached_parts(
    folder: Path | None,
    name: str,
    key: str,
    build: Callable[[], list[MeshPart]],
    frames: Collection[int | str] | None = None,
) -> list[MeshPart]:
    """The parts cached under ``folder`` for ``name`` and ``key``, else ``build()``'s, cached.

    Never fails for the cache's sake: a cache that cannot be read or written is logged and
    the parts are built (``folder`` None: no cache).

    Args:
        frames: the frames a part may be attached to (None: any); a cached part attached to
            another one is damage, for the scene would fail on every frame drawing it.
    """
    if folder is None:
        return build()
    path = folder / f"{name}-{key}.npz"
    if path.is_file():
        try:
            return _read(path, frames)
        except Exception as err:  # noqa: BLE001 (whatever a damaged copy raises: built again)
            log.warning(
                "The mesh cache %s is ignored (%s: %s); it is written again.",
                path,
                type(err).__name__,
                err,
            )
    parts = build()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        atomic_write(path, lambda stream: _write(stream, parts))
    except OSError as err:
        log.warning(
            "The mesh cache %s cannot be written (%s); meshes are read each time.", path, err
        )
    return parts


def _write(stream: io.BufferedIOBase, parts: list[MeshPart]) -> None:
    meta = [{"name": p.name, "frame": p.frame, "rgb": list(p.rgb)} for p in parts]
    arrays: dict[str, np.ndarray] = {"meta": np.array(json.dumps(meta))}
    for i, p in enumerate(parts):
        arrays[f"v{i}"] = np.asarray(p.vertices, dtype=np.float32)
        arrays[f"f{i}"] = np.asarray(p.faces, dtype=np.uint32)
    np.savez(stream, **arrays)  # stored, not deflated: what is read is what is on disk


def _read(path: Path, frames: Collection[int | str] | None = None) -> list[MeshPart]:
    """The parts of a cache file, each checked as :func:`_write` wrote it.

    Raises:
        StudioError, OSError, ValueError, KeyError, zipfile.BadZipFile: the file is damaged.
    """
    data = read_bytes_bounded(path, MAX_CACHE_BYTES, f"the mesh cache {path.name}")
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        if any(info.compress_type != zipfile.ZIP_STORED for info in archive.infolist()):
            raise ValueError("a member is compressed")
    with np.load(io.BytesIO(data), allow_pickle=False) as npz:
        meta = json.loads(str(npz["meta"]))
        if not isinstance(meta, list) or not meta:
            raise ValueError("its part list is not a list of parts")
        parts = []
        for i, m in enumerate(meta):
            v = np.asarray(npz[f"v{i}"], dtype=np.float32).reshape(-1, 3)
            f = np.asarray(npz[f"f{i}"], dtype=np.uint32).reshape(-1, 3)
            parts.append(_part(i, m, v, f, frames))
    return parts


def _part(
    i: int, m: object, v: np.ndarray, f: np.ndarray, frames: Collection[int | str] | None
) -> MeshPart:
    """Part ``i`` of a cache file from its entry ``m`` of the part list and its arrays.

    Raises:
        ValueError: a malformed entry, NaN or infinite vertices, a face past the vertices, or a
            frame not among ``frames``.
    """
    if not isinstance(m, dict) or not isinstance(m.get("name"), str):
        raise ValueError(f"part {i} is not a named part")
    frame, rgb = m.get("frame"), m.get("rgb")
    if not (isinstance(frame, str) or (isinstance(frame, int) and not isinstance(frame, bool))):
        raise ValueError(f"part {i} is attached to {frame!r}, not a frame")
    if frames is not None and frame not in frames:
        raise ValueError(f"part {i} is attached to frame {frame!r}, which the model does not have")
    if not (
        isinstance(rgb, list)
        and len(rgb) == 3
        and all(isinstance(c, int | float) and not isinstance(c, bool) and 0 <= c <= 1 for c in rgb)
    ):
        raise ValueError(f"part {i}'s colour is not three numbers from 0 to 1")
    if not np.isfinite(v).all():
        raise ValueError(f"part {i} holds NaN or infinite vertices")
    if len(f) and int(f.max()) >= len(v):
        raise ValueError(f"part {i} indexes a vertex it does not have")
    r, g, b = (float(c) for c in rgb)
    return MeshPart(m["name"], frame, v, f, (r, g, b))
