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

"""The report's analogues of paper 002's Figures 10-19: every one drawn or its absence said."""

import re

from gyro_noise_ros.cli.thermal import main
from gyro_noise_ros.thermal import methods, parallel
from gyro_noise_ros.thermal.methods import register_method
from gyro_noise_ros.thermal.parallel import ParallelModel
from gyro_noise_ros.thermal.report import figure_numbers, figures_markdown, PAPER_FIGURES
import numpy as np
import pytest
from test_thermal_cli import _bag
from test_thermal_parallel import SMALL, thermal_run

PNG = b'\x89PNG\r\n\x1a\n'
FAST = ['--f-lo-hz', '0.5', '--no-bag', '--no-small-signal', '--quiet']


class SmallParallel(ParallelModel):
    """The paper's model with the small MOPSO budget of test_thermal_parallel (same code)."""

    name = 'parallel_small'

    def __init__(self, **options):
        super().__init__(**{**SMALL, **options})


@pytest.fixture(scope='module')
def pair(tmp_path_factory):
    """Fit the small parallel model on one simulated bag; return (dir, test bag, model dir)."""
    register_method('parallel_small', SmallParallel)
    d = tmp_path_factory.mktemp('report')
    train, _, _ = _bag(d / 'train', 1)
    test, _, _ = _bag(d / 'test', 2)
    # the training report's figures are checked with a baseline below (fit is cheap there)
    assert main(['fit', train, '--method', 'parallel_small', '--out', str(d / 'm'),
                 '--no-figures', '--quiet']) == 0
    yield d, test
    methods._registered.pop('parallel_small', None)


def _table(text):
    """Return {paper figure number: 'here' cell} of a report's figure table."""
    rows = re.findall(r'^\| (\d+) \| [^|]+ \| (.+) \|$', text, flags=re.M)
    return {int(num): here for num, here in rows}


def _check_pngs(out, text, names):
    for name in names:
        data = (out / name).read_bytes()
        # a PNG with axes, lines and labels is tens of kB; 1000 bytes rules out an empty canvas
        assert data.startswith(PNG) and len(data) > 1000, name
        assert f']({name})' in text, name


@pytest.mark.slow  # a parallel-model fit and an apply drawing every paper figure (15-25 s)
def test_apply_parallel_report_has_every_paper_figure(pair):
    d, test = pair
    out = d / 'a'
    assert main(['apply', test, '--model', str(d / 'm' / 'model.json'), '--out', str(out),
                 *FAST]) == 0
    text = (out / 'report.md').read_text()
    table = _table(text)
    assert sorted(table) == list(range(10, 20))
    expected = {10: ['fig10_run.png'], 12: ['fig12_modes.png'], 13: ['fig13_classes.png'],
                14: ['fig14_tfpf.png'], 15: ['fig15_denoised.png'], 16: ['fig16_elman.png'],
                17: ['fig17_drift_part.png', 'fig17_drift.png'], 18: ['fig18_output.png'],
                19: ['fig19_allan.png']}
    for num, names in expected.items():
        assert sorted(re.findall(r'`([^`]+\.png)`', table[num])) == sorted(names), num
    # MOPSO is not re-run to draw Fig. 11: the row says where the figure is
    assert 'drawn by `fit`' in table[11] and '.png`' not in table[11]
    names = [n for ns in expected.values() for n in ns] + ['bandwidth.png', 'steps.png']
    _check_pngs(out, text, names)
    assert sorted(p.name for p in out.glob('*.png')) == sorted(names)


@pytest.mark.slow  # fit and apply with every figure (7-11 s)
def test_baseline_report_says_which_analogues_it_lacks(tmp_path):
    train, _, _ = _bag(tmp_path / 'train', 1)
    test, _, _ = _bag(tmp_path / 'test', 2)
    assert main(['fit', train, '--method', 'poly3', '--out', str(tmp_path / 'm'),
                 '--quiet']) == 0
    training = (tmp_path / 'm' / 'training.md').read_text()
    assert 'no analogue for `poly3`' in _table(training)[12]
    assert 'not drawn in this report' in _table(training)[19]
    _check_pngs(tmp_path / 'm', training, ['training_fig10_run.png', 'training_fig17_drift.png',
                                           'training_fig18_output.png'])
    out = tmp_path / 'a'
    assert main(['apply', test, '--model', str(tmp_path / 'm' / 'model.json'), '--out',
                 str(out), *FAST]) == 0
    text = (out / 'report.md').read_text()
    table = _table(text)
    assert sorted(table) == list(range(10, 20))
    for num in (11, 12, 13, 14, 15, 16):
        assert table[num] == f'no analogue for `poly3`: {PAPER_FIGURES[num][1]}'
    for num in (10, 17, 18, 19):
        assert '.png`' in table[num]
    _check_pngs(out, text, ['fig10_run.png', 'fig17_drift.png', 'fig18_output.png',
                            'fig19_allan.png'])


@pytest.mark.slow  # apply, then the figures redrawn from it (12-15 s)
def test_report_figures_reuse_the_last_apply(tmp_path, monkeypatch):
    train, _ = thermal_run(1, n=3000)
    test, _ = thermal_run(2, n=3000)
    model = SmallParallel(iterations=2, elman_epochs=2)
    model.fit(train, rng=np.random.default_rng(0))
    out = model.apply(test)
    calls = []
    real_vmd = parallel.vmd
    monkeypatch.setattr(parallel, 'vmd', lambda *a, **k: calls.append(1) or real_vmd(*a, **k))
    figs = model.report_figures(test, tmp_path)
    assert calls == []  # the run just applied: no second decomposition
    # what Fig. 15 shows as denoised is what apply compensated: out = denoised - prediction
    pred = model.drift_prediction_rad_s(test)
    for a, part in enumerate(model._report_parts[1]):
        z = part['zoom']
        np.testing.assert_allclose(part['zoom_denoised'] - pred[z, a], out[z, a], atol=1e-12)
        assert len(part['modes']) == model.axes[a]['k']
    # fit_info lives in this process: Fig. 11 is drawn too
    assert [n for n, _ in figs] == ['fig11_mopso.png', 'fig12_modes.png', 'fig14_tfpf.png',
                                    'fig15_denoised.png', 'fig16_elman.png',
                                    'fig17_drift_part.png']
    for name, caption in figs:
        assert (tmp_path / name).read_bytes().startswith(PNG)
        assert len(figure_numbers(caption)) == 1
    # another run object: decomposed once per axis for the figures
    other, _ = thermal_run(3, n=3000)
    assert model._parts_for(other) is model._report_parts[1]
    assert len(calls) == 3


def test_figure_numbers_and_missing_lines(tmp_path):
    assert figure_numbers('Raw (cf. Fig. 10)') == [10]
    assert figure_numbers('cf. Figs. 15, 18 and 19') == [15, 18, 19]
    assert figure_numbers('cf. Figs. 12-14') == [12, 13, 14]
    assert figure_numbers('bandwidth figure, 3 dB') == []
    (tmp_path / 'a.png').write_bytes(PNG)
    text = figures_markdown([('run (cf. Fig. 10)', tmp_path / 'a.png'),
                             ('Fig. 11 is elsewhere', None)], tmp_path, method='m')
    table = _table(text)
    assert table[10] == '`a.png`' and table[11] == 'none: Fig. 11 is elsewhere'
    assert table[12] == f'no analogue for `m`: {PAPER_FIGURES[12][1]}'
    assert table[19].startswith('not drawn in this report')
    assert text.count('![') == 1
