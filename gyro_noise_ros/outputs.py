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
Outputs that are either finished or visibly unfinished: staged folders, bags and files.

A tool killed or failing half-way must leave nothing that looks like a result, and a retry must
work. Three shapes cover every tool:

* :func:`staged_output` -- a tool's ``--out`` folder (reports, tables, figures, models). Files
  are written into a hidden ``.partial-<pid>-<token>`` folder inside it and moved into place one
  by one (``os.replace``, atomic per file) only when the body finished; on an error the staging
  folder is removed; after ``kill -9`` it stays, hidden and named partial, and the next run
  removes it once its process is gone. The user's folder itself is never moved or emptied (it may
  be ``.`` or hold other files).
* :func:`staged_new_dir` -- a folder that must not exist yet (a rosbag2 bag): built under its own
  name inside a hidden sibling ``.<name>.partial-<pid>`` and renamed into place on success (one
  atomic rename; the storage files rosbags names after the folder keep the right name).
* :func:`atomic_write_bytes` / :func:`atomic_write_text` -- one file, through a temporary sibling
  and ``os.replace``.

Every OS error becomes :class:`~gyro_noise_ros.errors.OutputError` (exit code 6) naming the path.
"""

from collections.abc import Iterator
from contextlib import contextmanager
import os
from pathlib import Path
import secrets
import shutil
from typing import Union

from .errors import OutputError

__all__ = ['atomic_write_bytes', 'atomic_write_text', 'make_out_dir', 'PARTIAL_PREFIX',
           'staged_new_dir', 'staged_output']

#: A file or folder name as the tools accept it.
StrPath = Union[str, 'os.PathLike[str]']

#: Name prefix of staging folders inside an output folder.
PARTIAL_PREFIX = '.partial-'


def _reason(err: OSError) -> str:
    return err.strerror or str(err)


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
        raise OutputError(f'{{{parameter}}} {str(out)!r} is an existing file, not a folder',
                          parameters=(parameter,))
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f'{{{parameter}}} {str(out)!r} cannot be created: {_reason(err)}',
                          parameters=(parameter,)) from err
    if not os.access(out, os.W_OK | os.X_OK):
        raise OutputError(f'{{{parameter}}} {str(out)!r} is not writable: permission denied',
                          parameters=(parameter,))
    return out


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def _remove_stale_partials(out: Path) -> None:
    for entry in out.glob(PARTIAL_PREFIX + '*'):
        try:
            pid = int(entry.name[len(PARTIAL_PREFIX):].split('-', 1)[0])
        except ValueError:
            continue
        if pid != os.getpid() and not _pid_alive(pid):
            shutil.rmtree(entry, ignore_errors=True)


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
    out = make_out_dir(path, parameter=parameter)
    _remove_stale_partials(out)
    stage = out / f'{PARTIAL_PREFIX}{os.getpid()}-{secrets.token_hex(4)}'
    try:
        stage.mkdir()
    except OSError as err:
        raise OutputError(f'{{{parameter}}} {str(out)!r} is not writable: {_reason(err)}',
                          parameters=(parameter,)) from err
    try:
        yield stage
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise
    try:
        _publish(stage, out)
        stage.rmdir()
    except OSError as err:
        raise OutputError(f'cannot move the results into {{{parameter}}} {str(out)!r}: '
                          f'{_reason(err)} (the finished files are in {str(stage)!r})',
                          parameters=(parameter,)) from err


@contextmanager
def staged_new_dir(path: StrPath, *, parameter: str = 'out') -> Iterator[Path]:
    """
    Build a folder that must not exist yet under a hidden sibling name; rename it on success.

    Parameters
    ----------
    path : str or os.PathLike
        The final folder (for example a rosbag2 bag); it must not exist.
    parameter : str, keyword-only
        The caller's parameter that named it, for messages (:class:`..errors.GyroNoiseError`).

    Yields
    ------
    pathlib.Path
        The staging folder (does not exist yet: writers such as rosbags create it themselves).

    Raises
    ------
    OutputError
        ``path`` exists, its parent cannot be written, or the rename failed.

    """
    final = Path(path)
    if final.exists() or final.is_symlink():
        raise OutputError(f'{{{parameter}}} {str(final)!r} already exists',
                          parameters=(parameter,))
    parent = final.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f'{{{parameter}}} {str(final)!r}: its folder cannot be created: '
                          f'{_reason(err)}', parameters=(parameter,)) from err
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f'{{{parameter}}} {str(final)!r}: its folder is not writable',
                          parameters=(parameter,))
    # The stage carries the final name inside a hidden holder folder: rosbags (like ros2 bag)
    # names a bag's storage file after its folder, and that name must survive the rename.
    holder = parent / f'.{final.name}.partial-{os.getpid()}'
    if holder.exists():
        shutil.rmtree(holder)
    try:
        holder.mkdir()
    except OSError as err:
        raise OutputError(f'{{{parameter}}} {str(final)!r}: its folder is not writable: '
                          f'{_reason(err)}', parameters=(parameter,)) from err
    stage = holder / final.name
    try:
        yield stage
    except BaseException:
        shutil.rmtree(holder, ignore_errors=True)
        raise
    try:
        os.rename(stage, final)
        holder.rmdir()
    except OSError as err:
        raise OutputError(f'cannot rename {str(stage)!r} to {{{parameter}}} {str(final)!r}: '
                          f'{_reason(err)}', parameters=(parameter,)) from err


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
    tmp = target.with_name(f'.{target.name}.partial-{os.getpid()}')
    try:
        with open(tmp, 'wb') as fh:
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
    """Write ``text`` to ``path`` atomically, encoded (:func:`atomic_write_bytes`)."""
    atomic_write_bytes(path, text.encode(encoding))
