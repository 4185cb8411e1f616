#!/usr/bin/env python3
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
Print the README's exit-code table from its one owner, ``gyro_noise_ros.errors.EXIT_CODES``.

Usage::

    python tools/exit_codes.py            # the Markdown table
    python tools/exit_codes.py --write    # put it into README.md in place of the old one

``test/test_bad_input.py`` fails when README.md holds another table than this one, so a code or
a meaning changes in ``errors.py`` and the README follows with ``--write``.
"""

import argparse
from pathlib import Path
import re
import sys

from gyro_noise_ros.cli._common import option_of
from gyro_noise_ros.cli.analyze import RENAMED
from gyro_noise_ros.errors import EXIT_CODES

README = Path(__file__).resolve().parents[1] / 'README.md'
#: The heading the table follows in README.md (the table is the first one under it).
HEADING = '## Exit codes of the command-line tools and nodes'


def markdown_table() -> str:
    """
    Return the exit codes as a Markdown table, one row per code, the options spelled.

    Returns
    -------
    str

    """
    rows = ['| code | meaning |', '|---|---|']
    rows += [f'| {code} | {spelled(meaning)} |' for code, meaning in sorted(EXIT_CODES.items())]
    return '\n'.join(rows) + '\n'


def spelled(meaning: str) -> str:
    """
    Return a meaning with each ``{parameter}`` spelled as the tools spell it (``--start``).

    Parameters
    ----------
    meaning : str
        A value of :data:`~gyro_noise_ros.errors.EXIT_CODES`.

    Returns
    -------
    str

    """
    return re.sub(r'\{(\w+)\}', lambda m: option_of(m.group(1), RENAMED), meaning)


def readme_table(text: str) -> str:
    """
    Return the table README.md holds under :data:`HEADING`.

    Parameters
    ----------
    text : str
        README.md.

    Returns
    -------
    str

    """
    section = text.split(HEADING, 1)[1]
    lines = section.split('\n| code |', 1)[1].split('\n\n', 1)[0]
    return '| code |' + lines + '\n'


def main(argv: list[str] | None = None) -> int:
    """
    Print the table, or write it into README.md.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (``--write``).

    Returns
    -------
    int
        0.

    """
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    p.add_argument('--write', action='store_true', help='replace the table in README.md')
    args = p.parse_args(argv)
    table = markdown_table()
    if not args.write:
        print(table, end='')
        return 0
    text = README.read_text()
    README.write_text(text.replace(readme_table(text), table, 1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
