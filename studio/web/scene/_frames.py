"""How often viser's page may draw the scene: while a slow live stream drives it, and while
nothing in it changes.

viser's page draws on demand, but after every update it receives it keeps drawing for a quarter
of a second (``RENDER_SETTLE_MS`` in its ``App.tsx``), as fast as the browser allows, and it
draws one frame a second besides, changed or not (``RENDER_HEARTBEAT_MS``, a safety net for
changes that never ask for a frame). Without a GPU every one of those frames is drawn by
SwiftShader in the browser's GPU process: about 50 ms of CPU a frame for this scene.

- **A slow live stream** (pose estimation without a GPU, see ``SceneLayout.slow_live_s``) brings
  a new pose at most once a second, and the frames after the first show the same pose again,
  in the very process where the camera's pose model runs its WebGL. So while one drives the
  scene, :class:`FramePacer` asks every browser showing the scene to start a frame at most every
  :data:`SLOW_FRAME_GAP_MS`, and the scene counts as still once nothing was sent for
  :data:`SLOW_STILL_AFTER_S`, before that gap is over: each pose is drawn in the one frame that
  follows it, and neither viser's settle frames nor its once-a-second frame are drawn until the
  next pose. One frame is enough: the page applies a message as it comes (below), and viser
  sets a node's pose in the first of its frame hooks, so the frame after a pose draws it (tested
  by reading what that frame drew against what the scene shows a second later).
- **A still scene**: when nothing has been sent to the page for :data:`STILL_AFTER_S`, a page
  that has finished loading (:data:`LOADING_S`) is asked to draw at most every
  :data:`STILL_FRAME_GAP_MS`, counted from the frame it drew last. The once-a-second frame then
  costs a quarter of what it did: a
  still page beside a training run took 0.08 of this machine's two cores, most of it that frame.
  The first message sent to the page afterwards (any update of the scene, or of the page's
  camera) first lifts the limit, and the frames a page was holding back are drawn at once.
  viser's page applies what it receives in its next frame, so the page must not wait for a
  frame to read the message that lifts the limit: while still, the page reads as hidden
  (``document.hidden``), for which viser applies each message as it comes.
- **Waking a still page for an update of the whole scene** (a pose): the script that wakes the
  page goes through that page's own message queue, the update through viser's queue for every
  page, so the page receives them in two batches, and a frame let go when the first is applied
  may be drawn before the second arrives (the old pose, on a busy machine; and while a slow
  stream drives the scene, the pose then waits for the next one). So the frames held back are
  let go only once viser has applied the update (its ``requestRender``, which it calls after
  each batch of scene messages), or at once if the update came first: the frame let go draws
  the update. Until then the page draws no frame at all (for at most
  :data:`UPDATE_AWAITED_MS`), not even one whose turn comes meanwhile. An update for one page
  alone is sent in one batch with the script that wakes it (viser's ``atomic``), and the frames
  are let go at once.

Anything the user does in the scene (a pointer, the wheel, a key) or a resize of its window lifts
the limit for :data:`INPUT_LIFTS_MS` and draws any frame held back, so orbiting stays as smooth
as the browser can draw it.

The limit is a wrapper of the page's ``requestAnimationFrame`` (the clock of three.js and of
React Three Fiber, which viser draws with), installed through viser's ``RunJavascriptMessage``.
It delays frames and never drops one; with a gap of 0 it hands every request straight to the
browser. A frame waiting for its turn counts its turn again when it comes, so a gap that grew
meanwhile (the scene became still) holds it too: viser's once-a-second frame, asked for just
before a slow stream's scene became still, waits for the next pose rather than being drawn
between poses. ``window.__studioFramePacing.frames`` counts the frames it let through.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import viser

SLOW_FRAME_GAP_MS = 500.0
"""Least time between two frames of viser's page while a slow live stream drives the scene: long
enough that the scene reads as still (:data:`SLOW_STILL_AFTER_S`, and the watch's
:data:`WATCH_EVERY_S`) before a second frame's turn comes, so a pose is drawn in one frame."""
STILL_FRAME_GAP_MS = 4000.0
"""Least time between two frames of a page whose scene is still: viser's safety-net frame, once
every 4 s instead of every second."""
STILL_AFTER_S = 1.5
"""Nothing sent to the page for this long: its scene is still (viser's settle window after the
last update, a quarter of a second, is long over)."""
SLOW_STILL_AFTER_S = 0.15
"""While a slow stream drives the scene: nothing sent for this long, and its last pose is drawn
(its frame comes at once); the scene is still until the next pose."""
LOADING_S = 5.0
"""A page that connected less than this long ago is still loading the scene (meshes, shaders):
it draws freely."""
INPUT_LIFTS_MS = 1500.0
"""How long a pointer, wheel or key event in the scene, or a resize, lifts the limit."""
UPDATE_AWAITED_MS = 2000.0
"""A page woken for an update of the scene draws no frame until it has applied it, for at most
this long (the update comes right behind the script waking the page; a message that changes
nothing in the scene, a label's, wakes the page too)."""
WATCH_EVERY_S = 0.1
"""How often the pacer looks whether the scene has become still."""

_PACING_JS = """
(() => {
  let p = window.__studioFramePacing;
  if (!p) {
    p = window.__studioFramePacing = {
      gapMs: 0, inputUntil: 0, next: 0, at: 0, lastT: -1, frames: 0,
      inFrame: false, // a frame let through is running
      inScript: false, // this script ran in the task now running (viser's batch carrying it)
      woken: false, // woken for an update still to come: let the held frames go once it is applied
      awaitUntil: 0, // and until then (at most this long) hold every frame, whenever its turn
      changed: false, // an update was applied while still, and no frame drew it yet
    };
    const raf = window.requestAnimationFrame.bind(window);
    const caf = window.cancelAnimationFrame.bind(window);
    const waiting = new Map(); // our id -> [timeout, the browser's frame id, callback]
    let seq = 0x40000000; // apart from the browser's own ids (a request made before this ran)
    const hand = (id, cb) => {
      waiting.get(id)[1] = raf((t) => {
        waiting.delete(id);
        if (t !== p.lastT) { p.lastT = t; p.frames += 1; p.at = performance.now(); p.next = p.at + p.gapMs; }
        p.inFrame = true;
        try { cb(t); } finally { p.inFrame = false; p.changed = false; }
      });
    };
    p.release = () => { // hand every frame held back to the browser now
      for (const [id, entry] of waiting) {
        if (!entry[0]) continue;
        clearTimeout(entry[0]);
        entry[0] = 0;
        hand(id, entry[2]);
      }
    };
    const wait = () => { // how long a frame requested now waits for its turn
      const now = performance.now();
      if (now < p.inputUntil) return 0;
      return Math.max(p.awaitUntil - now, p.gapMs > 0 ? p.next - now : 0);
    };
    const hold = (id, cb) => { // until its turn, counted again when it comes (the gap may have grown)
      const ms = wait();
      if (ms > 0) waiting.get(id)[0] = setTimeout(() => hold(id, cb), ms);
      else { waiting.get(id)[0] = 0; hand(id, cb); }
    };
    window.requestAnimationFrame = (cb) => {
      const id = ++seq;
      waiting.set(id, [0, 0, cb]);
      hold(id, cb);
      return id;
    };
    window.cancelAnimationFrame = (id) => {
      const entry = waiting.get(id);
      if (!entry) return caf(id);
      clearTimeout(entry[0]);
      if (entry[1]) caf(entry[1]);
      waiting.delete(id);
    };
    const lift = () => { p.inputUntil = performance.now() + %(lift)s; p.release(); };
    for (const type of ["pointerdown", "pointermove", "wheel", "keydown", "resize"]) {
      window.addEventListener(type, lift, { capture: true, passive: true });
    }
  }
  if (!p.hides) {
    // viser applies what it receives in its next frame, or at once while the page is hidden
    // (its messageQueue.ts); a still page reads as hidden, so that an update (and the script
    // waking the page, above all) is applied as it comes rather than in a frame held back.
    const hidden = Object.getOwnPropertyDescriptor(Document.prototype, "hidden").get;
    Object.defineProperty(document, "hidden", { configurable: true, get: () => p.still || p.atOnce || hidden.call(document) });
    p.hides = true;
  }
  // viser calls requestRender once it has applied a batch of scene messages (messageQueue.ts);
  // set again whenever viser set its own (it does so when its canvas mounts).
  const viewer = window.__viserMutable;
  const hooked = !!viewer && typeof viewer.requestRender === "function";
  if (hooked && !viewer.requestRender.__studio) {
    const render = viewer.requestRender;
    const applied = () => {
      render();
      // asked for by a frame, or for the batch carrying this script: not an update arriving
      if (p.inFrame || p.inScript) return;
      if (p.woken) { p.woken = false; p.awaitUntil = 0; p.release(); }
      else if (p.still) p.changed = true;
    };
    applied.__studio = true;
    viewer.requestRender = applied;
  }
  // viser calls requestRender for the batch carrying this script too, right after it
  p.inScript = true;
  queueMicrotask(() => { p.inScript = false; });
  const before = p.gapMs;
  p.gapMs = %(gap)s;
  p.still = %(still)s;
  p.atOnce = %(at_once)s;
  p.woken = false;
  p.awaitUntil = 0;
  if (p.gapMs !== before) p.next = p.at ? p.at + p.gapMs : 0; // from the last frame drawn
  if (p.gapMs < before) {
    if (!%(update_follows)s || !hooked || p.changed) p.release();
    else { // the update comes in a batch of its own, applied in a task of its own
      p.woken = true;
      p.awaitUntil = performance.now() + %(await_ms)s;
    }
  }
})();
"""


def pacing_js(
    gap_ms: float, still: bool = False, at_once: bool = False, update_follows: bool = False
) -> str:
    """The script that sets the least time between frames of viser's page (0: no limit),
    whether its scene is still, and whether a slow stream drives it (in both viser applies each
    update as it comes, see above: the frame that draws it is then the only one it needs).

    ``update_follows``: the script wakes a still page for an update of the scene that reaches it
    in a batch of its own; the frames held back are let go once viser has applied it (at once on
    a page whose viser does not say so)."""
    return _PACING_JS % {
        "gap": float(gap_ms),
        "lift": INPUT_LIFTS_MS,
        "still": "true" if still else "false",
        "at_once": "true" if at_once else "false",
        "update_follows": "true" if update_follows else "false",
        "await_ms": UPDATE_AWAITED_MS,
    }


class _Page:
    """One browser showing the scene: how to send it a script, and when it connected."""

    def __init__(self, send: Callable[[object], None]) -> None:
        self.send = send  # its connection's own queue_message, before the pacer wrapped it
        self.connected_at = time.monotonic()


class FramePacer:
    """Tells every browser showing the scene, and each one that connects, the frame gap.

    Every message viser sends to a page passes through the pacer (it wraps the ``queue_message``
    of the server and of each client's connection), which is how it knows the scene is still,
    and wakes a still page before the message that changes it.
    """

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self.gap_ms = 0.0
        """The gap while the scene changes: :data:`SLOW_FRAME_GAP_MS` while a slow stream
        drives it, else 0."""
        self._lock = threading.Lock()
        self._pages: dict[int, _Page] = {}
        self._still: set[int] = set()  # pages told the still gap
        self._last_sent = time.monotonic()
        self._closed = threading.Event()
        self._wrap(server._websock_server)
        server.on_client_connect(self._connected)
        server.on_client_disconnect(self._disconnected)
        self._thread = threading.Thread(target=self._watch, name="frame-pacer", daemon=True)
        self._thread.start()

    def slow(self, slow: bool) -> None:
        """Limit the frames while a slow live stream drives the scene; lift it otherwise."""
        gap = SLOW_FRAME_GAP_MS if slow else 0.0
        with self._lock:
            if gap == self.gap_ms:
                return
            self.gap_ms = gap
            for client_id, page in self._pages.items():
                if client_id not in self._still:
                    self._tell(page, gap)

    def still_pages(self) -> int:
        """How many pages are drawing at the still gap now (tests, benchmarks)."""
        with self._lock:
            return len(self._still)

    def close(self) -> None:
        """Stop watching for a still scene."""
        self._closed.set()
        self._thread.join(timeout=2.0)

    def _wrap(self, handler: object, client_id: int | None = None) -> Callable[[object], None]:
        """Route ``handler``'s outgoing messages through :meth:`_sent`; its original sender.

        ``client_id``: the page ``handler`` sends to alone (None: every page)."""
        send = handler.queue_message  # type: ignore[attr-defined]

        def queue_message(message: object) -> None:
            if client_id is None:
                self._sent(None)
                send(message)
                return
            with handler.atomic():  # type: ignore[attr-defined]
                self._sent(client_id)  # its page gets the message in the batch that wakes it
                send(message)

        handler.queue_message = queue_message  # type: ignore[attr-defined]
        return send

    def _sent(self, to: int | None) -> None:
        """A message is about to go to page ``to`` (None: to every page): wake the still ones
        first. A message to every page reaches each in a batch of its own, after the one waking
        it: a woken page lets its frames go once it has applied that batch."""
        with self._lock:
            self._last_sent = time.monotonic()
            if not self._still:
                return
            for client_id in self._still:
                page = self._pages.get(client_id)
                if page is not None:
                    self._tell(page, self.gap_ms, update_follows=to is None)
            self._still.clear()

    def _connected(self, client: viser.ClientHandle) -> None:
        # viser has no public call to run a script in one browser, nor to see what it sends;
        # its plotly support sends scripts through the connection the same way.
        page = _Page(self._wrap(client._websock_connection, client.client_id))
        with self._lock:
            self._pages[client.client_id] = page
            if self.gap_ms > 0:  # else the page draws as viser made it, without the wrapper
                self._tell(page, self.gap_ms)

    def _disconnected(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self._pages.pop(client.client_id, None)
            self._still.discard(client.client_id)

    def _tell(
        self, page: _Page, gap_ms: float, still: bool = False, update_follows: bool = False
    ) -> None:
        """Send ``page`` the gap (the caller holds the lock)."""
        from viser import _messages

        script = pacing_js(gap_ms, still, self.gap_ms > 0, update_follows)
        page.send(_messages.RunJavascriptMessage(script))

    def _watch(self) -> None:
        """Tell each loaded page the still gap once nothing was sent for STILL_AFTER_S (for
        SLOW_STILL_AFTER_S while a slow stream drives the scene)."""
        while not self._closed.wait(WATCH_EVERY_S):
            now = time.monotonic()
            with self._lock:
                quiet = SLOW_STILL_AFTER_S if self.gap_ms > 0 else STILL_AFTER_S
                if now - self._last_sent < quiet:
                    continue
                for client_id, page in self._pages.items():
                    if client_id in self._still or now - page.connected_at < LOADING_S:
                        continue
                    self._tell(page, max(STILL_FRAME_GAP_MS, self.gap_ms), still=True)
                    self._still.add(client_id)
