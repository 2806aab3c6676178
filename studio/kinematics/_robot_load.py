"""Loading a robot: its model and geometry, once per process, and off the process's lock when
other threads must keep running.

:func:`load_robot` builds a :class:`RobotArm` from the robot's URDF (Pinocchio), reads its meshes
(visual and collision) and computes the collision meshes' convex hulls (coal), then keeps it for
the rest of the process. Pinocchio and coal keep Python's lock (the GIL) while they read meshes
and compute hulls: 0.5-3 s for one robot, during which no other thread of the process runs. In a
server that froze the API and the scene at every first switch to a robot. After
:func:`isolate_robot_loading` (``studio serve`` calls it), the geometry is built in a child
process and handed back in Pinocchio's binary archives: this process waits without the lock and
holds it only to read them and set up the arm (a few tenths of a second at most;
``benchmarks/bench_robot_switch.py`` measures the API's latency during a switch both ways).

Given a cache folder (``studio serve`` keeps one under its data folder), the archives a child
wrote are kept there, one folder per robot, under a key of what they are built from (the URDF's
text, the versions of Pinocchio, Coal and example-robot-data); a robot is then built once per
machine, and later switches to it (in this process or another) read the archives in tens of
milliseconds without a child. A kept archive is read only when its SHA-256 matches the one
written beside it; anything else in the cache is ignored and built afresh.

The visual meshes are read from their files when the scene draws them or a URDF is exported
(``GeometryObject.meshPath``); the triangles Pinocchio loaded for them are never queried, so they
are dropped once the model is built, which also keeps the archives small.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from ._chain_ik import LinkPoints
from ._checks import KinematicsError
from ._robots import RobotArm, RobotSpec, robot_spec, robots_folder

log = logging.getLogger(__name__)

LOAD_TIMEOUT_S = 600.0
"""The longest a child process may take to build a robot's geometry (a first load takes seconds)."""

_arms: dict[tuple[str, bool], RobotArm] = {}
_locks: dict[tuple[str, bool], threading.Lock] = {}
_guard = threading.Lock()
_isolated = threading.Event()
_cache: list[Path] = []  # the cache folder isolate_robot_loading was given (none: no cache)
CACHE_VERSION = 1
"""Bumped when what a cache folder holds changes."""
_MANIFEST = "sha256.json"
"""The file of a kept robot naming each archive's SHA-256 (a kept folder appears whole: it is
written aside and renamed into place)."""

_CHILD = "from studio.kinematics._robot_load import _build_for_parent; _build_for_parent()"
_PARTS = ("model", "visual", "collision")
"""The files a child writes, one Pinocchio binary archive each."""
_REFUSED = "refused.txt"
"""The file a child writes instead: the sentence of the error that refused the robot."""


_CONTINUOUS = re.compile(r'(<joint\b[^>]*\btype=")continuous(")')


def _bounded_urdf(text: str) -> str:
    """``text`` with every ``continuous`` joint made ``revolute`` with limits of +-2 pi.

    Pinocchio gives a continuous joint two coordinates (cos, sin); one angle per joint is what
    limits, trajectories and exports speak, and +-2 pi is a full turn each way.
    """

    def revolute(match: re.Match[str]) -> str:
        return f"{match.group(1)}revolute{match.group(2)}"

    text = _CONTINUOUS.sub(revolute, text)
    links = set(re.findall(r'<link\s+name="([^"]+)"', text))
    for name in set(re.findall(r'<joint\s+name="([^"]+)"', text)) & links:
        # A joint named like a link (SO-100's "gripper") makes Pinocchio's frame lookups ambiguous.
        text = text.replace(f'<joint name="{name}"', f'<joint name="{name}_joint"')

    def add_limit(joint: re.Match[str]) -> str:
        body = joint.group(0)
        if 'type="revolute"' not in body:
            return body
        limit = re.search(r"<limit\b[^>]*/>", body)
        bounds = f'lower="{-2 * math.pi:.6f}" upper="{2 * math.pi:.6f}"'
        if limit is None:
            return body.replace(
                "</joint>", f'<limit {bounds} effort="100" velocity="1.0"/></joint>'
            )
        if "lower=" in limit.group(0):
            return body
        return body.replace(limit.group(0), limit.group(0).replace("<limit", f"<limit {bounds}"))

    return re.sub(r"<joint\b.*?</joint>", add_limit, text, flags=re.S)


def isolate_robot_loading(cache: Path | None = None) -> None:
    """From now on in this process, build a robot's geometry in a child process (see the module
    docstring): for a process whose other threads must not stall, such as a server's.

    Args:
        cache: a folder where each robot's built geometry is kept, so that it is built once per
            machine (safe to delete; None: nothing kept).
    """
    keep_robot_geometry(cache)
    _isolated.set()


def keep_robot_geometry(cache: Path | None) -> None:
    """From now on in this process, read each robot's built geometry from the folder ``cache``
    when it keeps it, and keep it there after a build (built in this process, unless
    :func:`isolate_robot_loading`): for a process that loads robots on a studio's behalf, such
    as its planning's child (None: nothing kept)."""
    _cache[:] = [] if cache is None else [Path(cache)]


def robot_cache_folder() -> Path | None:
    """The cache folder :func:`isolate_robot_loading` was given (None: none), for a child
    process that loads robots on this one's behalf: given it, the child reads the geometry kept
    there instead of building it again."""
    return _cache[0] if _cache else None


def robot_is_kept(name: str) -> bool:
    """Whether loading ``name`` with its geometry is quick: it is loaded in this process already,
    or the cache folder :func:`isolate_robot_loading` was given keeps its built geometry. Otherwise its first load builds its collision hulls (a minute or more on
    a busy machine), which is worth telling a person who waits."""
    spec = robot_spec(name)
    if (spec.name, True) in _arms:
        return True
    kept = _cache_entry(spec, _urdf_text(spec))
    return kept is not None and kept.is_dir()


def load_robot(name: str, geometry: bool = True) -> RobotArm:
    """The :class:`RobotArm` for ``name``, loaded once per process.

    Args:
        name: one of :func:`robot_names`.
        geometry: load the meshes too (a second or more per robot; needed for drawing and for
            :meth:`RobotArm.self_collisions`). Without them the model is ready in milliseconds,
            enough for limits, FK and IK.

    Raises:
        KinematicsError: an unknown name, or a model whose files are missing or unreadable.
    """
    spec = robot_spec(name)
    key = (spec.name, geometry)
    with _guard:
        arm = _arms.get(key)
        if arm is not None:
            return arm
        lock = _locks.setdefault(key, threading.Lock())
    with lock:  # a second thread asking meanwhile waits for this load, not another
        arm = _arms.get(key)
        if arm is None:
            arm = _load(spec, geometry)
            with _guard:
                _arms[key] = arm
    return arm


def _load(spec: RobotSpec, geometry: bool) -> RobotArm:
    text = _urdf_text(spec)
    if geometry and _isolated.is_set():
        model, visual, collision = _built_in_child(spec, text)
    elif geometry and _cache:
        model, visual, collision = _built_kept(spec, text)
    else:
        model, visual, collision = _built(spec, text, geometry)
    srdf = robots_folder() / spec.srdf if spec.srdf else None
    return RobotArm(spec, model, visual, collision, text, srdf)


def _urdf_text(spec: RobotSpec) -> str:
    if spec.generate is not None:
        return _bounded_urdf(spec.generate())
    urdf_path = robots_folder() / spec.urdf
    try:
        return _bounded_urdf(urdf_path.read_text())
    except OSError as err:
        raise KinematicsError(
            f"The {spec.title} URDF {urdf_path} cannot be read ({err.strerror}); reinstall "
            "example-robot-data."
        ) from None


def _built(
    spec: RobotSpec, text: str, geometry: bool
) -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel]:
    """The arm's reduced model, its visual geometry (mesh files, no triangles) and its collision
    geometry (convex hulls), from the URDF ``text``."""
    package_dirs = _package_dirs()
    try:
        model = pin.buildModelFromXML(text)
        if geometry:
            geoms = [
                pin.buildGeomFromUrdfString(model, text, kind, None, package_dirs, loader)
                for kind, loader in (
                    (pin.GeometryType.VISUAL, _visual_mesh_loader()),
                    (pin.GeometryType.COLLISION, None),
                )
            ]
        else:
            geoms = [pin.GeometryModel(), pin.GeometryModel()]
    except (RuntimeError, ValueError) as err:
        raise KinematicsError(
            f"The {spec.title} model cannot be built ({err}); its URDF or meshes are missing: "
            f"reinstall {spec.package}."
        ) from None
    model, (visual, collision) = _reduce(model, geoms, spec.arm_joints)
    _convex(collision)
    _drop_triangles(visual)
    return model, visual, collision


Parts = tuple[pin.Model, pin.GeometryModel, pin.GeometryModel]


def _built_in_child(spec: RobotSpec, text: str) -> Parts:
    """:func:`_built` in a child process, handed back in Pinocchio's binary archives (read in
    tens of milliseconds, a tenth of its pickles' text archives); this thread waits without
    Python's lock. In this process after all when no child can be started. Read from the cache
    folder instead when it keeps this robot, and kept there after a build."""
    kept = _cache_entry(spec, text)
    if kept is not None:
        parts = _read_kept(kept)
        if parts is not None:
            return parts
    with tempfile.TemporaryDirectory(prefix="studio-robot-") as folder:
        try:
            done = subprocess.run(
                [sys.executable, "-c", _CHILD, spec.name, folder],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                timeout=LOAD_TIMEOUT_S,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise KinematicsError(
                f"Loading the {spec.title} model took over {LOAD_TIMEOUT_S:.0f} s and was given "
                f"up; try again, or reinstall {spec.package} if it stays so."
            ) from None
        except OSError as err:  # no child process here: load it in this one, holding the lock
            log.warning("the %s model loads in this process: %s", spec.name, err)
            return _built(spec, text, True)
        files = [Path(folder) / f"{part}.bin" for part in _PARTS]
        refused = Path(folder) / _REFUSED
        if done.returncode == 0 and refused.is_file():
            raise KinematicsError(refused.read_text())
        if done.returncode != 0 or not all(f.is_file() for f in files):
            last = done.stderr.decode(errors="replace").strip().splitlines()[-1:] or ["no message"]
            raise KinematicsError(
                f"The {spec.title} model could not be built: its loading process ended with "
                f"code {done.returncode} ({last[0]}); reinstall {spec.package}."
            )
        parts = _read_archives(files)
        if kept is not None:
            _keep(kept, files)
    return parts


def _built_kept(spec: RobotSpec, text: str) -> Parts:
    """:func:`_built` in this process, read from the cache folder when it keeps this robot, and
    kept there after a build."""
    kept = _cache_entry(spec, text)
    parts = None if kept is None else _read_kept(kept)
    if parts is not None:
        return parts
    parts = _built(spec, text, True)
    if kept is not None:
        with tempfile.TemporaryDirectory(prefix="studio-robot-") as folder:
            files = [Path(folder) / f"{part}.bin" for part in _PARTS]
            for part, file in zip(parts, files, strict=True):
                part.saveToBinary(str(file))
            _keep(kept, files)
    return parts


def _read_archives(files: list[Path]) -> Parts:
    model, visual, collision = pin.Model(), pin.GeometryModel(), pin.GeometryModel()
    for part, file in zip((model, visual, collision), files, strict=True):
        part.loadFromBinary(str(file))
    return model, visual, collision


def _cache_entry(spec: RobotSpec, text: str) -> Path | None:
    """The cache folder's place for ``spec``'s built geometry from its URDF ``text`` (None: no
    cache)."""
    if not _cache:
        return None
    from importlib import metadata

    import coal

    try:
        robots_version = metadata.version("example-robot-data")
    except metadata.PackageNotFoundError:
        robots_version = None
    stamp = [CACHE_VERSION, pin.__version__, coal.__version__, robots_version, spec.arm_joints]
    digest = hashlib.sha256(json.dumps(stamp).encode())
    digest.update(text.encode())
    return _cache[0] / f"{spec.name}-{digest.hexdigest()[:20]}"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _read_kept(folder: Path) -> Parts | None:
    """The geometry kept in ``folder``, or None when there is none or it does not match its
    hashes (it is then built again and kept anew)."""
    files = [folder / f"{part}.bin" for part in _PARTS]
    try:
        expected = json.loads((folder / _MANIFEST).read_text())
        if not isinstance(expected, dict) or any(expected.get(f.name) != _sha256(f) for f in files):
            raise ValueError("an archive does not match its SHA-256")
        return _read_archives(files)
    except FileNotFoundError:
        return None
    except Exception as err:  # noqa: BLE001 (a damaged archive raises what Pinocchio's reader
        # meets: RuntimeError, ValueError, or a MemoryError for a length it cannot allocate)
        log.warning(
            "the kept geometry in %s is ignored and built again: %s: %s",
            folder,
            type(err).__name__,
            err,
        )
        return None


def _keep(folder: Path, files: list[Path]) -> None:
    """Copy the archives a child wrote, and their hashes, into ``folder`` of the cache (written
    aside, then renamed into place); a cache that cannot be written (a full disk, no permission)
    is logged and skipped."""
    temporary = folder.with_name(f".{folder.name}.{os.getpid()}.{threading.get_ident()}")
    try:
        temporary.mkdir(parents=True, exist_ok=True)
        for file in files:
            shutil.copyfile(file, temporary / file.name)
        hashes = {file.name: _sha256(temporary / file.name) for file in files}
        (temporary / _MANIFEST).write_text(json.dumps(hashes))
        if folder.exists():
            shutil.rmtree(folder)  # a damaged one, read and refused above
        os.replace(temporary, folder)
    except OSError as err:
        log.warning(
            "the built geometry of %s is not kept (%s): it is built again next time",
            folder.name,
            err,
        )
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def _build_for_parent() -> None:
    """A child process's work: build the geometry of the robot ``sys.argv[1]`` and write it in
    the folder ``sys.argv[2]`` (:data:`_PARTS`, Pinocchio's binary archives), or there the
    sentence of the :class:`KinematicsError` that refused it (:data:`_REFUSED`)."""
    spec, folder = robot_spec(sys.argv[1]), Path(sys.argv[2])
    try:
        parts = _built(spec, _urdf_text(spec), True)
    except KinematicsError as err:
        (folder / _REFUSED).write_text(str(err))
        return
    for name, part in zip(_PARTS, parts, strict=True):
        part.saveToBinary(str(folder / f"{name}.bin"))


def _drop_triangles(visual: pin.GeometryModel) -> None:
    """Replace the visual meshes' loaded triangles by an empty shape: they are drawn and
    exported from their files, never queried (a finely meshed link holds megabytes)."""
    import coal  # Pinocchio's collision library, installed with it

    for obj in visual.geometryObjects:
        if obj.meshPath:
            obj.geometry = coal.Sphere(0.0)


def _visual_mesh_loader() -> object:
    """The mesh loader of the visual meshes: axis-aligned boxes around their triangles.

    The visual meshes are only drawn and exported, never queried for distances, so the tree
    built around their triangles can be the cheapest; Coal's default (oriented boxes and swept
    spheres) takes about twice as long on the finely meshed arms (SO-101: 4.4 s -> 1.7 s).
    """
    import coal  # Pinocchio's collision library, installed with it

    return coal.MeshLoader(coal.BV_AABB)


def _convex(geom: pin.GeometryModel) -> None:
    """Replace each collision mesh by its convex hull (qhull, through coal).

    Distances between hulls cost a fraction of mesh-to-mesh ones (a 5-joint SO-101 check drops
    from about a second to milliseconds), and a hull contains its mesh, so a clearance found on
    hulls holds for the meshes: the check errs on the safe side. The hull is computed, not
    assumed: coal's GJK walks a convex shape's vertex graph to find support points, and on a
    mesh taken as its own hull that walk stops at local extremes, so distances came out
    centimetres too large and changed from one query to the next.
    """
    for obj in geom.geometryObjects:
        shape = obj.geometry
        if hasattr(shape, "buildConvexHull"):
            shape.buildConvexHull(True, "Qt")
            obj.geometry = shape.convex


def _package_dirs() -> list[str]:
    """The folders a URDF's ``package://NAME/...`` meshes are looked up in: the one holding
    ``example-robot-data/`` and the site-packages folders (``rtbdata/``, the Puma560's)."""
    import sysconfig

    folders = [sysconfig.get_paths()[key] for key in ("purelib", "platlib")]
    with contextlib.suppress(KinematicsError):  # a robot that does not need them
        folders.insert(0, str(robots_folder().parent.parent))
    return list(dict.fromkeys(folders))


def _reduce(
    model: pin.Model, geoms: list[pin.GeometryModel], keep: int
) -> tuple[pin.Model, list[pin.GeometryModel]]:
    """The model with only its first ``keep`` joints free; the rest locked at a valid angle."""
    locked = list(range(keep + 1, model.njoints))
    if not locked:
        return model, geoms
    q_ref = np.clip(np.zeros(model.nq), model.lowerPositionLimit, model.upperPositionLimit)
    reduced, reduced_geoms = pin.buildReducedModel(model, geoms, locked, q_ref)
    return reduced, list(reduced_geoms)


def prepare_arm_ik() -> float:
    """Load (or, the first time on this machine, compile) the IK and table-check kernels;
    returns the seconds.

    The kernels are cached on disk: compiling them takes seconds (tens on a loaded machine),
    which would otherwise stall the first frame of the first arm chosen in the studio, and the
    first pose checked against its table.
    """
    start = time.perf_counter()
    arm = load_robot("puma560", geometry=False)
    arm.inverse(arm.forward(arm.home), arm.home, iterations=2)
    # no geometry: the table check's kernel compiles for the types every arm's geometry has
    LinkPoints.from_geometry(pin.GeometryModel(), []).heights(arm.chain, arm.home, 0.0)
    return time.perf_counter() - start


def prepare_arm_ik_in_background() -> threading.Thread:
    """Run :func:`prepare_arm_ik` in a child process (a compile holds its interpreter's GIL),
    waited for by the returned daemon thread. If the child cannot start, the first arm chosen
    compiles the kernel itself."""
    code = "from studio.kinematics._robot_load import prepare_arm_ik; prepare_arm_ik()"

    def child() -> None:
        with contextlib.suppress(OSError):
            subprocess.run(
                [sys.executable, "-c", code],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                check=False,
            )

    thread = threading.Thread(target=child, name="studio-prepare-ik", daemon=True)
    thread.start()
    return thread
