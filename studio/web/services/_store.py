"""The on-disk stores under the data directory: one mechanism for recordings, demonstrations and
policies.

Everything a user makes lives in plain files so it survives a restart and can be used without the
studio: ``recordings/*.tape.csv``, ``recordings/*.demo.json``, ``policies/*.policy.npz``. Each
kind is a :class:`FolderStore`: a folder, a file suffix and the owning package's reader
(:mod:`studio.capture` for recordings and demonstrations, :mod:`studio.learning` for policies).
Training runs have their own store in :mod:`studio.web.services._runs`.

Names are plain file stems (letters, digits, ``-``, ``_``, ``.``; no separators, no ``..``), so a
name from a request can never point outside its folder. New files never replace old ones: an
upload or a new capture whose name is taken gets ``-2``, ``-3``, ... appended, and a file appears
under its name by a hard link that fails if the name was taken meanwhile (by another studio on
the same folder, say).

A symbolic link in a store's folder is never followed: it is listed as damaged (the studio reads
only regular files there), never read, served or changed, and deleting it removes the link only.

The shipped samples (:data:`studio.samples.SAMPLES_DIR`) are offered by every data folder as a
read-only group: names starting with ``sample-`` belong to it, can be played, trained on and
copied, never changed or deleted.

A store announces its own changes: every file it adds, changes or deletes calls its
``on_change`` with the list's name (``"recordings"``, ...), as the run queue does for runs, and
it refuses to delete a file its ``in_use`` names a reason for (a recording the live source
plays, a demonstration a queued run replays, a policy playing in the scene).
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import threading
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Generic, Protocol, TypeVar

from fastapi import UploadFile

from studio import StudioError, human_size
from studio.capture import (
    DEMO_SUFFIX,
    RECORDING_SUFFIX,
    RECORDING_SUFFIXES,
    Demonstration,
    being_recorded,
    delete_recording,
    rename_recording,
    summarize_any_recording,
    update_recording_meta,
)
from studio.learning import POLICY_SUFFIX, AnyPolicy, load_any_policy
from studio.motion import checked_demonstration
from studio.samples import SAMPLES_DIR

from .._errors import ConflictError, InvalidError, NotFoundError, TooLargeError
from ._changes import OnChange

log = logging.getLogger(__name__)

NAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}$")
"""A valid name: 1-100 characters, letters, digits, ``-``, ``_``, ``.``, not starting with ``.``."""
SAMPLE_PREFIX = "sample-"
"""Names of the shipped samples start with this prefix; users' files never do."""
UPLOAD_CHUNK_BYTES = 1024 * 1024
DEMONSTRATION_SUFFIX = DEMO_SUFFIX
"""Demonstrations lie next to their recordings: ``<name>.demo.json`` (the capture package's)."""

T = TypeVar("T")
InUse = Callable[[str], "str | None"]
"""Why a file cannot be deleted or renamed now (one sentence with the fix), or None."""
RecordingSummary = dict[str, object]
"""A recording's listing facts, as :func:`studio.capture.summarize_any_recording` gives them."""


def symlink_text(path: Path) -> str:
    """The refusal of a symbolic link found in a data folder."""
    return (
        f"{path.name} is a symbolic link, which the studio never follows in its data folder; "
        "put the file itself there, or delete the link."
    )


def link_new(tmp: Path, final: Path) -> bool:
    """Give the file ``tmp`` the name ``final`` unless that name is taken (never replacing a
    file, even one that appeared a moment ago); whether it did. ``tmp`` is left in place."""
    try:
        os.link(tmp, final)
    except FileExistsError:
        return False
    return True


def check_name(name: str, what: str = "name") -> str:
    """Return ``name`` if it is a plain file stem, else raise a 422 naming the rule."""
    if not isinstance(name, str) or ".." in name or "/" in name or "\\" in name:
        raise InvalidError(
            f"The {what} {name!r} contains a path separator or '..'; use only letters, digits, '-', '_' and '.'."
        )
    if not NAME_PATTERN.match(name):
        raise InvalidError(
            f"The {what} {name!r} is not allowed; use 1 to 100 letters, digits, '-', '_' or '.', not starting with '.'."
        )
    return name


def clean_upload_name(filename: str | None, suffix: str, fallback: str) -> str:
    """The store name for an uploaded file: its stem with odd characters replaced by ``-``.

    A file name holding a path separator or ``..`` is refused (422): browsers send bare names,
    so such a name is a crafted request. The samples' prefix is dropped, so an uploaded copy of a
    sample becomes the user's own file.
    """
    filename = filename or ""
    if "/" in filename or "\\" in filename or ".." in filename:
        raise InvalidError(
            f"The file name {filename!r} contains a path separator or '..'; upload a file with a plain name."
        )
    stem = filename[: -len(suffix)] if filename.endswith(suffix) else Path(filename).stem
    for extra in (".tape", ".pose", ".hand", ".policy", ".demo"):
        stem = stem.removesuffix(extra)
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "-", stem).strip("-.")[:80]
    return _user_name(stem) or fallback


def _user_name(name: str) -> str:
    """``name`` without the samples' prefix (and the separators that then lead it)."""
    while name.startswith(SAMPLE_PREFIX):
        name = name.removeprefix(SAMPLE_PREFIX).lstrip("-.")
    return name


def unique_name(base: str, taken: Callable[[str], bool]) -> str:
    """``base``, or ``base-2``, ``base-3``, ... : the first that is not ``taken``."""
    if not taken(base):
        return base
    k = 2
    while taken(f"{base}-{k}"):
        k += 1
    return f"{base}-{k}"


async def receive_upload(upload: UploadFile, folder: Path, limit: int) -> Path:
    """Stream an upload into a hidden temporary file in ``folder``, refusing more than ``limit`` bytes.

    Returns:
        The temporary file; the caller validates it and moves it to its final name (or deletes it).

    Raises:
        TooLargeError: the upload is over ``limit`` (nothing is kept).
    """
    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / f".upload-{uuid.uuid4().hex}.tmp"
    size = 0
    try:
        with tmp.open("wb") as out:
            while chunk := await upload.read(UPLOAD_CHUNK_BYTES):
                size += len(chunk)
                if size > limit:
                    raise TooLargeError(
                        f"The upload is larger than the limit of {human_size(limit)}; upload a smaller file or start the studio with a larger limit."
                    )
                out.write(chunk)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    if size == 0:
        tmp.unlink(missing_ok=True)
        raise InvalidError("The uploaded file is empty; choose a non-empty file.")
    return tmp


@dataclass(frozen=True)
class StoredFile(Generic[T]):
    """One file of a store as a listing shows it: read by its owner, or damaged with the reason.

    Attributes:
        name: the file's name in the store (its stem).
        path: where it lies.
        size_bytes: its size.
        sample: whether it is one of the read-only shipped samples.
        value: what the store's reader returned (None when damaged).
        error: why the reader refused it (None when readable).
    """

    name: str
    path: Path
    size_bytes: int
    sample: bool
    value: T | None = None
    error: str | None = None


class _FileCache(Generic[T]):
    """What a reader made of each file, its value or its refusal, read again only when the
    file's size or mtime changes (so a damaged file is not parsed again at every listing)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._entries: dict[Path, tuple[tuple[int, int], T | StudioError]] = {}

    def get(self, path: Path, load: Callable[[Path], T]) -> T:
        stat = path.stat()
        key = (stat.st_mtime_ns, stat.st_size)
        with self._lock:
            hit = self._entries.get(path)
        if hit is None or hit[0] != key:
            read: T | StudioError
            try:
                read = load(path)
            except StudioError as err:
                read = err
            hit = (key, read)
            with self._lock:
                self._entries[path] = hit
        if isinstance(hit[1], StudioError):
            raise hit[1]
        return hit[1]

    def forget_missing(self) -> None:
        """Drop the entries of files that no longer exist (deleted or renamed)."""
        with self._lock:
            paths = list(self._entries)
        gone = [path for path in paths if not path.exists()]
        with self._lock:
            for path in gone:
                self._entries.pop(path, None)


class FolderStore(Generic[T]):
    """Files ``<folder>/<name><suffix>`` of one kind, plus the shipped samples of that kind.

    Args:
        folder: the user's folder (created by the studio at start).
        suffix: the file suffix, e.g. ``.tape.csv``.
        what: the kind in messages, e.g. ``"recording"``.
        plural: the list's name in messages, e.g. ``"recordings"``.
        load: the owning package's reader of one file; it raises :class:`studio.StudioError`
            with one sentence for a damaged file. Its result is cached per file until the file
            changes.
        samples: a read-only folder of shipped samples (names starting with ``sample-``), or None.
        sample_fix: what to do instead of changing a sample, the second half of the refusal.
        remove: deletes one of the user's files (default: unlink it); raises a
            :class:`studio.StudioError` to refuse.
        also: further suffixes of the same kind (recordings of landmarks and hand poses beside
            the tape's); a name is unique across all of them.
        on_change: called with ``plural`` after each file added, changed or deleted.
        in_use: why a file cannot be deleted now, or None (default: never in use).
    """

    def __init__(
        self,
        folder: Path,
        *,
        suffix: str,
        what: str,
        plural: str,
        load: Callable[[Path], T],
        samples: Path | None = None,
        sample_fix: str = "copy it to make your own",
        remove: Callable[[Path], None] = Path.unlink,
        also: tuple[str, ...] = (),
        on_change: OnChange | None = None,
        in_use: InUse | None = None,
    ) -> None:
        self.folder = folder
        self.suffix = suffix
        self.suffixes = (suffix, *(s for s in also if s != suffix))
        self.what = what
        self.plural = plural
        self.samples = samples
        self.sample_fix = sample_fix
        self._load = load
        self._remove = remove
        self._cache: _FileCache[T] = _FileCache()
        self._claim_lock = threading.Lock()  # choosing a free name and taking it are one step
        self.on_change = on_change
        self._in_use = in_use

    def changed(self, plural: str | None = None) -> None:
        """Announce that the list ``plural`` (default: this store's) changed."""
        if self.on_change is not None:
            self.on_change(plural or self.plural)

    def in_use(self, name: str) -> str | None:
        """Why ``name`` cannot be deleted now (one sentence with the fix), or None."""
        return self._in_use(name) if self._in_use is not None else None

    # ------------------------------------------------------------------ names and paths

    def _stems(self, folder: Path | None) -> list[str]:
        if folder is None or not folder.is_dir():
            return []
        stems = (
            p.name[: -len(suffix)] for suffix in self.suffixes for p in folder.glob(f"*{suffix}")
        )
        return [s for s in stems if NAME_PATTERN.match(s)]

    def _find(self, name: str) -> Path | None:
        """The file of ``name`` (a symbolic link too, which callers refuse to follow)."""
        for folder in (self.folder, self.samples):
            if folder is None:
                continue
            for suffix in self.suffixes:
                path = folder / f"{name}{suffix}"
                if path.is_symlink() or path.is_file():
                    return path
        return None

    def stem_of(self, filename: str) -> str:
        """``filename`` without the store's suffix it ends with (the name it is listed under)."""
        return filename.removesuffix(self.suffix_of(filename))

    def suffix_of(self, filename: str) -> str:
        """The suffix of this store that ``filename`` ends with (the main one if none)."""
        return next((s for s in self.suffixes if filename.endswith(s)), self.suffix)

    def names(self) -> list[str]:
        """Every name: the samples first, then the user's files, each group alphabetical."""
        samples = [s for s in self._stems(self.samples) if s.startswith(SAMPLE_PREFIX)]
        names = set(self._stems(self.folder)) | set(samples)  # a stem with two suffixes: once
        return sorted(names, key=lambda n: (not self.is_sample(n), n))

    def exists(self, name: str) -> bool:
        """Whether ``name`` is taken, by a user's file or a sample."""
        return NAME_PATTERN.match(name) is not None and self._find(name) is not None

    @staticmethod
    def is_sample(name: str) -> bool:
        """Whether ``name`` is a read-only shipped sample."""
        return name.startswith(SAMPLE_PREFIX)

    def _located(self, name: str) -> Path:
        """The file of ``name``, a symbolic link included (422 for a bad name, 404 if none)."""
        path = self._find(check_name(name, f"{self.what} name"))
        if path is None:
            raise NotFoundError(
                f"There is no {self.what} named {name!r}; pick one from the {self.plural} list."
            )
        return path

    def path(self, name: str) -> Path:
        """The file of ``name``, a user's file or a sample, to read or serve (422 for a bad
        name, 404 if none, 409 for a symbolic link, which is never followed)."""
        path = self._located(name)
        if path.is_symlink():
            raise ConflictError(symlink_text(path))
        return path

    def writable_path(self, name: str) -> Path:
        """The file of ``name`` for a change (404 if none, 409 for a sample or a symbolic link)."""
        path = self.path(name)
        self._check_writable(name)
        return path

    def check_deletable(self, name: str) -> None:
        """Refuse what :meth:`delete` would refuse before trying (404 if none, 409 for a
        sample); a symbolic link may be deleted (the link only)."""
        self._located(name)
        self._check_writable(name)

    def _check_writable(self, name: str) -> None:
        if self.is_sample(name):
            raise ConflictError(
                f"The {self.what} {name!r} is a shipped sample, which cannot be changed or deleted; {self.sample_fix}."
            )

    def check_new_name(self, name: str) -> str:
        """Return ``name`` if a new user file may take it (422 for a bad or sample name, 409 if taken)."""
        check_name(name, f"{self.what} name")
        if self.is_sample(name):
            raise InvalidError(
                f"The {self.what} name {name!r} starts with {SAMPLE_PREFIX!r}, which is kept for the shipped samples; choose another name."
            )
        if self.exists(name):
            raise ConflictError(
                f"A {self.what} named {name!r} already exists; choose another name."
            )
        return name

    def new_name(self, base: str) -> str:
        """A free name for a new user file starting with ``base`` (the samples' prefix dropped)."""
        check_name(base, f"{self.what} name")
        return unique_name(_user_name(base) or self.what, self.exists)

    # ------------------------------------------------------------------ reading

    def load(self, name: str) -> T:
        """What the owning package's reader returns for ``name`` (cached until the file changes)."""
        return self.load_file(self.path(name))

    def load_file(self, path: Path) -> T:
        """What the reader returns for any file of this kind (a run's policy too), cached.

        Raises:
            StudioError: the reader's one sentence about a damaged file; a failure the reader
                did not foresee becomes an :class:`InvalidError` naming the file.
        """
        if path.is_symlink():  # never read through a link (a run's policy too)
            raise ConflictError(symlink_text(path))
        return self._cache.get(path, self._read)

    def _read(self, path: Path) -> T:
        try:
            return self._load(path)
        except (StudioError, FileNotFoundError):
            raise
        except Exception as err:  # a damage the reader did not foresee must not hide the others
            log.warning("could not read %s: %s: %s", path, type(err).__name__, err)
            raise InvalidError(
                f"{path.name} could not be read as a {self.what} ({type(err).__name__}); replace or delete the file."
            ) from None

    def entry(self, name: str) -> StoredFile[T]:
        """``name`` as a listing shows it (404 if it does not exist; a link: damaged)."""
        return self.entry_at(name, self._located(name))

    def entry_at(self, name: str, path: Path) -> StoredFile[T]:
        """The file at ``path`` as a listing shows it under ``name`` (e.g. a run's policy)."""
        size = path.lstat().st_size
        sample = self.is_sample(name)
        try:
            value = self.load_file(path)
        except StudioError as err:
            return StoredFile(name, path, size, sample, error=str(err))
        return StoredFile(name, path, size, sample, value=value)

    def entries(self) -> list[StoredFile[T]]:
        """Every file, samples first: each read, or listed as damaged with the reason."""
        out = []
        for name in self.names():
            path = self._find(name)
            if path is None:
                continue
            try:
                out.append(self.entry_at(name, path))
            except FileNotFoundError:  # deleted meanwhile
                continue
        self._cache.forget_missing()
        return out

    # ------------------------------------------------------------------ changing

    def delete(self, name: str) -> None:
        """Delete a user's file (404 if none, 409 for a sample or while :meth:`in_use` gives a
        reason); a symbolic link is removed itself, never what it points to. The store's
        ``remove`` does the deleting (for recordings it refuses a file a capture holds)."""
        self.check_deletable(name)
        reason = self.in_use(name)
        if reason:
            raise ConflictError(reason)
        path = self._located(name)
        if path.is_symlink():
            path.unlink()
        else:
            self._remove(path)
        self.changed()

    def adopt(
        self, tmp: Path, filename: str | None, taken: Callable[[str], bool] | None = None
    ) -> str:
        """Check an uploaded temporary file with the owner's reader and give it a free name.

        Args:
            tmp: the received file (see :func:`receive_upload`), in this store's folder.
            filename: the name the browser sent.
            taken: whether a name is used (default: :meth:`exists`).

        Returns:
            The new file's name.

        Raises:
            InvalidError: a bad file name, or the reader refuses the file (the temporary file is
                removed either way).
        """
        label = filename or "the upload"
        try:
            suffix = self.suffix_of(filename or "")
            base = clean_upload_name(filename, suffix, self.what)
            try:
                self._read(tmp)
            except StudioError as err:
                message = str(err).replace(str(tmp), label).replace(tmp.name, label)
                if not message.startswith(label):  # the reader's sentence names the file itself
                    message = f"{label} is not a valid Teach Studio {self.what}: {message}"
                raise InvalidError(message) from None
            return self.claim(tmp, base, taken, suffix=suffix)
        finally:
            tmp.unlink(missing_ok=True)

    def copy(
        self,
        name: str,
        new_name: str | None = None,
        prepare: Callable[[Path, str], None] | None = None,
    ) -> str:
        """Copy ``name`` (a sample or a user's file) into the user's folder; returns the copy's name.

        Args:
            name: the file to copy.
            new_name: the copy's name (default: ``name`` without the samples' prefix, made free).
            prepare: called with the temporary copy and its final name before it appears, e.g.
                to write the new name into the file's header.
        """
        source = self.path(name)
        if new_name is not None:
            self.check_new_name(new_name)
        self.folder.mkdir(parents=True, exist_ok=True)
        tmp = self.folder / f".copy-{uuid.uuid4().hex}.tmp"
        try:
            shutil.copyfile(source, tmp)
            with self._claim_lock:
                final = new_name or self.new_name(name)
                if prepare is not None:
                    prepare(tmp, final)
                if self.exists(final) or not link_new(
                    tmp, self.folder / f"{final}{self.suffix_of(source.name)}"
                ):
                    raise ConflictError(
                        f"A {self.what} named {final!r} already exists; choose another name."
                    )
            self.changed()
            return final
        finally:
            tmp.unlink(missing_ok=True)

    def claim(
        self,
        tmp: Path,
        base: str,
        taken: Callable[[str], bool] | None = None,
        exact: bool = False,
        suffix: str | None = None,
    ) -> str:
        """Give the finished file ``tmp`` (in this store's folder) a free name; returns it.

        The name is ``base``, else ``base-2``, ``base-3``, ... ; with ``exact`` only ``base``
        (409 when taken). The file gets ``suffix`` (default: the store's main one). A name taken
        meanwhile, by another studio too, is never replaced. ``tmp`` is removed either way.
        """
        taken = taken or self.exists
        try:
            with self._claim_lock:
                while True:
                    name = (
                        base if exact else unique_name(base, lambda n: taken(n) or self.exists(n))
                    )
                    if not (exact and taken(name)) and link_new(
                        tmp, self.folder / f"{name}{suffix or self.suffix}"
                    ):
                        self.changed()
                        return name
                    if exact:
                        raise ConflictError(
                            f"A {self.what} named {name!r} already exists; choose another name."
                        )
        finally:
            tmp.unlink(missing_ok=True)


class LiveRecordings(Protocol):
    """What holds a recording in this studio (the live pipeline): the one its source plays and
    the one its capture writes."""

    @property
    def recording(self) -> str | None:
        """The recording the live source plays, or None."""

    @property
    def capture_name(self) -> str | None:
        """The recording being captured, or None."""


class RecordingStore(FolderStore[RecordingSummary]):
    """Recordings ``<folder>/<name>.tape.csv`` (and ``.pose.csv``, ``.hand.csv``), each cached as
    the capture package's summary, which knows which ones are in use and renames a recording
    with the demonstrations cut from it.

    :func:`studio.capture.summarize_recording` streams the whole file (so damage shows) in one
    block of memory, however long the recording.

    Args:
        folder: the user's recordings (demonstrations lie beside them).
        live: what this studio plays and captures (None: nothing).
        on_change: called with ``"recordings"`` (and ``"demonstrations"`` when a rename changed
            theirs).
    """

    def __init__(
        self,
        folder: Path,
        live: LiveRecordings | None = None,
        on_change: OnChange | None = None,
    ) -> None:
        super().__init__(
            folder,
            suffix=RECORDING_SUFFIX,
            what="recording",
            plural="recordings",
            load=summarize_any_recording,
            samples=SAMPLES_DIR,
            sample_fix="copy it to your recordings to change it",
            remove=delete_recording,
            also=RECORDING_SUFFIXES,
            on_change=on_change,
        )
        self.live = live

    def _capturing(self) -> str | None:
        return self.live.capture_name if self.live is not None else None

    def in_use(self, name: str) -> str | None:
        """Why this studio holds recording ``name`` (it is the live source, or being captured),
        or None. A capture by another process is refused by its writer's lock when deleting
        (:func:`studio.capture.delete_recording`), and by :meth:`busy` before a change."""
        if self.live is not None and self.live.recording == name:
            return f"Recording {name!r} is the live source; switch the source to another one first."
        if self._capturing() == name:
            return f"Recording {name!r} is being captured; stop the recording first."
        return None

    def busy(self, name: str) -> str | None:
        """Why recording ``name`` cannot be renamed now, or None: :meth:`in_use`, or a capture
        by another studio (or ``studio record``) on the same data folder."""
        reason = self.in_use(name)
        if reason is None and self.captured_elsewhere(name):
            return f"Recording {name!r} is being captured by another studio or `studio record` on this data folder; stop that capture first."
        return reason

    def listed(self) -> list[str]:
        """The recordings to list: all but the one this studio is capturing (it is listed once
        the capture stops; its growing file is never read)."""
        capturing = self._capturing()
        return [name for name in self.names() if name != capturing]

    def captured_elsewhere(self, name: str) -> bool:
        """Whether another process (a second studio, ``studio record``) is capturing ``name``."""
        if self._capturing() == name:
            return False
        try:
            return being_recorded(self.path(name))
        except StudioError:  # missing, a link, not a regular file: nobody writes it
            return False

    def copy(
        self,
        name: str,
        new_name: str | None = None,
        prepare: Callable[[Path, str], None] | None = None,
    ) -> str:
        """Copy ``name`` into the user's recordings, its header naming the copy (see
        :meth:`FolderStore.copy`)."""

        def retitle(tmp: Path, final: str) -> None:
            update_recording_meta(tmp, name=final)
            if prepare is not None:
                prepare(tmp, final)

        return super().copy(name, new_name, prepare=retitle)

    def update(
        self,
        name: str,
        new_name: str | None = None,
        notes: str | None = None,
        operator: str | None = None,
    ) -> str:
        """Rename ``name`` and/or set its operator and notes; returns its name afterwards.

        The header is changed by an atomic replace, the frames are never touched; a rename also
        updates the demonstrations cut from the recording.

        Raises:
            ConflictError: a sample, being captured (here or elsewhere), a rename while it is in
                use, or the new name is taken.
            NotFoundError: no such recording, or it was deleted meanwhile.
            InvalidError: a bad new name.
        """
        path = self.writable_path(name)
        if self._capturing() == name or self.captured_elsewhere(name):
            raise ConflictError(
                self.busy(name)
                or f"Recording {name!r} is being captured; stop the recording first."
            )
        renaming = new_name is not None and new_name != name
        if new_name is not None and renaming:
            self.check_new_name(new_name)
            reason = self.busy(name)
            if reason:
                raise ConflictError(reason)
        changes = {k: v for k, v in (("notes", notes), ("operator", operator)) if v is not None}
        try:
            if changes:
                update_recording_meta(path, **changes)
            if new_name is not None and renaming:
                rename_recording(path, new_name)
                self.changed("demonstrations")  # their "recording" follows the rename
        except (StudioError, FileNotFoundError):
            if not path.exists():  # a DELETE won the race: say so, not "cannot open <path>"
                raise NotFoundError(
                    f"Recording {name!r} was deleted meanwhile; refresh the recordings list."
                ) from None
            raise
        finally:
            self.changed()
        return new_name if new_name is not None and renaming else name


def recording_store(
    folder: Path, live: LiveRecordings | None = None, on_change: OnChange | None = None
) -> RecordingStore:
    """The recordings in ``folder`` (see :class:`RecordingStore`)."""
    return RecordingStore(folder, live, on_change)


def demonstration_store(
    folder: Path, on_change: OnChange | None = None, in_use: InUse | None = None
) -> FolderStore[Demonstration]:
    """Demonstrations ``<folder>/<name>.demo.json``, next to the recordings they were cut from."""
    return FolderStore(
        folder,
        suffix=DEMONSTRATION_SUFFIX,
        what="demonstration",
        plural="demonstrations",
        load=checked_demonstration,
        samples=SAMPLES_DIR,
        sample_fix="cut your own from its recording instead",
        on_change=on_change,
        in_use=in_use,
    )


def policy_store(
    folder: Path, on_change: OnChange | None = None, in_use: InUse | None = None
) -> FolderStore[AnyPolicy]:
    """Policies ``<folder>/<name>.policy.npz`` of every kind the studio writes, tabular or
    tile-coded (runs keep theirs in their run folder; the store reads those too)."""
    return FolderStore(
        folder,
        suffix=POLICY_SUFFIX,
        what="policy",
        plural="policies",
        load=load_any_policy,
        on_change=on_change,
        in_use=in_use,
    )
