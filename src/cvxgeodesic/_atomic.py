"""Atomic file output: a failure never leaves a half-written file behind, and a replaced file keeps its metadata.

Every output is written to a temporary file next to its target and renamed over it. The rename would
otherwise reset what the user set on the file it replaces, so:

- the new file gets the replaced file's permission bits, and its owner and group where the process may
  set them (as root; a user can only give a file their own uid and groups);
- a *read-only* target (no write bit for its owner, or not writable by this process) is refused with a
  :class:`~cvxgeodesic.errors.ParameterError` unless the caller passes ``overwrite_read_only=True``: the
  rename would replace it although the file itself forbids writing (the directory allows the rename).
"""

from __future__ import annotations

import os
import secrets
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO

from .errors import ParameterError

__all__ = ["atomic_write", "check_output_dir", "check_replaceable", "output_folder", "output_set", "probe_folder"]

#: How the library names the permission in a refusal; the command line names its flag instead.
ALLOW_IN_PYTHON = "overwrite_read_only=True"

# temporary paths of output_set blocks -> the metadata of the target each one will replace: a writer that goes
# through atomic_write into such a path gives its file the target's mode from the start, not only at the rename
_PENDING: dict[Path, os.stat_result] = {}


def check_replaceable(target: str | os.PathLike, *, overwrite_read_only: bool = False,
                      allow: str | None = ALLOW_IN_PYTHON) -> os.stat_result | None:
    """The status of an existing ``target`` (None when there is none), refusing a read-only one.

    Read-only means: no write bit for the file's owner (``chmod a-w``, mode 444), or no write permission
    for this process (``os.access``). The first rule is what a ``root`` process sees too: root may write
    any file, so the mode bits are the only sign that the owner wants the file kept.

    Parameters
    ----------
    target : str or os.PathLike
    overwrite_read_only : bool, default False
        Replace a read-only file anyway (it keeps its mode: still read-only afterwards).
    allow : str or None
        How the caller's user gives that permission, for the message (a keyword, a command-line flag);
        None: only "make it writable".

    Returns
    -------
    os.stat_result or None

    Raises
    ------
    ParameterError
        ``target`` is read-only and ``overwrite_read_only`` is False; the message names the file and its mode.
    """
    try:
        st = os.lstat(target)
    except (FileNotFoundError, NotADirectoryError):
        return None
    if not stat.S_ISREG(st.st_mode):
        # a symbolic link is replaced by the new file, not followed: its target's mode and owner are not the
        # replaced file's (copying them would let `-o x -> /usr/bin/passwd` give root's new file mode 4755)
        return None
    if overwrite_read_only:
        return st
    if not st.st_mode & stat.S_IWUSR:
        what, how = "is read-only", "make it writable (chmod u+w)"
    elif not os.access(target, os.W_OK):  # another user's file in a folder this one may write to
        what, how = "is not writable by this user", "make it writable for you"
    else:
        return st
    how += f" or allow it with {allow}" if allow else " first"
    raise ParameterError(f"{os.fspath(target)} {what} ({stat.filemode(st.st_mode)}): refusing to replace it; {how}")


def _give_metadata(fd: int, st: os.stat_result | None) -> None:
    """Give the open file ``fd`` the owner, group and mode of ``st`` (the file it will replace), before any data."""
    if st is None:
        return
    own = os.fstat(fd)
    if hasattr(os, "fchown") and (own.st_uid, own.st_gid) != (st.st_uid, st.st_gid):
        with suppress(PermissionError):  # not root: the new file is the writer's, as with any editor's save
            os.fchown(fd, st.st_uid, st.st_gid)
    # after chown, which clears set-id bits; AttributeError, PermissionError: no Unix modes (Windows, some mounts)
    with suppress(AttributeError, PermissionError):
        os.fchmod(fd, stat.S_IMODE(st.st_mode) & 0o777)  # permission bits only: never set-id or sticky bits


def atomic_write(target: str | os.PathLike, write: Callable[[BinaryIO], object], *,
                 overwrite_read_only: bool = False, allow: str | None = ALLOW_IN_PYTHON) -> Path:
    """Call ``write(fh)`` on a fresh temporary file next to ``target``, then move it over ``target``.

    The temporary file lives in the target's directory, so ``os.replace`` is an
    atomic rename; on any exception (including KeyboardInterrupt) it is removed
    and ``target`` keeps its previous content, if any. A replaced file's mode (and
    owner and group, where the process may set them) carry over to the new one.

    Parameters
    ----------
    target : str or os.PathLike
        Final path; its directory must exist.
    write : callable
        Receives a binary file object opened for writing.
    overwrite_read_only : bool, default False
        Replace a read-only ``target`` (see :func:`check_replaceable`) instead of refusing.
    allow : str or None
        How the caller's user allows that, for the refusal's message (None: the caller does not offer it).

    Returns
    -------
    pathlib.Path
        ``target``.

    Raises
    ------
    ParameterError
        ``target`` is read-only and ``overwrite_read_only`` is False (nothing is written).
    OSError
        Writing failed (a full disk: ``write`` and ``fsync`` name no file); its ``filename`` is ``target``.
    """
    target = Path(target)
    st = _PENDING.get(target) or check_replaceable(target, overwrite_read_only=overwrite_read_only, allow=allow)
    while True:
        tmp = target.parent / f".{target.name}.{secrets.token_hex(4)}.tmp"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
            break
        except FileExistsError:  # pragma: no cover - astronomically unlikely
            continue
    try:
        _give_metadata(fd, st)
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException as exc:
        with suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno is not None and exc.filename in (None, str(tmp)):
            exc.filename = str(target)  # the output, not its temporary file (a system error's message shows it)
        raise
    return target


@contextmanager
def output_set(*targets: str | os.PathLike, overwrite_read_only: bool = False,
               allow: str | None = ALLOW_IN_PYTHON) -> Iterator[list[Path]]:
    """Temporary paths for several outputs that must appear together: all of them, or none.

    Yields one temporary path per target, next to it and with the same suffix (so writers
    that check the extension accept it). When the block ends normally, every temporary file
    is renamed over its target; when it raises (KeyboardInterrupt included), every
    temporary file is removed and no target changes. A rename that fails (or an interrupt
    between two renames) puts the targets renamed before it back: the files they replaced are
    kept as hard links until all renames are done (where the file system has none, such a
    target keeps its new content). Each replaced target's mode (owner, group) carries over, as
    in :func:`atomic_write`.

    Parameters
    ----------
    *targets : str or os.PathLike
        Final paths; their directories must exist.
    overwrite_read_only : bool, default False
        Replace read-only targets instead of refusing.
    allow : str or None
        How the caller's user allows that, for the refusal's message (None: the caller does not offer it).

    Yields
    ------
    list of pathlib.Path
        The temporary paths, in the order of ``targets``.

    Raises
    ------
    ParameterError
        A target is read-only and ``overwrite_read_only`` is False: raised on entry, before the block runs.
    """
    finals = [Path(t) for t in targets]
    stats = [check_replaceable(f, overwrite_read_only=overwrite_read_only, allow=allow) for f in finals]
    tmps = [p.parent / f".{p.stem}.{secrets.token_hex(4)}.part{p.suffix}" for p in finals]
    _PENDING.update({t: s for t, s in zip(tmps, stats, strict=True) if s is not None})
    try:
        yield tmps
        missing = [str(f) for f, t in zip(finals, tmps, strict=True) if not t.exists()]
        if missing:
            raise RuntimeError(f"output_set: nothing was written for {', '.join(missing)}")
        for tmp, st in zip(tmps, stats, strict=True):  # writers that did not go through atomic_write
            if st is not None:
                fd = os.open(tmp, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))  # our file, not a link put there
                try:
                    _give_metadata(fd, st)
                finally:
                    os.close(fd)
        _rename_all(finals, tmps)
    finally:
        for tmp in tmps:
            _PENDING.pop(tmp, None)
            with suppress(FileNotFoundError):
                os.unlink(tmp)


@contextmanager
def output_folder(folder: Path, *, allow: str | None = ALLOW_IN_PYTHON) -> Iterator[Path]:
    """A private folder inside ``folder`` for outputs whose names are known once written: they appear in ``folder``
    all together, or none of them.

    When the block ends normally, every file written into the yielded folder is moved into ``folder`` through
    :func:`output_set` (all or none; a replaced file's mode carries over; a read-only one is refused with a
    :class:`ParameterError`); when the block raises (KeyboardInterrupt included) or a move fails, nothing in
    ``folder`` changes. The private folder (``.cvxgeodesic.*.part``) and what is left in it are removed either way.

    Parameters
    ----------
    folder : pathlib.Path
        The output folder; it must exist.
    allow : str or None
        As for :func:`output_set` (``overwrite_read_only`` is never given here).

    Yields
    ------
    pathlib.Path
        The private folder.
    """
    stage = Path(tempfile.mkdtemp(prefix=".cvxgeodesic.", suffix=".part", dir=folder))
    try:
        yield stage
        names = sorted(p.name for p in stage.iterdir())
        with output_set(*(folder / n for n in names), allow=allow) as tmps:
            for name, tmp in zip(names, tmps, strict=True):
                os.replace(stage / name, tmp)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _rename_all(finals: list[Path], tmps: list[Path]) -> None:
    """Rename every ``tmps[i]`` over ``finals[i]``; on any failure, the finals renamed so far are put back."""
    done: list[tuple[Path, Path | None]] = []  # (final, hard link to the file it replaced, or None: there was none)
    backups: list[Path] = []
    try:
        for final, tmp in zip(finals, tmps, strict=True):
            backup = None
            if os.path.lexists(final):
                backup = final.parent / f".{final.name}.{secrets.token_hex(4)}.old"
                try:
                    os.link(final, backup, follow_symlinks=False)  # a link stays a link
                    backups.append(backup)
                except OSError:  # no hard links here: this target cannot be put back
                    backup = final
            os.replace(tmp, final)
            done.append((final, backup))
    except BaseException:
        for final, backup in reversed(done):
            with suppress(OSError):  # the file system failing on the way back too
                if backup is None:
                    os.unlink(final)
                elif backup != final:
                    os.replace(backup, final)
        raise
    finally:
        for backup in backups:
            with suppress(FileNotFoundError):
                os.unlink(backup)


def probe_folder(folder: str | os.PathLike, prefix: str = ".cvxgeodesic.") -> None:
    """Create and remove an empty temporary file in ``folder``: what every output does first (the atomic writes
    go through a temporary file there). Unlike the mode bits, this also stops root on a read-only file system.

    Raises
    ------
    OSError
        No file can be created in ``folder``; the caller turns it into a message naming its option.
    """
    fd, probe = tempfile.mkstemp(prefix=prefix, suffix=".probe", dir=folder)
    os.close(fd)
    os.unlink(probe)


def check_output_dir(path: str | os.PathLike, what: str = "output folder") -> Path:
    """Check, without creating anything, that the folder ``path`` exists or can be created, and takes files.

    Made before the work whose results go there, so that a folder under a file, or on a read-only file
    system, fails at once. The probe is the one :func:`~cvxgeodesic.validation.check_output_path` makes:
    creating and removing a temporary file in ``path``, or in its closest existing ancestor when ``path``
    is still to be created (so it holds for root too, whom the mode bits do not stop).

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        The folder's name in messages (``"--out"``).

    Returns
    -------
    pathlib.Path
        ``path`` (the folder is not created here).

    Raises
    ------
    ParameterError
        ``path`` is a file, an ancestor of it is a file, or no file can be created there.
    """
    p = Path(os.fspath(path))
    existing = p
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        detail = "is a file, not a folder" if existing == p else f"cannot be created: {existing} is a file"
        raise ParameterError(f"{what} {p} {detail}")
    try:
        probe_folder(existing)
    except OSError as exc:
        verb = "cannot write files in it" if existing == p else f"cannot be created in {existing}"
        raise ParameterError(f"{what} {p}: {verb} ({exc.strerror or exc})") from None
    return p
