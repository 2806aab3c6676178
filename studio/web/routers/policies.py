"""``/api/policies``: uploaded policy files and every run's policy, to watch or download."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, File, Response, UploadFile
from fastapi.responses import FileResponse
from starlette.concurrency import run_in_threadpool

from studio.learning import POLICY_SUFFIX, AnyPolicy, policy_summary

from .._deps import SettingsDep, StudioDep
from .._schemas import PolicyPublic
from ..services import StoredFile, receive_upload
from . import file_responses

router = APIRouter(prefix="/api/policies", tags=["policies"])


def policy_public(
    entry: StoredFile[AnyPolicy], source: Literal["upload", "run"] = "upload"
) -> PolicyPublic:
    """The list entry of one policy file of either kind, from the learning package's summary.

    A damaged file keeps its name and size and says why it cannot be used.
    """
    summary = policy_summary(entry.value) if entry.value is not None else {}
    return PolicyPublic(
        name=entry.name,
        source=source,
        run=entry.name if source == "run" else None,
        size_bytes=entry.size_bytes,
        error=entry.error,
        **summary,
    )


@router.get("")
def list_policies(studio: StudioDep) -> list[PolicyPublic]:
    """Uploaded policies, then the policy of every run that has one (newest run first).

    A damaged file is listed with the reason; it stays on disk untouched.
    """
    out = [policy_public(entry) for entry in studio.policies.entries()]
    for run in studio.runs.list():
        if run.has_policy and run.status != "running":
            try:
                out.append(policy_public(studio.policies.entry_at(run.id, run.policy_path), "run"))
            except FileNotFoundError:  # the run was deleted meanwhile
                continue
    return out


@router.post("", status_code=201)
async def upload_policy(
    studio: StudioDep, settings: SettingsDep, file: Annotated[UploadFile, File()]
) -> PolicyPublic:
    """Upload a ``.policy.npz`` (413 over the limit, 422 if it is not a policy file).

    The name comes from the file name; a taken name (by a policy or a run) gets ``-2``, ``-3``,
    ... appended.
    """
    tmp = await receive_upload(file, studio.policies.folder, settings.upload_limit_bytes)

    def adopt() -> PolicyPublic:  # reading the file and the run folders: not on the loop
        taken = studio.policy_names()
        name = studio.policies.adopt(tmp, file.filename, lambda n: n in taken)
        return policy_public(studio.policies.entry(name))

    return await run_in_threadpool(adopt)


@router.get(
    "/{name}/file",
    response_class=FileResponse,
    responses=file_responses("application/octet-stream"),
)
def download_policy(name: str, studio: StudioDep) -> FileResponse:
    """The uploaded policy file."""
    return FileResponse(
        studio.policies.path(name),
        media_type="application/octet-stream",
        filename=f"{name}{POLICY_SUFFIX}",
    )


@router.delete("/{name}", status_code=204)
def delete_policy(name: str, studio: StudioDep) -> Response:
    """Delete an uploaded policy (409 while it plays in the scene; a run's policy goes with its run)."""
    studio.delete_policy(name)
    return Response(status_code=204)
