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
Reading recordings whose writer was killed, without modifying them.

Two storages, two ways a killed writer (``kill -9``, power loss) leaves its file:

* **MCAP without summary and footer.** rosbags (and most MCAP readers) start at the footer, so
  the whole file is refused ("File end magic is invalid"). Everything before the cut is intact:
  :func:`recovering_reader_class` is rosbags' ``Reader`` that reads such a file by its complete
  chunks (:mod:`._recovering_mcap`, on the record walk of :mod:`.mcap_records`), so rosbags'
  iterator and the block reader of :mod:`.storage` read it unchanged.
* **sqlite3 with a hot rollback journal** (rosbags keeps a transaction open between commits).
  rosbags opens the database immutable and would read the half-written pages of the unfinished
  transaction. :func:`rolled_back_copy` copies the ``.db3`` and its ``-journal`` to a temporary
  folder and lets sqlite roll the transaction back there: what was committed is read, the user's
  files are never opened for writing. The copy lives until the process exits.

:func:`truncation_note` and :func:`rollback_note` word the one-line note on each case; the
caller decides where it goes (:class:`.storage.BagSource` logs it as a warning).
"""

from __future__ import annotations

import atexit
from pathlib import Path
import shutil
import tempfile
from typing import TYPE_CHECKING

from ..errors import BagError
from ..outputs import StrPath

if TYPE_CHECKING:
    from rosbags.rosbag2 import Reader

    from .mcap_records import McapTruncation

#: Free space kept beyond the copy itself when a rolled-back copy is made (bytes).
COPY_MARGIN_BYTES = 64 << 20


def recovering_reader_class() -> type[Reader]:
    """
    Return rosbags' unified ``Reader`` that also reads an MCAP file without summary and footer.

    Returns
    -------
    type
        ``RecoveringReader``: with a footer, rosbags' reader unchanged; without one, the storage
        reader's ``truncation`` attribute is a :class:`.mcap_records.McapTruncation` and its chunk
        index is built by walking the file.

    """
    # rosbags is imported when a bag is read, not when the package is
    from ._recovering_mcap import RecoveringReader

    return RecoveringReader


def truncation_note(path: StrPath, truncation: McapTruncation) -> str:
    """
    Return the one-line note on a truncated MCAP file.

    ``path`` is the bag as the user named it, ``truncation`` what the record walk found.

    """
    return (f'truncated MCAP {str(path)!r} (no summary/footer: its writer was killed): read '
            f'{truncation.messages} messages up to t = {truncation.span_s:.3f} s by its '
            f'{truncation.chunks} chunks, {truncation.lost_bytes} bytes after them lost '
            f'({truncation.stop_reason}); `gyro_noise_record repair {path}` writes a complete '
            'bag')


# ---------------------------------------------------------------------------------------------
# sqlite3: a hot rollback journal, rolled back in a copy

_COPIES: dict[tuple[tuple[int, int, int, int], tuple[int, int, int, int]], Path] = {}


def journal_is_hot(db3: Path) -> bool:
    """
    Tell whether a ``.db3`` has a non-empty rollback journal beside it (a writer died mid-way).

    Parameters
    ----------
    db3 : pathlib.Path
        The sqlite3 file.

    Returns
    -------
    bool

    """
    journal = db3.with_name(db3.name + '-journal')
    try:
        return journal.stat().st_size > 0
    except OSError:
        return False


def _identity(path: Path) -> tuple[int, int, int, int]:
    st = path.stat()
    return (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)


def rolled_back_copy(db3: StrPath) -> Path:
    """
    Copy an sqlite3 file and its hot journal to a temporary folder and roll the journal back there.

    The originals are only read. The copy is made once per process (cached by the files' identity,
    size and modification time) and removed when the process exits; ``TMPDIR`` chooses where.

    Parameters
    ----------
    db3 : str or os.PathLike
        The sqlite3 file; ``<name>-journal`` beside it is the journal.

    Returns
    -------
    pathlib.Path
        The rolled-back copy (committed transactions only).

    Raises
    ------
    BagError
        The files cannot be read, the temporary folder lacks the space for the copy, or sqlite
        cannot roll the journal back.

    """
    import sqlite3

    db3 = Path(db3)
    journal = db3.with_name(db3.name + '-journal')
    try:
        key = (_identity(db3), _identity(journal))
        need = key[0][2] + key[1][2]
    except OSError as err:
        raise BagError(f'sqlite3 file {str(db3)!r} cannot be read: '
                       f'{err.strerror or err}') from err
    hit = _COPIES.get(key)
    if hit is not None and hit.exists():
        return hit
    root = tempfile.gettempdir()
    free = shutil.disk_usage(root).free
    if free < need + COPY_MARGIN_BYTES:
        raise BagError(
            f'sqlite3 file {str(db3)!r} has an unfinished transaction ({journal.name}) and '
            f'reading it needs a rolled-back copy of {need / 1e9:.2f} GB, but {root!r} has '
            f'{free / 1e9:.2f} GB free: set TMPDIR to a folder with room, or write a '
            f'complete bag elsewhere with `gyro_noise_record repair {db3.parent}`')
    folder = Path(tempfile.mkdtemp(prefix='gyro_noise_rollback-', dir=root))
    atexit.register(shutil.rmtree, folder, True)
    copy = folder / db3.name
    try:
        shutil.copyfile(db3, copy)
        shutil.copyfile(journal, folder / journal.name)
        con = sqlite3.connect(copy)
        try:
            # The first read of a database with a hot journal rolls the journal back.
            con.execute('SELECT count(*) FROM sqlite_master').fetchone()
        finally:
            con.close()
    except (OSError, sqlite3.Error) as err:
        shutil.rmtree(folder, ignore_errors=True)
        raise BagError(f'sqlite3 file {str(db3)!r}: its unfinished transaction '
                       f'({journal.name}) cannot be rolled back in a copy: {err}') from err
    # A journal sqlite did not judge hot (a zeroed header) stays; it holds nothing to roll back,
    # and rosbags opens the copy immutable, ignoring it.
    _COPIES[key] = copy
    return copy


def rollback_note(path: StrPath, db3: Path) -> str:
    """
    Return the one-line note on an sqlite3 file read through a rolled-back copy.

    ``path`` is the bag as the user named it, ``db3`` its sqlite3 file.

    """
    return (f'sqlite3 bag {str(path)!r} has an unfinished transaction ({db3.name}-journal: its '
            'writer was killed): reading what was committed, through a rolled-back copy (the '
            f'files are left as they are); `gyro_noise_record repair {path}` writes a complete '
            'bag')
