"""``/api/policies``: uploaded policy files and every run's policy, to watch or download."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Response, UploadFile
from fastapi.responses import FileResponse

from .._deps import SettingsDep, StudioDep
from .._errors import ConflictError
from .._runs import Run
from .._state import Studio
from .._store import policy_summary, receive_upload

router = APIRouter(prefix="/api/policies", tags=["policies"])


def _public(studio: Studio, name: str) -> dict:
    path = studio.policies.path(name)
    return {
        "name": name,
        "source": "upload",
        "run": None,
        **policy_summary(studio.policies.load(name)),
        "size_bytes": path.stat().st_size,
    }


def _run_public(studio: Studio, run: Run) -> dict:
    return {
        "name": run.id,
        "source": "run",
        "run": run.id,
        **policy_summary(studio.policies.load_file(run.policy_path)),
        "size_bytes": run.policy_path.stat().st_size,
    }


@router.get("")
def list_policies(studio: StudioDep) -> list[dict]:
    """Uploaded policies, then the policy of every run that has one (newest run first)."""
    out = []
    for name in studio.policies.names():
        try:
            out.append(_public(studio, name))
        except Exception:  # an unreadable file is not listed; it stays on disk untouched
            continue
    for run in studio.runs.list():
        if run.has_policy and run.status != "running":
            try:
                out.append(_run_public(studio, run))
            except Exception:
                continue
    return out


@router.post("", status_code=201)
async def upload_policy(
    studio: StudioDep, settings: SettingsDep, file: Annotated[UploadFile, File()]
) -> dict:
    """Upload a ``.policy.npz`` (413 over the limit, 422 if it is not a policy file).

    The name comes from the file name; a taken name gets ``-2``, ``-3``, ... appended.
    """
    tmp = await receive_upload(file, studio.policies.folder, settings.upload_limit_bytes)
    taken = studio.policy_names()
    name = studio.policies.adopt(tmp, file.filename, lambda n: n in taken)
    studio.changes.bump("policies")
    return _public(studio, name)


@router.get("/{name}/file")
def download_policy(name: str, studio: StudioDep) -> FileResponse:
    """The uploaded policy file."""
    return FileResponse(
        studio.policies.path(name),
        media_type="application/octet-stream",
        filename=f"{name}.policy.npz",
    )


@router.delete("/{name}", status_code=204)
def delete_policy(name: str, studio: StudioDep) -> Response:
    """Delete an uploaded policy (409 while it plays in the scene; a run's policy goes with its run)."""
    if not studio.policies.exists(name) and name in {r.id for r in studio.runs.list()}:
        raise ConflictError(
            f"Policy {name!r} belongs to a run; delete the run to delete its policy."
        )
    studio.policies.path(name)
    if studio.policy_in_use(f"policy:{name}"):
        raise ConflictError(f"Policy {name!r} is playing in the scene; stop watching it first.")
    studio.policies.delete(name)
    studio.changes.bump("policies")
    return Response(status_code=204)
