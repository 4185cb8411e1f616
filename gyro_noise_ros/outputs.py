# Copyright 2026 gyro_noise_ros developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
Outputs that are either finished or visibly unfinished, and never replace what a user has.

A tool killed or failing half-way must leave nothing that looks like a result, a retry must work,
and no run replaces existing data unless its caller says ``overwrite`` (every tool's
``--overwrite``, a node's ``overwrite`` parameter). The shapes:

* :func:`staged_output` -- a tool's ``--out`` folder (reports, tables, figures, models, SD logs).
  Files are written into a hidden ``.partial-<pid>-<token>`` folder inside it and moved into
  place one by one (``os.replace``, atomic per file) only when the body finished; on an error or
  an interrupt the staging folder is removed, and so are the folders the run created. Before any
  work :func:`check_out_dir` refuses a folder that is not empty (a visible entry) unless
  ``--overwrite``: then files of the same names are replaced and the others kept.
* :func:`staged_new_dir` -- a folder that must not exist yet (a rosbag2 bag), built under its own
  name inside a hidden sibling ``.<name>.partial-<pid>`` and renamed into place on success; with
  ``--overwrite`` an existing *bag* folder (:func:`is_bag_dir`) is swapped out at the end.
* :func:`atomic_write_bytes` / :func:`atomic_write_text` -- one file, through a temporary sibling
  and ``os.replace``.

Every stage is held with an ``flock`` while its run lives, so the next run of a tool removes the
stages of killed runs (``kill -9``, power loss) by the lock, not by a process id that may have
been reused. Every OS error becomes :class:`~gyro_noise_ros.errors.OutputError` (exit code 6)
naming the path; a full disk is told apart (:func:`is_disk_full`).
"""

from collections.abc import Iterator
from contextlib import contextmanager
import errno
import fcntl
import os
from pathlib import Path
import secrets
import shutil
from typing import Union

from .errors import OutputError

__all__ = ['atomic_write_bytes', 'atomic_write_text', 'check_new_dir', 'check_new_file',
           'check_out_dir', 'free_bytes', 'is_bag_dir', 'is_disk_full', 'make_out_dir',
           'PARTIAL_PREFIX', 'remove_stale_partials', 'removed_if_unused',
           'staged_new_dir',
           'staged_output']

#: A file or folder name as the tools accept it.
StrPath = Union[str, 'os.PathLike[str]']

#: Name prefix of staging folders inside an output folder.
PARTIAL_PREFIX = '.partial-'
#: The parameter that lets a run replace existing data, as messages name it (errors.py).
OVERWRITE = 'overwrite'
#: Files a rosbag2 folder holds (what ``--overwrite`` may replace as a bag).
_BAG_SUFFIXES = ('.db3', '.db3-journal', '.db3-wal', '.db3-shm', '.mcap', '.mcap.zstd',
                 '.db3.zstd')
_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


def _reason(err: OSError) -> str:
    return err.strerror or str(err)


def _refused(parameter: str, text: str) -> OutputError:
    """Return ``OutputError('{parameter} text')``; ``text`` may name :data:`OVERWRITE` too."""
    return OutputError(f'{{{parameter}}} {text}', parameters=(parameter, OVERWRITE))


def is_disk_full(err: BaseException) -> bool:
    """
    Tell whether an error is a full disk or quota (ENOSPC, EDQUOT, EFBIG, sqlite "disk is full").

    Parameters
    ----------
    err : BaseException
        The error (an ``OSError``, or a library's wrapping of one, such as sqlite3's).

    Returns
    -------
    bool

    """
    seen: set[int] = set()
    while err is not None and id(err) not in seen:
        seen.add(id(err))
        if isinstance(err, OSError) and err.errno in _FULL_ERRNOS:
            return True
        if 'disk is full' in str(err) or 'No space left' in str(err):
            return True
        err = err.__cause__ or err.__context__  # type: ignore[assignment]
    return False


def _existing_ancestor(path: Path) -> Path:
    ancestor = path
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    return ancestor


def free_bytes(path: StrPath) -> int | None:
    """
    Return the bytes free for an unprivileged user on the file system that would hold ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        A file or folder (need not exist: its nearest existing folder is asked).

    Returns
    -------
    int or None
        None where the system cannot say.

    """
    try:
        usage = os.statvfs(_existing_ancestor(Path(path).absolute()))
    except (OSError, AttributeError):
        return None
    return usage.f_bavail * usage.f_frsize


def _check_creatable(target: Path, parameter: str, *, into: bool = False) -> None:
    """Refuse ``target`` under a file or an unwritable folder (``into``: a folder written into)."""
    ancestor = _existing_ancestor(target if into else target.parent)
    if not ancestor.exists():
        return
    if not ancestor.is_dir():
        raise _refused(parameter, f'{str(target)!r} cannot be created: {str(ancestor)!r} is a '
                       'file')
    what = 'is not writable' if ancestor == target else (
        f'cannot be created: {str(ancestor)!r} is not writable')
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise _refused(parameter, f'{str(target)!r} {what}: permission denied')
    # os.access trusts the mode bits: a read-only mount, /proc or an ACL say no only when tried
    try:
        _try_creating_in(ancestor)
    except OSError as err:
        raise _refused(parameter, f'{str(target)!r} {what}: {_reason(err)}') from err


def _try_creating_in(folder: Path) -> None:
    """
    Raise OSError unless an entry can be created in ``folder``; leave nothing there, even stopped.

    An unnamed file (``O_TMPFILE``) vanishes with its descriptor, so a signal between creating
    and removing it leaves no name behind; where the file system lacks it, a uniquely named
    folder is made and removed in a ``finally``.
    """
    tmpfile = getattr(os, 'O_TMPFILE', 0)
    if tmpfile:
        try:
            os.close(os.open(folder, tmpfile | os.O_WRONLY, 0o600))
            return
        except OSError as err:
            if err.errno not in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL):
                raise
    probe = folder / f'.gyro_noise_probe-{os.getpid()}-{secrets.token_hex(4)}'
    try:
        probe.mkdir()
    finally:
        try:
            probe.rmdir()
        except OSError:
            pass  # not made (the refusal is mkdir's error) or already gone


def _check_named(path: StrPath, parameter: str) -> None:
    """Refuse an empty name: ``Path('')`` is the working folder, never what was meant."""
    if not os.fspath(path).strip():
        raise _refused(parameter, 'is empty: give a name')


def _visible_entries(folder: Path) -> list[str]:
    try:
        return sorted(e.name for e in os.scandir(folder) if not e.name.startswith('.'))
    except OSError as err:
        raise OutputError(f'{str(folder)!r} cannot be listed: {_reason(err)}') from err


def check_out_dir(path: StrPath, *, parameter: str = 'out', overwrite: bool = False) -> None:
    """
    Refuse an output folder before any work, creating nothing (the ``--out`` rule of every tool).

    An existing folder that holds a visible file or folder (a previous result, or the user's
    own files) is refused unless ``overwrite``: a run then replaces the files of the names it
    writes and keeps the others. Hidden entries (the stages of killed runs) do not count.

    Parameters
    ----------
    path : str or os.PathLike
        The folder named by the user (may not exist yet).
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).
    overwrite : bool, keyword-only
        ``--overwrite`` was given.

    Raises
    ------
    OutputError
        ``path`` is a file, lies under a file or an unwritable folder (as root every folder is
        writable: the staging step then finds the rest), or is not empty without ``overwrite``.

    """
    _check_named(path, parameter)
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise _refused(parameter, f'{str(out)!r} is an existing file, not a folder')
    _check_creatable(out, parameter, into=True)
    if out.is_dir() and not overwrite:
        names = _visible_entries(out)
        if names:
            more = f' and {len(names) - 1} more' if len(names) > 1 else ''
            raise _refused(
                parameter, f'{str(out)!r} is not empty (it holds {names[0]!r}{more}): give '
                f'{{overwrite}} to write into it (files of the same names are replaced, '
                'the others kept), or a new folder')


def is_bag_dir(path: StrPath) -> bool:
    """
    Tell whether ``path`` is a folder holding only rosbag2 files (or nothing).

    Parameters
    ----------
    path : str or os.PathLike
        A folder.

    Returns
    -------
    bool
        True for a folder of ``metadata.yaml`` and storage files (``.db3``, ``.mcap``, sqlite3
        journals), or an empty folder: what ``--overwrite`` may replace as a bag.

    """
    folder = Path(path)
    if folder.is_symlink() or not folder.is_dir():
        return False
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return False
    return all(e.is_file(follow_symlinks=False)
               and (e.name == 'metadata.yaml' or e.name.endswith(_BAG_SUFFIXES))
               for e in entries)


def check_new_dir(path: StrPath, *, parameter: str = 'out', overwrite: bool = False) -> None:
    """
    Refuse the target of a new bag folder before any work, creating nothing.

    Parameters
    ----------
    path : str or os.PathLike
        The bag folder to create.
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).
    overwrite : bool, keyword-only
        An existing bag folder may be replaced (never a file or another kind of folder).

    Raises
    ------
    OutputError
        ``path`` exists (without ``overwrite``, or not as a bag folder), or its folder cannot be
        created or written.

    """
    _check_named(path, parameter)
    final = Path(path)
    if final.exists() or final.is_symlink():
        if not overwrite:
            raise _refused(parameter, f'{str(final)!r} already exists: give {{overwrite}} '
                           'to replace it, or a new name')
        if not is_bag_dir(final):
            kind = 'a file' if not final.is_dir() or final.is_symlink() else (
                'a folder that is not a bag')
            raise _refused(parameter, f'{str(final)!r} is {kind}: {{overwrite}} replaces '
                           'only a bag folder; give a new name')
    _check_creatable(final, parameter)


def check_new_file(path: StrPath, *, parameter: str, overwrite: bool = False) -> None:
    """
    Refuse the target of an output file before any work, creating nothing.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).
    overwrite : bool, keyword-only
        An existing file may be replaced.

    Raises
    ------
    OutputError
        ``path`` is a folder, exists without ``overwrite``, or its folder is missing or not
        writable.

    """
    _check_named(path, parameter)
    target = Path(path)
    if target.is_dir():
        raise _refused(parameter, f'{str(target)!r} is a folder, not a file')
    if not target.parent.is_dir():
        raise _refused(parameter, f'{str(target)!r}: its folder does not exist')
    if target.exists() and not overwrite:
        raise _refused(parameter, f'{str(target)!r} already exists: give {{overwrite}} to '
                       'replace it, or a new name')
    _check_creatable(target, parameter)


def make_out_dir(path: StrPath, *, parameter: str = 'out') -> Path:
    """
    Create the output folder ``path`` (and its parents) of a tool and check it can be written.

    Parameters
    ----------
    path : str or os.PathLike
        The folder.
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OutputError
        It cannot be created, is a file, or cannot be written (one line naming it and why).

    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise _refused(parameter, f'{str(out)!r} is an existing file, not a folder')
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise _refused(parameter, f'{str(out)!r} cannot be created: {_reason(err)}') from err
    if not os.access(out, os.W_OK | os.X_OK):
        raise _refused(parameter, f'{str(out)!r} is not writable: permission denied')
    return out


def _missing_folders(path: Path) -> list[Path]:
    """Return the folders of ``path`` (itself included) that do not exist, deepest first."""
    missing = []
    folder = path.absolute()
    while not folder.exists() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    return missing


def _remove_if_empty(folders: list[Path]) -> None:
    """Remove the folders a failed run created (deepest first) if nothing else went into them."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


@contextmanager
def removed_if_unused(path: StrPath) -> Iterator[None]:
    """
    Remove the folder ``path`` (and its missing parents) again if the block fails leaving it empty.

    For a tool that makes its ``--out`` folder before its work (to find an unwritable one early):
    a refusal or an interrupt then leaves no new empty folder behind.

    Parameters
    ----------
    path : str or os.PathLike
        The output folder (need not exist yet).

    """
    created = _missing_folders(Path(path))
    try:
        yield
    except BaseException:
        _remove_if_empty(created)
        raise


def _hold(path: Path) -> int:
    """Open ``path`` (a stage) and hold an exclusive lock on it while the run lives."""
    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        raise
    return fd


def _release(fd: int | None) -> None:
    if fd is not None:
        try:
            os.close(fd)  # closing the last descriptor drops the lock
        except OSError:
            pass


def _is_stale(path: Path) -> bool:
    """Tell whether a stage is left by a dead run: nobody holds its lock."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False  # a live run holds it
    finally:
        os.close(fd)
    return True


def remove_stale_partials(folder: StrPath, pattern: str) -> list[Path]:
    """
    Remove the stages of killed runs matching ``pattern`` in ``folder``; return what was removed.

    Parameters
    ----------
    folder : str or os.PathLike
        Where the stages are.
    pattern : str
        Glob of their names (``.partial-*`` inside an output folder, ``.<name>.partial-*``
        beside a bag or file).

    Returns
    -------
    list of pathlib.Path

    """
    removed = []
    for entry in Path(folder).glob(pattern):
        if entry.is_symlink() or not _is_stale(entry):
            continue
        try:
            if entry.is_dir():
                shutil.rmtree(entry)
            else:
                entry.unlink()
        except OSError:
            continue  # not ours to remove (permissions): it stays hidden and named partial
        removed.append(entry)
    return removed


def _publish(stage: Path, out: Path) -> None:
    for entry in sorted(stage.iterdir()):
        target = out / entry.name
        if entry.is_dir() and target.is_dir():
            # a folder cannot replace a non-empty folder in one step: move the old one aside
            old = out / f'{PARTIAL_PREFIX}{os.getpid()}-old-{entry.name}'
            os.rename(target, old)
            os.rename(entry, target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            if target.is_dir():
                shutil.rmtree(target)
            os.replace(entry, target)


@contextmanager
def staged_output(path: StrPath, *, parameter: str = 'out') -> Iterator[Path]:
    """
    Stage a tool's outputs and publish them in ``path`` only if the body finishes (module doc).

    The caller checked ``path`` with :func:`check_out_dir` before its work (whether it may be
    written into); folders this call creates are removed again when the body fails.

    Parameters
    ----------
    path : str or os.PathLike
        The tool's output folder (created if missing).
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).

    Yields
    ------
    pathlib.Path
        The staging folder: write every output there, under its final name.

    Raises
    ------
    OutputError
        The folder cannot be created or written, or publishing failed.

    """
    created = _missing_folders(Path(path))
    out = make_out_dir(path, parameter=parameter)
    remove_stale_partials(out, PARTIAL_PREFIX + '*')
    stage = out / f'{PARTIAL_PREFIX}{os.getpid()}-{secrets.token_hex(4)}'
    lock = None
    try:
        stage.mkdir()
        lock = _hold(stage)
    except OSError as err:
        _release(lock)
        shutil.rmtree(stage, ignore_errors=True)
        _remove_if_empty(created)
        raise _refused(parameter, f'{str(out)!r} is not writable: {_reason(err)}') from err
    try:
        try:
            yield stage
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            _remove_if_empty(created)
            raise
        try:
            _publish(stage, out)
            stage.rmdir()
        except OSError as err:
            raise OutputError(f'cannot move the results into {{{parameter}}} {str(out)!r}: '
                              f'{_reason(err)} (the finished files are in {str(stage)!r})',
                              parameters=(parameter,)) from err
    finally:
        _release(lock)


def _swap_in(stage: Path, final: Path, holder: Path) -> None:
    """Rename ``stage`` to ``final``; an existing ``final`` (a bag) goes into ``holder`` first."""
    old = None
    if final.exists() or final.is_symlink():
        old = holder / f'{final.name}.old'
        os.rename(final, old)
    try:
        os.rename(stage, final)
    except OSError:
        if old is not None:
            os.rename(old, final)
        raise


@contextmanager
def staged_new_dir(path: StrPath, *, parameter: str = 'out',
                   overwrite: bool = False) -> Iterator[Path]:
    """
    Build a folder that must not exist yet under a hidden sibling name; rename it on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final folder (for example a rosbag2 bag).
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).
    overwrite : bool, keyword-only
        An existing bag folder at ``path`` is replaced at the end (:func:`check_new_dir`).

    Yields
    ------
    pathlib.Path
        The staging folder (does not exist yet: writers such as rosbags create it themselves).

    Raises
    ------
    OutputError
        ``path`` exists (without ``overwrite``, or not as a bag), its parent cannot be written,
        or the rename failed.

    """
    final = Path(path)
    check_new_dir(final, parameter=parameter, overwrite=overwrite)
    parent = final.parent
    created = _missing_folders(parent)
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise _refused(parameter, f'{str(final)!r}: its folder cannot be created: '
                       f'{_reason(err)}') from err
    remove_stale_partials(parent, f'.{final.name}.partial-*')
    # The stage carries the final name inside a hidden holder folder: rosbags (like ros2 bag)
    # names a bag's storage file after its folder, and that name must survive the rename.
    holder = parent / f'.{final.name}.partial-{os.getpid()}-{secrets.token_hex(4)}'
    lock = None
    try:
        holder.mkdir()
        lock = _hold(holder)
    except OSError as err:
        _release(lock)
        shutil.rmtree(holder, ignore_errors=True)
        _remove_if_empty(created)
        raise _refused(parameter, f'{str(final)!r}: its folder is not writable: '
                       f'{_reason(err)}') from err
    try:
        try:
            yield holder / final.name
        except BaseException:
            shutil.rmtree(holder, ignore_errors=True)
            _remove_if_empty(created)
            raise
        try:
            _swap_in(holder / final.name, final, holder)
        except OSError as err:
            raise OutputError(f'cannot rename {str(holder / final.name)!r} to {{{parameter}}} '
                              f'{str(final)!r}: {_reason(err)}', parameters=(parameter,)) from err
        shutil.rmtree(holder, ignore_errors=True)
    finally:
        _release(lock)


def atomic_write_bytes(path: StrPath, data: bytes) -> None:
    """
    Write ``data`` to ``path`` through a temporary sibling and ``os.replace`` (module doc).

    Parameters
    ----------
    path : str or os.PathLike
        Target file.
    data : bytes
        Content.

    Raises
    ------
    OutputError
        The file cannot be written.

    """
    target = Path(path)
    if target.parent.is_dir():
        remove_stale_partials(target.parent, f'.{target.name}.partial-*')
    tmp = target.with_name(f'.{target.name}.partial-{os.getpid()}-{secrets.token_hex(4)}')
    try:
        with open(tmp, 'wb') as fh:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
            os.replace(tmp, target)
    except OSError as err:
        try:
            tmp.unlink()
        except OSError:
            pass
        raise OutputError(f'cannot write {str(target)!r}: {_reason(err)}') from err


def atomic_write_text(path: StrPath, text: str, encoding: str = 'utf-8') -> None:
    """Write ``text`` to ``path`` atomically in ``encoding``: :func:`atomic_write_bytes`."""
    atomic_write_bytes(path, text.encode(encoding))
