"""``/api/policies``: uploaded policy files and every run's policy, to watch or download."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Response, UploadFile
from fastapi.responses import FileResponse
from starlette.concurrency import run_in_threadpool

from studio.learning import POLICY_SUFFIX, AnyPolicy, policy_summary

from .._deps import PoliciesDep, SettingsDep
from .._schemas import PolicyPublic
from ..services import PolicySource, StoredFile, receive_upload
from . import file_responses

router = APIRouter(prefix="/api/policies", tags=["policies"])


def policy_public(entry: StoredFile[AnyPolicy], source: PolicySource = "upload") -> PolicyPublic:
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
def list_policies(policies: PoliciesDep) -> list[PolicyPublic]:
    """Uploaded policies, then the policy of every run that has one (newest run first).

    A damaged file is listed with the reason; it stays on disk untouched.
    """
    return [policy_public(entry, source) for entry, source in policies.listed()]


@router.post("", status_code=201)
async def upload_policy(
    policies: PoliciesDep, settings: SettingsDep, file: Annotated[UploadFile, File()]
) -> PolicyPublic:
    """Upload a ``.policy.npz`` (413 over the limit, 422 if it is not a policy file).

    The name comes from the file name; a taken name (by a policy or a run) gets ``-2``, ``-3``,
    ... appended.
    """
    tmp = await receive_upload(file, policies.store.folder, settings.upload_limit_bytes)

    def adopt() -> PolicyPublic:  # reading the file and the run folders: not on the loop
        return policy_public(policies.store.entry(policies.adopt(tmp, file.filename)))

    return await run_in_threadpool(adopt)


@router.get(
    "/{name}/file",
    response_class=FileResponse,
    responses=file_responses("application/octet-stream"),
)
def download_policy(name: str, policies: PoliciesDep) -> FileResponse:
    """The uploaded policy file."""
    return FileResponse(
        policies.store.path(name),
        media_type="application/octet-stream",
        filename=f"{name}{POLICY_SUFFIX}",
    )


@router.delete("/{name}", status_code=204)
def delete_policy(name: str, policies: PoliciesDep) -> Response:
    """Delete an uploaded policy (409 while it plays in the scene; a run's policy goes with its run)."""
    policies.delete(name)
    return Response(status_code=204)
