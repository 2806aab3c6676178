"""The network bridge: receive tape frames over UDP (:class:`NetworkSource`) and send them, in
the bridge's wire format.

A small device-side program (or ``studio bridge``) sends one datagram per frame. UDP suits a
110 Hz stream on a LAN: no head-of-line blocking, and a lost frame is better late than never.
Lost frames show up as gaps in the frame counter and are counted as dropped; malformed datagrams
are counted as rejected, with the reason in ``status().warning``. So is a well-formed datagram of
another tape: the stream's region count is fixed by the config (when given) or by its first
frame, so one stray sender can never end a capture whose recording has a fixed width.
UDP has no connection to lose: while no datagram arrives for :data:`SILENCE_SECONDS`, the
source keeps listening and ``status().error`` says so; the first datagram clears it.

The source listens on loopback unless told otherwise. Listening beyond loopback needs a token:
then only datagrams signed with it (:func:`bridge_key`) are taken, since anyone who reaches the
port could otherwise drive the live tape and so what is recorded.

The wire format (version 1): one tape frame per UDP datagram, all fields big-endian (network
order)::

    offset  size  type      field
    0       4     bytes     magic b"STAP"
    4       1     uint8     version (1)
    5       1     uint8     flags (bit 0: signed; the others reserved, 0)
    6       2     uint16    regions R
    8       4     uint32    frame counter (wraps at 2**32)
    12      8     float64   timestamp t, seconds since the sender started
    20      2     uint16    status bits (bit 4 switch0, bit 5 trigger, bit 6 switch1)
    22      4*R   float32   bend per region, radians
    22+4R   4*R   float32   twist per region, radians

A signed datagram (flags bit 0) ends with 16 more bytes: the first 16 bytes of the HMAC-SHA256
of everything before them, keyed by :func:`bridge_key` of the studio's token. A receiver given a
key (a network source listening beyond loopback) takes only datagrams signed with it, so nobody
without the token can drive the live tape. The signature authenticates frames; it does not hide
them.

A 16-region frame is 150 bytes (166 signed). A receiver rejects (and counts) datagrams with
another magic, a newer version, a length that does not match R, non-finite angles, or (given a
key) no signature or a wrong one.
"""

from __future__ import annotations

import hashlib
import hmac
import socket
import struct
import time

import numpy as np

from studio import is_loopback

from ._errors import CaptureError
from ._observations import TapeFrame
from ._recording_format import MAX_REGIONS
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource, check_seconds
from ._source_specs import DEFAULT_PORT

MAGIC = b"STAP"
"""First four bytes of every datagram."""
WIRE_VERSION = 1
"""The version this code writes and the newest it reads."""
HEADER = struct.Struct("!4sBBHIdH")
"""Everything before the angles."""
SIGNED = 0x01
"""Flags bit: the datagram ends with a signature (:data:`SIGNATURE_BYTES`)."""
SIGNATURE_BYTES = 16
"""Length of a datagram's signature: truncated HMAC-SHA256."""
KEY_CONTEXT = b"teach-studio network bridge v1"
"""What :func:`bridge_key` mixes into the token, so the key signs only bridge frames."""


class WireError(ValueError):
    """A datagram that does not decode; the message says why."""


def bridge_key(token: str) -> bytes:
    """The key that signs bridge datagrams, derived from the studio's token (the token itself
    never goes on the wire)."""
    return hmac.new(token.encode(), KEY_CONTEXT, hashlib.sha256).digest()


def _signature(key: bytes, signed_part: bytes) -> bytes:
    return hmac.new(key, signed_part, hashlib.sha256).digest()[:SIGNATURE_BYTES]


def encode_frame(frame: TapeFrame, key: bytes | None = None) -> bytes:
    """One datagram for ``frame`` (angles rounded to float32), signed when given a ``key``
    (:func:`bridge_key`)."""
    regions = frame.bend.shape[0]
    flags = SIGNED if key is not None else 0
    head = HEADER.pack(
        MAGIC,
        WIRE_VERSION,
        flags,
        regions,
        frame.frame & 0xFFFFFFFF,
        frame.t,
        frame.status & 0xFFFF,
    )
    data = head + np.concatenate([frame.bend, frame.twist]).astype(">f4").tobytes()
    return data + _signature(key, data) if key is not None else data


def decode_frame(data: bytes, key: bytes | None = None) -> TapeFrame:
    """The frame in a datagram; given a ``key`` (:func:`bridge_key`), only a datagram signed with
    it.

    Raises:
        WireError: the datagram is malformed or, given a key, unsigned or signed with another
            (the message says which).
    """
    if len(data) < HEADER.size:
        raise WireError(f"{len(data)} bytes is shorter than the {HEADER.size}-byte header")
    magic, version, flags, regions, counter, t, status = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise WireError(f"magic {magic!r} is not {MAGIC!r}")
    if version < 1 or version > WIRE_VERSION:
        raise WireError(
            f"wire version {version} is not supported (this studio reads 1..{WIRE_VERSION})"
        )
    if not 1 <= regions <= MAX_REGIONS:
        raise WireError(f"{regions} regions is outside 1..{MAX_REGIONS}")
    signed = bool(flags & SIGNED)
    expected = HEADER.size + 8 * regions + (SIGNATURE_BYTES if signed else 0)
    if len(data) != expected:
        raise WireError(f"{len(data)} bytes where {regions} regions need {expected}")
    if key is not None:
        if not signed:
            raise WireError(
                "an unsigned frame, where this studio takes only frames signed with its token "
                "(give the sender the token: studio bridge --token)"
            )
        body = data[:-SIGNATURE_BYTES]
        if not hmac.compare_digest(_signature(key, body), data[-SIGNATURE_BYTES:]):
            raise WireError(
                "a frame signed with another token (give the sender this studio's token)"
            )
    count = 2 * regions
    angles = np.frombuffer(data, dtype=">f4", count=count, offset=HEADER.size).astype(np.float64)
    if not np.isfinite(angles).all() or not np.isfinite(t):
        raise WireError("a NaN or infinite value")
    return TapeFrame(float(t), int(counter), angles[:regions], angles[regions:], int(status))


RECEIVE_POLL_SECONDS = 0.1
"""Socket timeout: how quickly the receiver notices a stop request."""
SILENCE_SECONDS = 2.0
"""After this long without a datagram, the status reports that the sender went quiet."""
MAX_DATAGRAM_BYTES = 65535
"""Largest UDP payload."""
MAX_COUNTER_GAP = 10_000
"""A larger jump in the frame counter is a restarted sender, not lost frames."""


class NetworkSource(ThreadedSource[TapeFrame]):
    """Tape frames from UDP datagrams (wire format in :mod:`studio.capture._network`).

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
