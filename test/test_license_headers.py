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
Every Python source file starts with the Apache-2.0 header, exactly as in ``test/_realdata.py``.

The header is the first 13 lines of that file; a shebang line may stand before it. Checked
without ament_copyright (not on PyPI) over the package, test/, bench/, tools/, docs/scripts/ and
launch/ plus setup.py. (The SPDX two-line form fails Jazzy's ament_copyright: README, Licence.)
"""

from _lint_scope import PACKAGE_ROOT, SOURCE_DIRS
import pytest

HEADER_LINES = 13


def _header():
    with open(PACKAGE_ROOT / 'test' / '_realdata.py', encoding='utf-8') as f:
        lines = f.read().splitlines()[:HEADER_LINES]
    return lines


def _sources():
    files = [PACKAGE_ROOT / 'setup.py']
    for name in SOURCE_DIRS:
        folder = PACKAGE_ROOT / name
        if folder.is_dir():
            files += sorted(p for p in folder.rglob('*.py')
                            if not any(part.startswith(('.', '__pycache__'))
                                       for part in p.relative_to(PACKAGE_ROOT).parts))
    return files


def _missing_header(path, header):
    with open(path, encoding='utf-8') as f:
        lines = f.read().splitlines()
    if lines and lines[0].startswith('#!'):
        lines = lines[1:]
    return lines[:len(header)] != header


def test_header_is_apache_2():
    header = _header()
    assert header[0].startswith('# Copyright ')
    assert '# Licensed under the Apache License, Version 2.0 (the "License");' in header


def test_every_source_file_has_the_header():
    header = _header()
    files = _sources()
    assert len(files) > 50, f'only {len(files)} source files found under {PACKAGE_ROOT}'
    missing = [str(p.relative_to(PACKAGE_ROOT)) for p in files if _missing_header(p, header)]
    assert not missing, (f'{len(missing)} file(s) lack the Apache-2.0 header (lines 1-'
                         f'{HEADER_LINES} of test/_realdata.py): ' + ', '.join(missing))


@pytest.mark.parametrize('first', [[], ['#!/usr/bin/env python3']])
def test_check_catches_a_missing_header(tmp_path, first):
    header = _header()
    good = tmp_path / 'good.py'
    good.write_text('\n'.join(first + header + ['', 'x = 1']) + '\n', encoding='utf-8')
    bad = tmp_path / 'bad.py'
    bad.write_text('\n'.join(first + header[:5] + header[6:] + ['', 'x = 1']) + '\n',
                   encoding='utf-8')
    assert not _missing_header(good, header)
    assert _missing_header(bad, header)
