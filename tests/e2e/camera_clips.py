"""Camera clips for the browser tests and the camera benchmark, made at run time (nothing committed).

Chromium plays a ``.y4m`` file as its fake camera (``--use-fake-device-for-media-stream
--use-file-for-fake-video-capture=FILE``) and loops it. The header needs the ``C420`` chroma tag
(``C420mpeg2`` is refused). Every frame carries its index in a small barcode in the top-left
corner, which the page reads back (:data:`READ_STAMP_JS`), so each result is matched to the frame
the pose model saw.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

WIDTH, HEIGHT = 640, 480
STAMP_BITS = 10
"""Frame-index bits in the stamp (clips up to 1,024 frames)."""
STAMP_CELL = 12
"""Side of one stamp cell in pixels: a white start cell, then the bits, black 0 and white 1."""
STAMP_Y = 6
"""Top of the stamp row in pixels."""

READ_STAMP_JS = f"""(frame) => {{
    // The frame index stamped in the top-left corner of a test clip (tests/e2e/camera_clips.py).
    const cell = {STAMP_CELL}, bits = {STAMP_BITS}, top = {STAMP_Y};
    const c = window.__stampCanvas || (window.__stampCanvas = document.createElement("canvas"));
    c.width = cell * (bits + 1); c.height = cell;
    const ctx = c.getContext("2d", {{ willReadFrequently: true }});
    const sx = frame.width / {WIDTH}, sy = frame.height / {HEIGHT};
    ctx.drawImage(frame, 0, top * sy, c.width * sx, cell * sy, 0, 0, c.width, cell);
    const px = ctx.getImageData(0, 0, c.width, cell).data;
    const at = (i) => {{ const o = 4 * (Math.floor(cell / 2) * c.width + i * cell + Math.floor(cell / 2)); return px[o + 1]; }};
    if (at(0) < 128) return null; // no start cell: not a stamped clip
    let n = 0;
    for (let b = 0; b < bits; b++) n |= (at(b + 1) >= 128 ? 1 : 0) << b;
    return n;
}}"""
"""A page-side function(canvas) -> the stamped frame index, or null (camera.js's ``probe``)."""

COLLECT_FRAMES_JS = f"""async () => {{
    window.__frames = [];
    const {{ S, listen }} = await import("/static/state.js");
    S.camera.probe = {READ_STAMP_JS};
    listen("landmarks", (frame) => window.__frames.push(frame));
}}"""
"""Run in the studio page: every answered frame, with the stamp of its picture, in ``__frames``."""


def stamp(rgb: np.ndarray, index: int) -> np.ndarray:
    """``rgb`` with ``index`` written in the top-left barcode."""
    out = rgb.copy()
    cells = [1] + [(index >> b) & 1 for b in range(STAMP_BITS)]
    for i, bit in enumerate(cells):
        x = i * STAMP_CELL
        out[STAMP_Y : STAMP_Y + STAMP_CELL, x : x + STAMP_CELL] = 255 if bit else 0
    return out


def rgb_to_i420(rgb: np.ndarray) -> bytes:
    """One frame as planar YUV 4:2:0 (BT.601, studio range), as y4m's ``C420`` stores it."""
    f = rgb.astype(np.float32)
    r, g, b = f[..., 0], f[..., 1], f[..., 2]
    y = 16 + (65.481 * r + 128.553 * g + 24.966 * b) / 255
    u = 128 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255
    v = 128 + (112.0 * r - 93.786 * g - 18.214 * b) / 255

    def half(p: np.ndarray) -> np.ndarray:
        return p.reshape(p.shape[0] // 2, 2, p.shape[1] // 2, 2).mean(axis=(1, 3))

    planes = [y, half(u), half(v)]
    return b"".join(np.clip(np.rint(p), 0, 255).astype(np.uint8).tobytes() for p in planes)


def write_y4m(path: Path, frames: Iterable[np.ndarray], fps: int, first: int = 0) -> Path:
    """Write RGB frames (HEIGHT, WIDTH, 3) uint8, each stamped with its index plus ``first``, as a
    y4m clip (clips stamped from different ``first`` tell apart which one the camera played)."""
    with path.open("wb") as out:
        out.write(f"YUV4MPEG2 W{WIDTH} H{HEIGHT} F{fps}:1 Ip A1:1 C420\n".encode())
        for index, rgb in enumerate(frames):
            assert rgb.shape == (HEIGHT, WIDTH, 3), rgb.shape
            assert first + index < 1 << STAMP_BITS, "the stamp holds no such index"
            out.write(b"FRAME\n")
            out.write(rgb_to_i420(stamp(rgb, first + index)))
    return path


def astronaut_clip(path: Path, frames: int = 30, fps: int = 10, first: int = 0) -> Path:
    """scikit-image's ``astronaut.png`` (a public-domain NASA portrait) centred in a 640x480 frame."""
    import skimage.data
    from PIL import Image

    photo = Image.fromarray(skimage.data.astronaut()).resize((HEIGHT, HEIGHT), Image.LANCZOS)
    canvas = np.full((HEIGHT, WIDTH, 3), 40, np.uint8)
    x0 = (WIDTH - HEIGHT) // 2
    canvas[:, x0 : x0 + HEIGHT] = np.asarray(photo)
    return write_y4m(path, (canvas for _ in range(frames)), fps, first)


def blank_clip(path: Path, frames: int = 10, fps: int = 10, first: int = 0) -> Path:
    """An empty grey room: no person in view."""
    canvas = np.full((HEIGHT, WIDTH, 3), 128, np.uint8)
    return write_y4m(path, (canvas for _ in range(frames)), fps, first)


# ---------------------------------------------------------------------------- the drawn figure

FIGURE_ELBOW_DEG = (170.0, 60.0)
"""The drawn right elbow's interior angle, arm hanging nearly straight -> bent and raised."""


def figure_elbow_deg(index: int, frames: int) -> float:
    """The drawn elbow angle of frame ``index`` of a figure clip: a smooth raise and lower, looped."""
    straight, bent = FIGURE_ELBOW_DEG
    phase = (1 - math.cos(2 * math.pi * index / frames)) / 2
    return straight + (bent - straight) * phase


def _capsule(
    draw: object, a: tuple[float, float], b: tuple[float, float], r: float, fill: str
) -> None:
    draw.line([a, b], fill=fill, width=int(2 * r))  # type: ignore[attr-defined]
    for x, y in (a, b):
        draw.ellipse([x - r, y - r, x + r, y + r], fill=fill)  # type: ignore[attr-defined]


def draw_figure(elbow_deg: float) -> np.ndarray:
    """A person facing the camera, drawn in capsules, with the right arm raised by ``elbow_deg``.

    The person's right arm is on the image's left. As the elbow bends from 170 to 60 degrees the
    upper arm lifts sideways from 10 to 80 degrees, so the whole motion stays in the image plane.
    """
    from PIL import Image, ImageDraw

    img = Image.new("RGB", (WIDTH, HEIGHT), (214, 222, 230))
    d = ImageDraw.Draw(img)
    skin, shirt, trousers = "#e0ac89", "#3a6ea5", "#3b3b4f"
    cx = WIDTH / 2
    neck = (cx, 150.0)
    r_sh, l_sh = (cx - 52, 162.0), (cx + 52, 162.0)
    r_hip, l_hip = (cx - 30, 285.0), (cx + 30, 285.0)
    upper, fore = 88.0, 82.0
    # legs
    _capsule(d, r_hip, (cx - 38, 370), 15, trousers)
    _capsule(d, (cx - 38, 370), (cx - 42, 455), 13, trousers)
    _capsule(d, l_hip, (cx + 38, 370), 15, trousers)
    _capsule(d, (cx + 38, 370), (cx + 42, 455), 13, trousers)
    # torso
    d.polygon([r_sh, l_sh, (cx + 36, 290), (cx - 36, 290)], fill=shirt)
    _capsule(d, r_sh, l_sh, 14, shirt)
    _capsule(d, neck, (cx, 120), 9, skin)
    # head with a face
    d.ellipse([cx - 32, 58, cx + 32, 132], fill=skin)
    d.ellipse([cx - 32, 52, cx + 32, 86], fill="#4a3424")
    for ex in (cx - 12, cx + 12):
        d.ellipse([ex - 5, 88, ex + 5, 96], fill="white")
        d.ellipse([ex - 2.5, 89.5, ex + 2.5, 94.5], fill="#222")
    d.line([(cx, 96), (cx - 3, 108), (cx + 2, 109)], fill="#a0705a", width=2)
    d.arc([cx - 12, 106, cx + 12, 120], 20, 160, fill="#8a3b3b", width=3)
    # the left arm (image right) hangs
    l_el = (l_sh[0] + 12, l_sh[1] + upper)
    _capsule(d, l_sh, l_el, 11, shirt)
    _capsule(d, l_el, (l_el[0] + 4, l_el[1] + fore), 9, skin)
    d.ellipse([l_el[0] - 6, l_el[1] + fore - 4, l_el[0] + 14, l_el[1] + fore + 16], fill=skin)
    # the right arm (image left) raises: abduction follows the elbow's bend
    bend = (FIGURE_ELBOW_DEG[0] - elbow_deg) / (FIGURE_ELBOW_DEG[0] - FIGURE_ELBOW_DEG[1])
    abduction = math.radians(10 + 70 * bend)
    u = (-math.sin(abduction), math.cos(abduction))  # from shoulder to elbow (y down)
    el = (r_sh[0] + upper * u[0], r_sh[1] + upper * u[1])
    turn = -math.radians(180 - elbow_deg)  # the forearm turns up from the upper arm's line
    f = (
        u[0] * math.cos(turn) + u[1] * math.sin(turn),
        -u[0] * math.sin(turn) + u[1] * math.cos(turn),
    )
    wr = (el[0] + fore * f[0], el[1] + fore * f[1])
    _capsule(d, r_sh, el, 11, shirt)
    _capsule(d, el, wr, 9, skin)
    hand = (wr[0] + 10 * f[0], wr[1] + 10 * f[1])
    d.ellipse([hand[0] - 10, hand[1] - 10, hand[0] + 10, hand[1] + 10], fill=skin)
    return np.asarray(img)


def figure_clip(path: Path, frames: int = 120, fps: int = 10, first: int = 0) -> Path:
    """The drawn figure raising and lowering its right arm once over ``frames`` (looped by Chromium)."""
    drawn = (draw_figure(figure_elbow_deg(k, frames)) for k in range(frames))
    return write_y4m(path, drawn, fps, first)


def image_elbow_deg(image: np.ndarray, side: str = "right") -> float:
    """The interior elbow angle, in degrees, of normalised image landmarks (33, >=2), in pixels."""
    s, e, w = (12, 14, 16) if side == "right" else (11, 13, 15)
    p = np.asarray(image, float)[:, :2] * [WIDTH, HEIGHT]
    a, b = p[s] - p[e], p[w] - p[e]
    cos = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


# ---------------------------------------------------------------------------- the studio's mannequin

MANNEQUIN_ABDUCTION_DEG = (10.0, 80.0)
"""The rendered right upper arm's lift sideways from hanging, over the motion."""
MANNEQUIN_FLEXION_DEG = (10.0, 120.0)
"""The rendered right elbow's flexion (0 straight) over the motion: interior angle 170 -> 60."""
MANNEQUIN_CAMERA = {"distance_m": 3.2, "focal_px": 700.0, "centre": (0.0, 0.21, -0.5)}
"""A pinhole camera in front of the body, looking at it, in the arm base frame (x forward, z up)."""


def mannequin_q(index: int, frames: int) -> np.ndarray:
    """The right arm's joints (HumanArm's order) in frame ``index``: abducted and bent in the
    picture's plane (the humerus turned so the elbow bends sideways and up), a raise and lower."""
    phase = (1 - math.cos(2 * math.pi * index / frames)) / 2
    abduction = np.radians(np.interp(phase, [0, 1], MANNEQUIN_ABDUCTION_DEG))
    flexion = np.radians(np.interp(phase, [0, 1], MANNEQUIN_FLEXION_DEG))
    return np.array([0.0, abduction, -math.pi / 2, flexion, 0.0, 0.0, 0.0])


class Mannequin:
    """The studio's own human model (Gepetto's human meshes, :class:`~studio.kinematics.HumanBody`)
    drawn with its right arm at a pose, by a painter's algorithm (triangles far to near)."""

    def __init__(self) -> None:
        from studio.kinematics import HumanBody

        self.body = HumanBody("right")
        names = [p.name for p in self.body.parts]
        self.joints = {
            side: [
                names.index(f"{side}_{link}")
                for link in ("upperarm/upperarm_mesh", "lowerarm/lowerarm_mesh", "hand/hand_mesh")
            ]
            for side in ("right", "left")
        }

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (N, 2) and depths (N,) of arm-base-frame points."""
        cam = MANNEQUIN_CAMERA
        rel = np.asarray(points, float) - np.asarray(cam["centre"])
        depth = cam["distance_m"] - rel[:, 0]  # the camera stands on +x, looking at -x
        # Image right is the body's +y (its left): a camera facing the person, not a mirror.
        u = WIDTH / 2 + cam["focal_px"] * rel[:, 1] / depth
        v = HEIGHT / 2 - cam["focal_px"] * rel[:, 2] / depth
        return np.stack([u, v], axis=1), depth

    def arm_pixels(self, q: np.ndarray, side: str = "right") -> np.ndarray:
        """Shoulder, elbow and wrist of ``side`` in pixels (3, 2) with the right arm at ``q``."""
        poses = self.body.poses(np.asarray(q, float))
        return self.project(np.stack([poses[i][:3, 3] for i in self.joints[side]]))[0]

    def render(self, q: np.ndarray) -> np.ndarray:
        from PIL import Image, ImageDraw

        light = np.array([0.6, -0.3, 0.75])
        light /= np.linalg.norm(light)
        tris, colours, depths = [], [], []
        for part, pose in zip(self.body.parts, self.body.poses(np.asarray(q, float)), strict=True):
            v = part.vertices.astype(float) @ pose[:3, :3].T + pose[:3, 3]
            t = v[part.faces]
            n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
            n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-12
            shade = 0.45 + 0.55 * np.abs(n @ light)
            px, depth = self.project(t.reshape(-1, 3))
            tris.append(px.reshape(-1, 3, 2))
            depths.append(depth.reshape(-1, 3).mean(axis=1))
            colours.append(np.clip(np.outer(shade, part.rgb) * 255, 0, 255).astype(np.uint8))
        tri, colour, depth = np.concatenate(tris), np.concatenate(colours), np.concatenate(depths)
        img = Image.new("RGB", (WIDTH, HEIGHT), (214, 222, 230))
        draw = ImageDraw.Draw(img)
        for k in np.argsort(-depth):  # far to near
            draw.polygon([tuple(p) for p in tri[k]], fill=tuple(int(c) for c in colour[k]))
        return np.asarray(img)


def mannequin_clip(path: Path, frames: int = 40, fps: int = 10, first: int = 0) -> Path:
    """The studio's mannequin raising and bending its right arm once over ``frames`` (looped)."""
    model = Mannequin()
    rendered = (model.render(mannequin_q(k, frames)) for k in range(frames))
    return write_y4m(path, rendered, fps, first)


CLIPS: dict[str, Callable[..., Path]] = {
    "astronaut": astronaut_clip,
    "blank": blank_clip,
    "figure": figure_clip,
    "mannequin": mannequin_clip,
}
"""Clip makers by name, for the tests and the benchmark."""
