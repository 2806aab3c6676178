"""The network bridge: receive tape frames over UDP (:class:`NetworkSource`) and send them.

A small device-side program (or ``studio bridge``) sends one datagram per frame in the format of
:mod:`._wire`. UDP suits a 110 Hz stream on a LAN: no head-of-line blocking, and a lost frame is
better late than never. Lost frames show up as gaps in the frame counter and are counted as
dropped; malformed datagrams are counted as rejected, with the reason in ``status().warning``.
So is a well-formed datagram of another tape: the stream's region count is fixed by the config
(when given) or by its first frame, so one stray sender can never end a capture whose recording
has a fixed width.
UDP has no connection to lose: while no datagram arrives for :data:`SILENCE_SECONDS`, the
source keeps listening and ``status().error`` says so; the first datagram clears it.

The source listens on loopback unless told otherwise. Listening beyond loopback needs a token:
then only datagrams signed with it (:func:`._wire.bridge_key`) are taken, since anyone who
reaches the port could otherwise drive the live tape and so what is recorded.
"""

from __future__ import annotations

import socket
import time

from studio import is_loopback

from ._errors import CaptureError
from ._frames import TapeFrame
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource, check_seconds
from ._wire import DEFAULT_PORT, WireError, bridge_key, decode_frame, encode_frame

RECEIVE_POLL_SECONDS = 0.1
"""Socket timeout: how quickly the receiver notices a stop request."""
SILENCE_SECONDS = 2.0
"""After this long without a datagram, the status reports that the sender went quiet."""
MAX_DATAGRAM_BYTES = 65535
"""Largest UDP payload."""
MAX_COUNTER_GAP = 10_000
"""A larger jump in the frame counter is a restarted sender, not lost frames."""


class NetworkSource(ThreadedSource[TapeFrame]):
    """Tape frames from UDP datagrams (wire format in :mod:`studio.capture._wire`).

    Args:
        host: address to listen on (loopback by default; ``"0.0.0.0"`` for a device on the LAN,
            which needs a ``token``).
        port: UDP port (0 picks a free one; see :attr:`address`).
        config: the tape config the frames belong to; its ``regions`` fixes the region count
            every datagram must have (default: the first datagram's count).
        queue_frames: frames buffered before dropping.
        token: when given, only datagrams signed with it are taken (``studio bridge --token``,
            :class:`FrameSender` ``token=``); required to listen beyond loopback.

    Raises:
        CaptureError: from :meth:`start` when the port cannot be bound, or the host is not
            loopback and there is no token.
    """

    kind = "network"

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        config: object = None,
        queue_frames: int = DEFAULT_QUEUE_FRAMES,
        token: str | None = None,
    ) -> None:
        super().__init__(queue_frames)
        self.host, self.port = host, int(port)
        self.config = config
        self._key = bridge_key(token) if token else None
        self._sock: socket.socket | None = None
        self._last_counter: int | None = None
        self._regions: int | None = None

    @property
    def address(self) -> tuple[str, int]:
        """The bound ``(host, port)`` (after :meth:`start`), else the requested one."""
        if self._sock is not None:
            return self._sock.getsockname()[:2]
        return self.host, self.port

    @property
    def regions(self) -> int | None:
        """The region count every datagram must have (``None`` until the first frame fixes it)."""
        configured = getattr(self.config, "regions", None)
        return int(configured) if configured is not None else self._regions

    def _open(self) -> None:
        self._regions = None  # a restarted stream may come from another tape
        if self._sock is not None:
            return
        if self._key is None and not is_loopback(self.host):
            raise CaptureError(
                f"listening for tape frames on UDP {self.host} opens the bridge to other machines, which needs a token to sign the frames; give one (studio record --token, and the same to studio bridge --token), or listen on 127.0.0.1."
            )
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        try:
            sock.bind((self.host, self.port))
        except OSError as err:
            sock.close()
            raise CaptureError(
                f"cannot listen on UDP {self.host}:{self.port} ({err.strerror}); choose another port."
            ) from None
        sock.settimeout(RECEIVE_POLL_SECONDS)
        self._sock = sock

    def _close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def _produce(self) -> None:
        sock = self._sock
        assert sock is not None
        last_datagram = time.monotonic()
        while not self._stop_event.is_set():
            try:
                data, sender = sock.recvfrom(MAX_DATAGRAM_BYTES)
            except TimeoutError:
                quiet = time.monotonic() - last_datagram
                if quiet > SILENCE_SECONDS:
                    host, port = self.address
                    waited = "no frames yet" if self._last_counter is None else "no frames"
                    with self._lock:
                        self._error = (
                            f"{waited} on UDP {host}:{port} for {quiet:.0f} s; check that the "
                            "device or `studio bridge` is running and sends to this address."
                        )
                continue
            except OSError as err:
                if self._stop_event.is_set():
                    return
                raise CaptureError(
                    f"the UDP socket failed ({err.strerror}); restart the network source."
                ) from None
            last_datagram = time.monotonic()
            if self._error is not None:
                with self._lock:
                    self._error = None  # the sender is back
            try:
                frame = decode_frame(data, self._key)
            except WireError as err:
                self._reject(f"rejected a datagram from {sender[0]}:{sender[1]}: {err}.")
                continue
            regions, expected = frame.bend.shape[0], self.regions
            if expected is None:
                self._regions = regions
            elif regions != expected:
                self._reject(
                    f"rejected a datagram from {sender[0]}:{sender[1]}: {regions} regions where "
                    f"this stream has {expected}; send each tape to its own port."
                )
                continue
            if self._last_counter is not None:
                gap = (frame.frame - self._last_counter - 1) & 0xFFFFFFFF
                if 0 < gap < MAX_COUNTER_GAP:
                    self._count_dropped(gap)
            self._last_counter = frame.frame
            self._push(frame)


class FrameSender:
    """Send frames to a :class:`NetworkSource` (what a device-side program does).

    Args:
        host: the receiver's address.
        port: the receiver's UDP port.
        token: the receiving studio's token: every datagram is signed with it (a source
            listening beyond loopback takes only signed frames).
    """

    def __init__(
        self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, token: str | None = None
    ) -> None:
        try:
            found = socket.getaddrinfo(host, int(port), socket.AF_INET, socket.SOCK_DGRAM)
        except (OSError, OverflowError, UnicodeError) as err:  # gaierror is an OSError
            reason = getattr(err, "strerror", None) or err
            raise CaptureError(
                f"{host}:{port} is not an address to send to ({reason}); give the receiver's HOST:PORT, e.g. 127.0.0.1:{DEFAULT_PORT}."
            ) from None
        self.target = found[0][4]
        self._key = bridge_key(token) if token else None
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sent = 0

    def send(self, frame: TapeFrame) -> None:
        """Send one frame as one datagram.

        Raises:
            CaptureError: the datagram cannot be sent (no route to the receiver, ...).
        """
        try:
            self._sock.sendto(encode_frame(frame, self._key), self.target)
        except OSError as err:
            host, port = self.target
            raise CaptureError(
                f"cannot send to {host}:{port} ({err.strerror or err}); check the address and the network."
            ) from None
        self.sent += 1

    def close(self) -> None:
        """Release the socket."""
        self._sock.close()

    def __enter__(self) -> FrameSender:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def stream_source(
    source: ThreadedSource,
    host: str,
    port: int,
    seconds: float | None = None,
    on_frames: object = None,
    token: str | None = None,
) -> int:
    """Forward every frame of ``source`` to ``host:port`` until it ends or ``seconds`` pass.

    Args:
        source: a started or unstarted source (it is started and stopped here).
        host: the receiver's address.
        port: the receiver's UDP port.
        seconds: how long to stream (``None``: until the source ends).
        on_frames: optional callable given each batch of frames sent (for progress).
        token: the receiving studio's token, to sign every frame with (see :class:`FrameSender`).

    Returns:
        Frames sent.

    Raises:
        CaptureError: the source reported an error.
    """
    seconds = check_seconds(seconds)
    deadline = None if seconds is None else time.monotonic() + seconds
    with FrameSender(host, port, token) as sender:
        source.start()
        try:
            while deadline is None or time.monotonic() < deadline:
                frames = source.read(timeout=0.1)
                for frame in frames:
                    sender.send(frame)
                if frames and callable(on_frames):
                    on_frames(frames)
                status = source.status()
                if status.error:
                    raise CaptureError(status.error)
                if not frames and not status.running:
                    break
        finally:
            source.stop()
        return sender.sent
