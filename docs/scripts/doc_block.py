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

"""Replace a generated block of a Markdown page (between two marker comments) in place."""

from pathlib import Path
import sys


def write_block(path: str, begin: str, end: str, block: str, who: str) -> int:
    """
    Put ``block`` (which starts with ``begin`` and ends with ``end``) in place of the old one.

    Parameters
    ----------
    path : str
        The Markdown file.
    begin, end : str
        The marker comments.
    block : str
        The new block, markers included.
    who : str
        The script's name, for the message.

    Returns
    -------
    int
        0, or 1 (with a line on stderr) when the page has no such block.

    """
    page = Path(path)
    text = page.read_text()
    if begin not in text or end not in text:
        print(f'{who}: {page} has no {begin} ... {end} block', file=sys.stderr)
        return 1
    head, rest = text.split(begin, 1)
    page.write_text(head + block + rest.split(end, 1)[1])
    print(f'updated {page}', file=sys.stderr)
    return 0
