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
tools/output_digests.py on its smallest run: the digests repeat, and a changed byte shows.

The whole run (every tool, each in a fresh process, ~2-3 min) is the lead's check that a
refactor changed no output (``--baseline``); here one calibration, twice, run as its program in
this process (~3 s).
"""

import importlib.util

from _lint_scope import PACKAGE_ROOT
import pytest

_spec = importlib.util.spec_from_file_location(
    'output_digests', PACKAGE_ROOT / 'tools' / 'output_digests.py')
output_digests = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(output_digests)


@pytest.fixture(scope='module')
def two_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp('digests')
    output_digests.make_inputs(root / 'in', ['calibrate_six'])
    for name in ('a', 'b'):
        (root / name).mkdir()
        assert output_digests.run_one('calibrate_six', root / 'in', root / name) == 0
    return root


def test_a_run_repeats_byte_for_byte(two_runs):
    a = output_digests.digests(two_runs / 'a')
    b = output_digests.digests(two_runs / 'b')
    names = {f'calibrate_six/{f}' for f in ('calibration.json', 'calibration.md',
                                            'calibration.yaml', 'report.html')}
    assert set(a) == names
    assert a == b
    assert all(v == 'identical' for _, v in output_digests.compare(a, b))
    # the raw pages differ (Bokeh's random ids): the digest is of the normalised bytes
    page = 'calibrate_six/report.html'
    assert (two_runs / 'a' / page).read_bytes() != (two_runs / 'b' / page).read_bytes()


def test_a_changed_byte_or_a_missing_file_is_reported(two_runs, tmp_path):
    a = output_digests.digests(two_runs / 'a')
    md = two_runs / 'b' / 'calibrate_six' / 'calibration.md'
    text = md.read_text()
    md.write_text(text.replace('|', '!', 1))
    try:
        b = output_digests.digests(two_runs / 'b')
    finally:
        md.write_text(text)
    del b['calibrate_six/calibration.yaml']
    verdicts = dict(output_digests.compare(a, b))
    assert verdicts['calibrate_six/calibration.md'] == 'DIFFERENT'
    assert verdicts['calibrate_six/calibration.yaml'] == 'only in new'
    assert verdicts['calibrate_six/calibration.json'] == 'identical'


def test_unknown_run_names_are_refused():
    with pytest.raises(SystemExit, match='unknown nope'):
        output_digests.main(['--tools', 'nope'])
