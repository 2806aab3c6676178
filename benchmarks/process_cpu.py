"""CPU time of a browser benchmark's processes, from /proc, by role.

Frames per second swing with whatever else runs on a shared machine; the CPU seconds a process
spends per frame it helps produce far less. :class:`ProcessCpu` sums ``utime + stime`` (every
thread of the process) for the studio server and for each Chromium process the benchmark
launched: the browser, the GPU process (where SwiftShader draws every WebGL call of every page),
utilities (network, storage, the fake camera), and each renderer under the name of the page it
serves (:func:`renderer_roles`, from a short trace of which frame's work runs where).
"""

from __future__ import annotations

import json
import os
import re
import time
from typing import Any

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
OTHER_RENDERER = "renderer (other)"
ROLE_ORDER = (
    "renderer: bare page",
    "renderer: studio page",
    "renderer: scene",
    OTHER_RENDERER,
    "GPU process",
    "browser",
    "utilities",
    "studio server",
)


def _stat(pid: int) -> tuple[int, float] | None:
    """(parent pid, CPU seconds of the process's own threads), or None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    # after the command: state(0) ppid(1) ... utime(11) stime(12)
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def descendants(root: int) -> list[int]:
    """``root`` and every process under it."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit() and (st := _stat(int(entry))) is not None:
            children.setdefault(st[0], []).append(int(entry))
    out, todo = [], [root]
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo += children.get(pid, [])
    return out


def _cmdline(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def chromium_role(cmdline: str) -> str | None:
    """The role of a Chromium process by its ``--type`` (renderers are named later), else None."""
    if "chrom" not in cmdline.split(" ", 1)[0]:
        return None
    kind = re.search(r"--type=(\S+)", cmdline)
    if kind is None:
        return "browser"
    return {
        "gpu-process": "GPU process",
        "renderer": OTHER_RENDERER,
        "utility": "utilities",
        "zygote": "browser",
    }.get(kind.group(1), "utilities")


def frame_id(context: Any, page_or_frame: Any) -> str:
    """The DevTools id of a Playwright page's main frame, or of an out-of-process iframe."""
    session = context.new_cdp_session(page_or_frame)
    try:
        return session.send("Page.getFrameTree")["frameTree"]["frame"]["id"]
    finally:
        session.detach()


def renderer_roles(browser: Any, frames: dict[str, str], seconds: float = 2.0) -> dict[int, str]:
    """Which renderer process serves which page: ``{pid: role}``, from ``{frame id: role}``.

    Traces the browser for ``seconds`` and names each renderer after the frame its timeline
    events (timers, frame callbacks, paints) belong to: the pages must do something meanwhile.
    """
    browser.start_tracing(categories=["devtools.timeline"])
    time.sleep(seconds)
    trace = json.loads(browser.stop_tracing())
    events = trace["traceEvents"] if isinstance(trace, dict) else trace
    found: dict[int, str] = {}
    for e in events:
        frame = ((e.get("args") or {}).get("data") or {}).get("frame")
        if frame in frames and e.get("pid") not in found:
            found[e["pid"]] = frames[frame]
    return found


def threads(pid: int) -> dict[int, tuple[str, float]]:
    """``{thread id: (name without its digits, CPU seconds)}`` of one process."""
    out = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/stat") as f:
                raw = f.read()
        except OSError:
            continue
        name = raw[raw.index("(") + 1 : raw.rindex(")")]
        fields = raw.rsplit(")", 1)[1].split()
        out[int(tid)] = (
            re.sub(r"[0-9]+", "", name),
            (int(fields[11]) + int(fields[12])) / CLOCK_TICKS,
        )
    return out


class ProcessCpu:
    """CPU seconds by role, for the studio server's process tree and this process's Chromiums.

    The GPU process, where software WebGL and the display compositor run, is also split by
    thread (``"GPU: <thread name>"`` keys), to tell drawing from compositing.
    """

    def __init__(self, studio_pid: int) -> None:
        self.studio_pid = studio_pid
        self.renderers: dict[int, str] = {}

    def snapshot(self) -> dict[int, tuple[str, float]]:
        """``{pid: (role, CPU seconds so far)}`` of every process counted now."""
        out: dict[int, tuple[str, float]] = {}
        for pid in descendants(self.studio_pid):
            if (st := _stat(pid)) is not None:
                out[pid] = ("studio server", st[1])
        for pid in descendants(os.getpid()):
            role = chromium_role(_cmdline(pid))
            if role is None or (st := _stat(pid)) is None:
                continue
            out[pid] = (self.renderers.get(pid, role), st[1])
            if role == "GPU process":
                for tid, (name, t) in threads(pid).items():
                    out[-tid] = (f"GPU: {name}", t)  # negative: apart from the process ids
        return out

    @staticmethod
    def spent(
        before: dict[int, tuple[str, float]], after: dict[int, tuple[str, float]]
    ) -> dict[str, float]:
        """CPU seconds by role between two snapshots (a process started meanwhile from zero).

        The ``"GPU: ..."`` keys split the GPU process's figure; they are not added to it again.
        """
        out = dict.fromkeys(ROLE_ORDER, 0.0)
        for pid, (role, t) in after.items():
            out[role] = out.get(role, 0.0) + t - before.get(pid, (role, 0.0))[1]
        return out


def machine_busy_s() -> float:
    """CPU seconds the whole machine has spent busy (all cores, /proc/stat), for others' load."""
    with open("/proc/stat") as f:
        fields = [int(v) for v in f.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / CLOCK_TICKS
