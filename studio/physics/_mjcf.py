"""A robot's URDF made readable by MuJoCo's URDF compiler.

MuJoCo compiles a URDF directly (``mujoco.MjSpec.from_string``) once three things are true of it:

- its meshes are files MuJoCo reads (binary STL or OBJ) at paths it can find: a relative
  reference is made absolute against the URDF's folder, and a mesh in another format (the
  Kinova's Collada ``.dae``, the Puma560's ASCII STL) is converted once with ``trimesh`` into the
  cache folder and referenced there;
- the ``<visual>`` elements are gone (the simulation collides the ``<collision>`` geometry only,
  and visual meshes are often Collada), and so are the ROS-only ``<gazebo>`` and
  ``<transmission>`` blocks;
- a ``<mujoco><compiler .../></mujoco>`` element inside ``<robot>`` keeps every link a body of its
  own (``fusestatic="false"``: the tool frame stays a body to measure) and every path whole
  (``strippath="false"``).

This module only rewrites text and converts meshes; :mod:`._model` compiles the result.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

from ._errors import PhysicsError

MUJOCO_MESHES = (".stl", ".obj")
"""The mesh formats MuJoCo reads itself (an STL in binary form only); any other is converted to
a binary STL."""

MIN_MASS_KG = 1e-3
"""The mass MuJoCo gives a moving link whose URDF states none (``boundmass``): enough to compile
a kinematics-only URDF (the Puma560's from its DH table) and too little to matter beside a real
link's."""

MIN_INERTIA_KG_M2 = 1e-6
"""The rotational inertia given likewise (``boundinertia``)."""

_DROPPED = re.compile(r"\s*<(visual|gazebo|transmission)\b.*?</\1>", re.S)
_MESH = re.compile(r'(<mesh\b[^>]*\bfilename=")([^"]+)(")')
_COMPILER = (
    '<mujoco><compiler strippath="false" fusestatic="false" discardvisual="true" '
    f'balanceinertia="true" boundmass="{MIN_MASS_KG}" boundinertia="{MIN_INERTIA_KG_M2}"/>'
    "</mujoco>"
)


def mujoco_reads(path: Path) -> bool:
    """Whether MuJoCo reads the mesh file ``path`` itself: an OBJ, or an STL in binary form (it
    refuses an ASCII STL, the form of rtb-data's Puma560 links). A binary STL is an 80-byte
    header, a face count, and 50 bytes a face: its size says which it is."""
    suffix = path.suffix.lower()
    if suffix not in MUJOCO_MESHES:
        return False
    if suffix != ".stl":
        return True
    try:
        with path.open("rb") as file:
            head = file.read(84)
        size = path.stat().st_size
    except OSError:
        return True  # unreadable: the compile says so in its own sentence
    faces = int.from_bytes(head[80:84], "little") if len(head) == 84 else -1
    return size == 84 + 50 * faces


def converted_mesh(source: Path, cache: Path) -> Path:
    """``source`` as an STL file under ``cache`` (converted once, kept by its content's hash).

    Raises:
        PhysicsError: the mesh cannot be read or the cache cannot be written.
    """
    import trimesh

    try:
        digest = hashlib.sha256(source.read_bytes()).hexdigest()[:16]
    except OSError as err:
        raise PhysicsError(
            f"The mesh {source} cannot be read ({err.strerror or err}); reinstall the robot's "
            "description (example-robot-data)."
        ) from None
    target = cache / f"{source.stem}-{digest}.stl"
    if target.is_file():
        return target
    try:
        mesh = trimesh.load(source, force="mesh")
        cache.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(f".{target.name}.{os.getpid()}")
        mesh.export(partial, file_type="stl")
        partial.replace(target)  # a converted mesh appears whole or not at all
    except OSError as err:
        raise PhysicsError(
            f"Cannot write the converted mesh {target} ({err.strerror or err}); give a writable "
            "data folder (--data-dir)."
        ) from None
    except ValueError as err:
        raise PhysicsError(
            f"The mesh {source} cannot be converted for MuJoCo ({err}); reinstall the robot's "
            "description (example-robot-data)."
        ) from None
    return target


def mujoco_urdf(urdf: Path, cache: Path) -> str:
    """The text of the URDF file ``urdf`` as MuJoCo compiles it (see the module docstring).

    Args:
        urdf: a URDF whose mesh references are absolute or relative to its folder (as
            ``studio export-urdf --robot NAME`` writes it).
        cache: where converted meshes are kept.

    Raises:
        PhysicsError: the URDF or a mesh cannot be read, or a converted mesh cannot be written.
    """
    try:
        text = urdf.read_text(encoding="utf-8")
    except OSError as err:
        raise PhysicsError(
            f"The URDF {urdf} cannot be read ({err.strerror or err}); write it again with "
            "`studio export-urdf --robot NAME --out DIR`."
        ) from None
    text = _DROPPED.sub("", text)

    def readable(match: re.Match[str]) -> str:
        path = Path(match.group(2).removeprefix("file://"))
        path = path if path.is_absolute() else urdf.parent / path
        if not mujoco_reads(path):
            path = converted_mesh(path, cache)
        return f"{match.group(1)}{path}{match.group(3)}"

    text = _MESH.sub(readable, text)
    head, tail = text.rsplit("</robot>", 1)
    return f"{head}  {_COMPILER}\n</robot>{tail}"
