"""A full disk is one sentence on every write path, leaves nothing half-made, and a capture it
stops keeps its frames and shows why on the page until dismissed.

The disk is "filled" by making every write to a file under the data folder fail with ENOSPC
(``open``/``os.fdopen`` for writing, ``os.write``, ``os.sendfile``), as a full disk would."""

from __future__ import annotations

import builtins
import errno
import io
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from studio.web._errors import StorageError, storage_sentence
from tests.web.conftest import TINY_RUN, wait_for

SAMPLES = Path(__file__).resolve().parents[2] / "studio" / "samples"


def _full() -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


class _FullFile:
    """A file opened for writing on a full disk: every write fails."""

    def __init__(self, f: io.IOBase) -> None:
        self._f = f

    def write(self, *args: object) -> int:
        raise _full()

    def __getattr__(self, name: str) -> object:
        return getattr(self._f, name)

    def __enter__(self) -> _FullFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self._f.close()


@contextmanager
def disk_full(monkeypatch: pytest.MonkeyPatch, folder: Path) -> Iterator[None]:
    """Make writes to files under ``folder`` fail with ENOSPC while the block runs."""
    folder = folder.resolve()
    real_open, real_write, real_sendfile = io.open, os.write, os.sendfile

    def under(fd_or_path: int | str | os.PathLike) -> bool:
        try:
            where = (
                os.readlink(f"/proc/self/fd/{fd_or_path}")
                if isinstance(fd_or_path, int)
                else os.path.abspath(os.fspath(fd_or_path))
            )
        except (OSError, TypeError):
            return False
        return where.startswith(f"{folder}{os.sep}")

    def opened(file, mode="r", *args, **kwargs):
        f = real_open(file, mode, *args, **kwargs)
        return _FullFile(f) if any(c in mode for c in "wax+") and under(file) else f

    def write(fd: int, data: bytes) -> int:
        if under(fd):
            raise _full()
        return real_write(fd, data)

    def sendfile(out_fd: int, in_fd: int, offset, count: int) -> int:
        if under(out_fd):
            raise _full()
        return real_sendfile(out_fd, in_fd, offset, count)

    with monkeypatch.context() as m:
        m.setattr(io, "open", opened)
        m.setattr(builtins, "open", opened)
        m.setattr(os, "write", write)
        m.setattr(os, "sendfile", sendfile)
        yield


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def _is_the_sentence(detail: str, data_dir: Path) -> None:
    assert detail.startswith(f"The disk holding {data_dir.resolve()} is full")
    assert detail.endswith("free some space and try again.")
    assert "\n" not in detail and "Traceback" not in detail


def test_the_sentence() -> None:
    folder = Path("/data")
    assert (
        storage_sentence(_full(), folder, "12 frames kept", "record again")
        == "The disk holding /data is full: 12 frames kept; free some space and record again."
    )
    assert "read-only" in storage_sentence(OSError(errno.EROFS, "x"), folder)
    assert "quota" in storage_sentence(OSError(errno.EDQUOT, "x"), folder)
    assert "permissions" in storage_sentence(PermissionError(errno.EACCES, "x"), folder)
    assert storage_sentence(OSError(errno.EIO, "x"), folder) is None
    assert storage_sentence(ValueError("bad"), folder) is None
    # the capture writer quotes the strerror in its own error
    quoted = RuntimeError(f"cannot write x.tape.csv ({os.strerror(errno.ENOSPC)}); ...")
    assert "is full" in storage_sentence(quoted, folder)


def _sample_recording() -> Path:
    return SAMPLES / "sample-reach-1.tape.csv"


def _write_paths(client: TestClient) -> dict[str, Callable[[], object]]:
    """Every write path of the API but captures and runs (tested on their own)."""
    recording = _sample_recording()

    def upload_recording():
        return client.post(
            "/api/recordings", files={"file": ("new.tape.csv", recording.read_bytes())}
        )

    def upload_policy():
        policy = next((client.app.state.studio.settings.runs_dir).rglob("*.policy.npz"))
        return client.post("/api/policies", files={"file": ("p.policy.npz", policy.read_bytes())})

    return {
        "upload a recording": upload_recording,
        "upload a policy": upload_policy,
        "edit notes": lambda: client.patch("/api/recordings/mine", json={"notes": "full"}),
        "copy a sample": lambda: client.post("/api/recordings/sample-reach-1/copy"),
        "cut a demonstration": lambda: client.post(
            "/api/demonstrations",
            json={"recording": "mine", "t0": 1.0, "t1": 3.4, "goal_from_end": True},
        ),
    }


@pytest.mark.parametrize(
    "path",
    [
        "upload a recording",
        "upload a policy",
        "edit notes",
        "copy a sample",
        "cut a demonstration",
    ],
)
def test_every_write_path_is_one_sentence_and_leaves_nothing(
    client: TestClient, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, path: str
) -> None:
    assert (
        client.post("/api/recordings/sample-reach-1/copy", json={"name": "mine"}).status_code == 201
    )
    run = client.post("/api/runs", json=TINY_RUN).json()["id"]
    assert client.app.state.studio.runs.wait_idle(60)
    assert client.get(f"/api/runs/{run}").json()["has_policy"]
    before = _files(tmp_path)
    with disk_full(monkeypatch, tmp_path):
        answer = _write_paths(client)[path]()
    assert answer.status_code == StorageError.status_code, answer.text
    _is_the_sentence(answer.json()["detail"], tmp_path)
    assert _files(tmp_path) == before  # nothing half-made, nothing changed
    # and once there is room again, the same request works
    again = _write_paths(client)[path]()
    assert again.status_code in (200, 201), again.text


def test_a_capture_stopped_by_a_full_disk_keeps_its_frames_and_says_so(
    open_client: Callable[..., TestClient], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    client = open_client(source="simulator")
    assert client.post("/api/capture/start", json={"name": "take"}).status_code == 200
    assert wait_for(lambda: client.get("/api/capture").json()["frames"] > 200)
    with disk_full(monkeypatch, tmp_path):
        assert wait_for(lambda: not client.get("/api/capture").json()["active"])
    capture = client.get("/api/capture").json()
    error = capture["error"]
    recordings = tmp_path / "recordings"
    assert error.startswith(f"The disk holding {recordings.resolve()} is full: ")
    assert error.endswith("frames kept; free some space and record again.")
    kept = int(error.split(" frames kept")[0].rsplit(" ", 1)[1])
    assert kept > 0
    listed = client.get("/api/recordings/take").json()
    assert listed["frames"] == kept and listed["recovered"]
    # the live fit goes on and never clears it; the page shows it until dismissed
    frames = client.get("/api/source").json()["frames"]
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > frames + 50)
    assert client.get("/api/capture").json()["error"] == error
    assert client.delete("/api/capture/error").status_code == 204
    assert client.get("/api/capture").json()["error"] is None
    # a new capture works once there is room again
    assert client.post("/api/capture/start", json={"name": "take-2"}).status_code == 200
    assert client.post("/api/capture/stop").status_code == 200


@pytest.mark.parametrize("fmt", ["csv", "mcap", "lerobot"])
def test_a_full_temporary_folder_is_blamed_not_the_data_folder(
    client: TestClient, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fmt: str
) -> None:
    """A download is written in the temporary folder: with that one full, the answer once named
    the data folder's disk (which had room), or spoke the command line's words (--out)."""
    import tempfile

    temporary = tmp_path / "temporary"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    with disk_full(monkeypatch, temporary):
        r = client.get(f"/api/robot/export/demonstration/sample-reach-1?format={fmt}")
    assert r.status_code == 507, r.text
    detail = r.json()["detail"]
    assert detail.startswith(f"The disk holding the temporary folder {temporary} is full")
    assert str(tmp_path / "recordings") not in detail and "--out" not in detail
    assert "\n" not in detail
    assert _files(temporary) == []  # nothing half-made left behind
    ok = client.get(f"/api/robot/export/demonstration/sample-reach-1?format={fmt}")
    assert ok.status_code == 200  # room again: the same export works
