"""A robot's URDF as a folder that loads anywhere: ``<name>.urdf`` and ``meshes/``.

Mesh references (``package://example-robot-data/robots/...`` in example-robot-data's URDFs) are
copied under ``meshes/`` and rewritten relative to the URDF, so RViz, Pinocchio, yourdfpy or
Foxglove load the folder without a ROS package path. The URDF is the one the studio's model and
checks are built from (:attr:`RobotArm.urdf_text`): continuous joints bounded to +-2 pi and
joint names the exported trajectories use (the Puma560's is generated from its DH table, with
the link meshes of ``rtb-data``, the scene's).

The folder is built next to ``out`` and renamed into place; a mesh that cannot be found refuses
the export with one sentence and leaves nothing behind.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from studio._files import make_temp_dir
from studio.kinematics import RobotArm, load_robot

from ._errors import ExportError

MESH_DIR = "meshes"
_MESH = re.compile(r'(<mesh\b[^>]*\bfilename=")([^"]+)(")')


def _resolve(reference: str, share: Path, base: Path | None) -> Path:
    """The file a URDF mesh reference names (``package://pkg/rest``, ``file://``, or relative)."""
    if reference.startswith("package://"):
        return share / reference.removeprefix("package://")
    if reference.startswith("file://"):
        return Path(reference.removeprefix("file://"))
    path = Path(reference)
    return path if path.is_absolute() or base is None else base / path


def portable_urdf(
    urdf_text: str,
    share: Path,
    folder: Path,
    base: Path | None = None,
    package: str = "example-robot-data",
) -> tuple[str, list[Path]]:
    """``urdf_text`` with every mesh copied into ``folder/meshes`` and referenced relatively.

    Args:
        urdf_text: the URDF.
        share: the folder ``package://`` references are relative to.
        folder: where the URDF will live (the meshes go to ``folder/meshes/...``).
        base: the folder relative references are relative to (default: none allowed).
        package: the installed package the meshes come from, named when one is missing.

    Returns:
        The rewritten URDF and the meshes copied.

    Raises:
        ExportError: the URDF names no mesh, or a mesh file is missing.
    """
    copied: dict[str, Path] = {}
    missing: list[str] = []

    def rewrite(match: re.Match[str]) -> str:
        reference = match.group(2)
        source = _resolve(reference, share, base)
        if not source.is_file():
            missing.append(reference)
            return match.group(0)
        parts = source.parts
        tail = Path(*parts[parts.index("robots") + 1 :]) if "robots" in parts else Path(source.name)
        relative = Path(MESH_DIR) / tail
        if reference not in copied:
            target = folder / relative
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target)
            copied[reference] = target
        return f"{match.group(1)}{relative.as_posix()}{match.group(3)}"

    text = _MESH.sub(rewrite, urdf_text)
    if missing:
        raise ExportError(
            f"The URDF names the mesh {missing[0]}, which is not installed"
            f"{f' ({len(missing) - 1} more missing)' if len(missing) > 1 else ''}; reinstall the "
            f"robot's description ({package}) so the exported folder can draw it."
        )
    if not copied:
        raise ExportError(
            "The URDF names no mesh; a robot without meshes cannot be drawn elsewhere: choose a "
            "robot from `studio robots`."
        )
    return text, list(copied.values())


def _share(arm: RobotArm) -> Path:
    """The folder ``package://`` references of ``arm``'s URDF resolve against, found from the
    mesh paths Pinocchio resolved when it loaded the model."""
    tails = [m.group(2).removeprefix("package://") for m in _MESH.finditer(arm.urdf_text)]
    tails = [t for t in tails if t]
    for model in (arm.visual_model, arm.collision_model):
        for obj in model.geometryObjects:
            path = str(obj.meshPath)
            for tail in tails:
                if path.endswith(tail):
                    return Path(path[: -len(tail)])
    return Path("/nonexistent")  # every reference then reads as missing: one sentence below


def export_urdf(robot: RobotArm | str, out: Path) -> Path:
    """Write ``out/<robot>.urdf`` and ``out/meshes/`` for ``robot``.

    Raises:
        ExportError: ``out`` is a file or a non-empty folder, a mesh is missing, or the folder
            cannot be written.
        KinematicsError: an unknown robot name.
    """
    arm = load_robot(robot) if isinstance(robot, str) else robot
    if out.is_file() or (out.is_dir() and any(out.iterdir())):
        raise ExportError(
            f"{out} already exists and is not an empty folder; give a new folder for the URDF "
            "and its meshes (nothing was written)."
        )
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = make_temp_dir(f".{out.name}.", out.parent)
    except OSError as err:
        raise ExportError(
            f"Cannot write the folder {out} ({err.strerror or err}); choose a writable --out."
        ) from None
    try:
        portable, _ = portable_urdf(arm.urdf_text, _share(arm), tmp, package=arm.spec.package)
        (tmp / f"{arm.name}.urdf").write_text(portable, encoding="utf-8")
        if out.is_dir():
            out.rmdir()
        tmp.rename(out)
    except OSError as err:
        raise ExportError(
            f"Cannot write the folder {out} ({err.strerror or err}); choose a writable --out."
        ) from None
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return out / f"{arm.name}.urdf"
