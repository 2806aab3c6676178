"""How often viser's page may draw the scene while a slow live stream drives it.

viser's page draws on demand, but after every update it receives it keeps drawing for a quarter
of a second (``RENDER_SETTLE_MS`` in its ``App.tsx``), as fast as the browser allows. Without a
GPU every one of those frames is drawn by SwiftShader in the browser's GPU process: about 50 ms
of CPU a frame for this scene, 4 to 7 frames an update, in the very process where the camera's
pose model runs its WebGL. The pose model then waits behind the scene.

A slow live stream (pose estimation without a GPU, see ``SceneLayout.slow_live_s``) brings a new
pose at most once a second, and the frames after the first show the same pose again. So while
one drives the scene, :class:`FramePacer` asks every browser showing the scene to start a frame
at most every :data:`SLOW_FRAME_GAP_MS`: the update is drawn, and one frame after it (for what
viser finishes after a commit, such as a texture upload), instead of a burst. Anything the user
does in the scene (a pointer, the wheel, a key) lifts the limit for
:data:`INPUT_LIFTS_MS`, so orbiting stays as smooth as the browser can draw it.

The limit is a wrapper of the page's ``requestAnimationFrame`` (the clock of three.js and of
React Three Fiber, which viser draws with), installed through viser's ``RunJavascriptMessage``.
It delays frames and never drops one; with a gap of 0 it hands every request straight to the
browser. ``window.__studioFramePacing.frames`` counts the frames it let through.
"""

from __future__ import annotations

import threading

import viser

SLOW_FRAME_GAP_MS = 250.0
"""Least time between two frames of viser's page while a slow live stream drives the scene: as
long as viser's settle window, so an update is drawn in one frame and settled in one more."""
INPUT_LIFTS_MS = 1500.0
"""How long a pointer, wheel or key event in the scene lifts the limit."""

_PACING_JS = """
(() => {
  let p = window.__studioFramePacing;
  if (!p) {
    p = window.__studioFramePacing = { gapMs: 0, inputUntil: 0, next: 0, lastT: -1, frames: 0 };
    const raf = window.requestAnimationFrame.bind(window);
    const caf = window.cancelAnimationFrame.bind(window);
    const waiting = new Map(); // our id -> [timeout, the browser's frame id]
    let seq = 0x40000000; // apart from the browser's own ids (a request made before this ran)
    const hand = (id, cb) => {
      waiting.get(id)[1] = raf((t) => {
        waiting.delete(id);
        if (t !== p.lastT) { p.lastT = t; p.frames += 1; p.next = performance.now() + p.gapMs; }
        cb(t);
      });
    };
    window.requestAnimationFrame = (cb) => {
      const id = ++seq;
      const now = performance.now();
      const wait = p.gapMs > 0 && now >= p.inputUntil ? p.next - now : 0;
      waiting.set(id, [0, 0]);
      if (wait > 0) waiting.get(id)[0] = setTimeout(() => hand(id, cb), wait);
      else hand(id, cb);
      return id;
    };
    window.cancelAnimationFrame = (id) => {
      const entry = waiting.get(id);
      if (!entry) return caf(id);
      clearTimeout(entry[0]);
      if (entry[1]) caf(entry[1]);
      waiting.delete(id);
    };
    const lift = () => { p.inputUntil = performance.now() + %(lift)s; };
    for (const type of ["pointerdown", "pointermove", "wheel", "keydown"]) {
      window.addEventListener(type, lift, { capture: true, passive: true });
    }
  }
  p.gapMs = %(gap)s;
})();
"""


def pacing_js(gap_ms: float) -> str:
    """The script that sets the least time between frames of viser's page (0: no limit)."""
    return _PACING_JS % {"gap": float(gap_ms), "lift": INPUT_LIFTS_MS}


class FramePacer:
    """Tells every browser showing the scene, and each one that connects, the frame gap."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self.gap_ms = 0.0
        self._lock = threading.Lock()
        server.on_client_connect(self._connected)

    def slow(self, slow: bool) -> None:
        """Limit the frames while a slow live stream drives the scene; lift it otherwise."""
        gap = SLOW_FRAME_GAP_MS if slow else 0.0
        with self._lock:
            if gap == self.gap_ms:
                return
            self.gap_ms = gap
        for client in list(self.server.get_clients().values()):
            self._send(client)

    def _connected(self, client: viser.ClientHandle) -> None:
        if self.gap_ms > 0:  # else the page draws as viser made it, without the wrapper
            self._send(client)

    def _send(self, client: viser.ClientHandle) -> None:
        # viser has no public call to run a script in one browser; its plotly support sends
        # this message the same way.
        from viser import _messages

        message = _messages.RunJavascriptMessage(pacing_js(self.gap_ms))
        client._websock_connection.queue_message(message)
