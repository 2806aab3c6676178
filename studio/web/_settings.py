"""The studio server's settings: one pydantic object, served to the routes through a dependency.

`studio serve` builds a :class:`Settings` from its flags and hands it to
:func:`studio.web.create_app`; tests build one with a temporary ``data_dir`` and
``allowed_hosts=["testserver"]`` (the host name FastAPI's ``TestClient`` sends).
"""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

from studio import is_loopback
from studio._layout import (
    POLICIES_DIR,
    RECORDINGS_DIR,
    RUNS_DIR,
    mesh_cache_dir,
    robot_cache_dir,
)

DEFAULT_UPLOAD_LIMIT_BYTES = 50_000_000
"""Largest accepted upload (recordings, policies): 50 MB, about 40 minutes of 110 Hz tape frames."""

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1", "[::1]")
"""Host names that always reach this machine only."""


class Settings(BaseModel):
    """Where the studio keeps its data and where it listens.

    Attributes:
        data_dir: holds ``recordings/`` (recordings and ``*.demo.json``), ``runs/`` and
            ``policies/``; the current directory by default.
        host: address both servers bind to; loopback unless the user opens it up.
        port: HTTP port of the page and the API.
        viser_port: port of the viser 3D scene server.
        upload_limit_bytes: uploads larger than this are refused with 413.
        source: the live source at start: ``"simulator"``, the name of a recording in
            ``recordings/``, or ``None`` for no live source (tests, headless use).
        allowed_hosts: extra ``Host`` header names accepted besides the loopback names and
            ``host`` (the DNS-rebinding guard refuses every other name).
        viser_url: the scene URL the page embeds; default ``http://<host>:<viser_port>``.
        run_workers: threads one training run uses (``None``: one per CPU core).
        scene_instance: the id the running scene server answers at ``/studio-instance``; the
            page checks it so that it never embeds another program's scene (set by
            :func:`studio.web.serve`; None: no scene, or not checked).
        token: when set, the scene answers only requests carrying it (``?token=`` or the cookie
            it sets); required when ``host`` or ``bridge_host`` is not loopback. The API's own
            check reads the same field.
        bridge_host: address the network-bridge source listens on: loopback unless the user
            asks otherwise; beyond loopback it takes only frames signed with ``token``.
    """

    model_config = ConfigDict(frozen=True)

    data_dir: Path = Path(".")
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=1, le=65535)
    viser_port: int = Field(8080, ge=1, le=65535)
    upload_limit_bytes: int = Field(DEFAULT_UPLOAD_LIMIT_BYTES, ge=1)
    source: str | None = "simulator"
    allowed_hosts: tuple[str, ...] = ()
    viser_url: str | None = None
    run_workers: int | None = Field(None, ge=1)
    scene_instance: str | None = None
    token: str | None = None
    bridge_host: str = "127.0.0.1"

    @property
    def recordings_dir(self) -> Path:
        """Recordings (``*.tape.csv``) and demonstrations (``*.demo.json``)."""
        return self.data_dir / RECORDINGS_DIR

    @property
    def runs_dir(self) -> Path:
        """One folder per training run."""
        return self.data_dir / RUNS_DIR

    @property
    def policies_dir(self) -> Path:
        """Uploaded policy files."""
        return self.data_dir / POLICIES_DIR

    @property
    def mesh_cache_dir(self) -> Path:
        """Where the drawn robots' simplified meshes are kept (a cache: safe to delete)."""
        return mesh_cache_dir(self.data_dir)

    @property
    def robot_cache_dir(self) -> Path:
        """Where the robots' built models and collision hulls are kept (a cache: safe to delete)."""
        return robot_cache_dir(self.data_dir)

    @property
    def is_loopback(self) -> bool:
        """Whether ``host`` only accepts connections from this machine."""
        return is_loopback(self.host)

    def trusted_hosts(self) -> list[str]:
        """Host header names the API answers (everything else gets 400)."""
        names = [*LOOPBACK_NAMES, *self.allowed_hosts]
        if self.host not in ("0.0.0.0", "::", ""):
            names.append(self.host)
        return list(dict.fromkeys(names))

    def scene_url(self) -> str:
        """The URL of the viser scene as the page should load it."""
        if self.viser_url:
            return self.viser_url
        host = "127.0.0.1" if self.host in ("0.0.0.0", "::", "") else self.host
        if ":" in host and not host.startswith("["):
            host = f"[{host}]"
        url = f"http://{host}:{self.viser_port}"
        return f"{url}/?token={self.token}" if self.token else url


def get_settings() -> Settings:
    """The settings of the running app; :func:`studio.web.create_app` overrides this dependency."""
    return Settings()
