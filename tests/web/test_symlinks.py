"""Symbolic links in the data folder are never followed.

The default data folder is the current folder, so an unpacked archive can carry a link such as
``recordings/evil.tape.csv -> /etc/passwd``. The stores list such a link as damaged, never read,
serve or change what it points to, and deleting it removes the link only.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

SECRET = "root:x:0:0:secret line\n"


@pytest.fixture
def secret(tmp_path: Path) -> Path:
    """A file outside the data folder that no request may reveal."""
    path = tmp_path.parent / f"{tmp_path.name}-outside.txt"
    path.write_text(SECRET)
    yield path
    path.unlink(missing_ok=True)


STORES = [
    ("recordings", "evil.tape.csv", "/api/recordings", "/api/recordings/evil/file"),
    ("recordings", "evil.demo.json", "/api/demonstrations", "/api/demonstrations/evil"),
    ("policies", "evil.policy.npz", "/api/policies", "/api/policies/evil/file"),
]


@pytest.mark.parametrize(("folder", "file", "listing", "read"), STORES)
def test_a_link_in_a_store_is_listed_as_damaged_and_never_followed(
    open_client, tmp_path, secret, folder, file, listing, read
):
    (tmp_path / folder).mkdir(exist_ok=True)
    link = tmp_path / folder / file
    os.symlink(secret, link)
    client = open_client()

    entry = {e["name"]: e for e in client.get(listing).json()}["evil"]
    assert "symbolic link" in entry["error"]
    response = client.get(read)
    assert response.status_code == 409, response.text
    assert SECRET not in response.text and "symbolic link" in response.json()["detail"]
    if folder == "recordings" and file.endswith(".tape.csv"):
        response = client.patch("/api/recordings/evil", json={"notes": "x"})
        assert response.status_code == 409 and secret.read_text() == SECRET

    assert client.delete(f"{listing}/evil").status_code == 204  # the link only
    assert not link.is_symlink() and secret.read_text() == SECRET
