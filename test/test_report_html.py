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
report.html without a browser: the page holds the JSON, shows only its numbers, loads nothing.

The browser half (rendering, console errors, screenshots) is test_report_html_browser.py.
"""

import hashlib
import html
import json

from _html_report import check_static, parse_report
from gyro_noise_ros.analysis.card import card_markdown, verdict
from gyro_noise_ros.analysis.summary_md import glossary_markdown, in_short_markdown
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.cli.analyze import main as analyze_main
from gyro_noise_ros.htmlreport.figures import (envelope_decimate, log_decimate,
                                               MAX_SERIES_POINTS)
from gyro_noise_ros.htmlreport.page import markdown_to_html
import numpy as np
import pytest

T0_NS = 1_700_000_000 * 10**9
FAST = ['--chunk-size', '600', '--memory', '50', '--order-grid', '0:2:0.1', '--quiet',
        '--jobs', '1']
#: Page size limit of the demo's report (bytes).
DEMO_LIMIT_BYTES = 5 * 1024 * 1024


def write_bag(path, n, rate_hz, *, seed, drift_rad_s2=0.0):
    """Write a rosbag2 of ``n`` Imu messages: white gyro noise plus a bias ramp, +z up."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    gyro = rng.normal(0.0, 1e-3, (n, 3)) + drift_rad_s2 * t[:, None]
    accel = np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0.0, 0.01, (n, 3))
    stamps = T0_NS + np.round(t * 1e9).astype(np.int64)
    with ImuBagWriter(path, imu_topic='/imu/data_raw', temperature_topic=None) as w:
        w.write_imu(stamps, gyro, accel)
    return path


@pytest.fixture(scope='module')
def analyzed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('html')
    bags = [write_bag(tmp / 'bag_a', 4 * 600 + 50, 200.0, seed=1, drift_rad_s2=1e-6),
            write_bag(tmp / 'bag_b', 3 * 600, 200.0, seed=2)]
    out = tmp / 'out'
    # a label with HTML's special characters: the page must escape it, the JSON keep it
    assert analyze_main([*map(str, bags), '--out', str(out), '--label', 'a<b>&"c"', 'b2',
                         *FAST]) == 0
    return out, bags


def test_every_number_on_the_page_is_the_json(analyzed):
    out, _ = analyzed
    doc = json.loads((out / 'summary.json').read_text())
    page = check_static(out / 'report.html', doc, min_numbers=100)
    shown = {n[0] for n in page.nums}
    # the key numbers of every bag and axis are on the page
    for i, b in enumerate(doc['bags']):
        for axis in b['axes']:
            for key in ('offset_drift_deg_s_per_h', 'mean_variance_deg2_s2', 'alpha_var_mean',
                        'alpha_corr_mean', 'allan_datasheet/bias_stability_deg_h',
                        'allan_datasheet/arw_deg_per_sqrt_h'):
                assert f'/bags/{i}/axes/{axis}/{key}' in shown, key
    text = (out / 'report.html').read_text()
    visible = text[:text.index('<script type="application/json"')]
    assert 'a&lt;b&gt;&amp;&quot;c&quot;' in visible or 'a&lt;b&gt;&amp;"c"' in visible
    assert '<b>&' not in visible


def test_in_short_is_the_markdown_s(analyzed):
    out, _ = analyzed
    doc = json.loads((out / 'summary.json').read_text())
    md = in_short_markdown(doc)
    assert md in (out / 'summary.md').read_text()
    text = (out / 'report.html').read_text()
    # the page shows the same paragraphs, its glossary folded under them
    assert markdown_to_html(in_short_markdown(doc, glossary=False)) in text
    assert ('<details id="glossary"><summary>What the numbers mean</summary>\n'
            + markdown_to_html(glossary_markdown())) in text
    # the answer first: verdict, card, then "In short", figures, tables, method
    order = [text.index('<div id="verdict"')] + [
        text.index(f'<section id="{s}">') for s in ('card', 'in-short', 'figures', 'tables',
                                                    'method')]
    assert order == sorted(order)


def test_verdict_and_card_are_summary_md_s(analyzed):
    """The page opens with summary.md's verdict and card: gyro and accelerometer, every axis."""
    out, _ = analyzed
    doc = json.loads((out / 'summary.json').read_text())
    level, text = verdict(doc)
    md = (out / 'summary.md').read_text()
    assert md.startswith(f'# gyro_noise_analyze summary\n\n**Verdict: {level}**. {text}')
    assert card_markdown(doc) in md
    page = parse_report(out / 'report.html')
    card = page.sections['card']
    for i, b in enumerate(doc['bags']):
        for axis in 'xyz':
            assert f'gyro {axis}' in card and f'accel {axis}' in card
    shown = {n[0] for n in page.nums}
    for i, b in enumerate(doc['bags']):
        for axis in 'xyz':
            acc = f'/bags/{i}/accelerometer_allan/{axis}'
            for key in ('velocity_random_walk_m_s2_per_sqrt_hz', 'bias_stability_m_s2',
                        'bias_stability_ci_low_m_s2', 'bias_instability_m_s2'):
                assert f'{acc}/{key}' in shown, key
            gyro = f'/bags/{i}/axes/{axis}/allan_datasheet'
            for key in ('arw_deg_per_sqrt_h', 'arw_rad_per_sqrt_s', 'bias_stability_deg_h',
                        'bias_stability_ci_high_deg_h', 'bias_instability_deg_h'):
                assert f'{gyro}/{key}' in shown, key
    # the imu.yaml block is the file, character for character
    assert (out / 'imu.yaml').read_text() in card
    # the verdict's level is the first thing on the page after the title
    assert page.sections.get('card') is not None
    html = (out / 'report.html').read_text()
    assert f'<span class="level">{level}</span>' in html


def test_provenance_command_versions_inputs(analyzed):
    out, bags = analyzed
    page = parse_report(out / 'report.html')
    method = page.sections['method']
    assert 'gyro_noise_analyze' in method and '--chunk-size 600' in method
    for name in ('gyro_noise_ros', 'Python', 'numpy', 'bokeh'):
        assert name in method
    for bag in bags:
        for f in sorted(p for p in bag.rglob('*') if p.is_file()):
            digest = hashlib.sha256(f.read_bytes()).hexdigest()
            assert digest in method and str(f.stat().st_size) in method


def test_figures_are_inline_bokeh(analyzed):
    out, _ = analyzed
    text = (out / 'report.html').read_text()
    # BokehJS once, inline; five figures: Allan of the gyro and of the accelerometer, bias,
    # variance, orders
    assert text.count('<div class="figure">') == 5
    assert text.count('Bokeh=') + text.count('Bokeh =') >= 1
    assert '<script src=' not in text and '<link ' not in text


def test_no_html_writes_none(tmp_path):
    bag = write_bag(tmp_path / 'bag', 2 * 600, 200.0, seed=3)
    out = tmp_path / 'out'
    assert analyze_main([str(bag), '--out', str(out), '--no-html', *FAST]) == 0
    assert (out / 'summary.json').is_file() and not (out / 'report.html').exists()


def test_interrupted_page_leaves_nothing_that_looks_finished(tmp_path, monkeypatch):
    import gyro_noise_ros.app.analyze as app

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    # report.html is written inside the staged output: an interrupt while writing it publishes
    # none of the run's files
    monkeypatch.setattr(app, 'write_analyze_html', interrupted)
    bag = write_bag(tmp_path / 'bag', 2 * 600, 200.0, seed=4)
    out = tmp_path / 'out'
    assert analyze_main([str(bag), '--out', str(out), *FAST]) == 130
    assert not (out / 'report.html').exists() and not (out / 'summary.json').exists()


def _envelope_oracle(y, max_points):
    """Slow twin: each of max_points // 2 equal bins keeps its first min and first max."""
    n = len(y)
    bins = max_points // 2
    edges = [int(e) for e in np.linspace(0, n, bins + 1).astype(np.int64)]
    keep = []
    for b in range(bins):
        seg = [(y[i], i) for i in range(edges[b], edges[b + 1]) if np.isfinite(y[i])]
        if not seg:
            continue
        lo = min(seg, key=lambda p: (p[0], p[1]))[1]
        hi = min(seg, key=lambda p: (-p[0], p[1]))[1]
        keep += sorted({lo, hi})
    return keep


def test_envelope_decimation_keeps_every_extreme():
    rng = np.random.default_rng(5)
    y = rng.normal(size=50_001)
    y[1234] = 40.0
    y[40_000] = -40.0
    y[100:300] = np.nan
    keep = envelope_decimate(y, 2000)
    assert keep.size <= 2000 and np.all(np.diff(keep) > 0)
    assert 1234 in keep and 40_000 in keep
    assert list(keep) == _envelope_oracle(y, 2000)
    assert list(envelope_decimate(y[:500])) == list(range(500))
    assert envelope_decimate(y).size <= MAX_SERIES_POINTS


def test_log_decimation_is_even_in_log_tau():
    tau = np.arange(1, 100_001) / 1000.0
    keep = log_decimate(tau, 200)
    assert keep[0] == 0 and keep[-1] == tau.size - 1 and keep.size <= 202
    steps = np.diff(np.log10(tau[keep]))
    # 5 decades over ~200 points: 0.025 decade each; the dense end is integer-limited
    assert steps[-50:].max() < 0.05
    assert list(log_decimate(tau[:50], 200)) == list(range(50))


@pytest.mark.slow
def test_demo_length_report_is_small(tmp_path):
    """A record as long as ``make demo``'s (about 140 s at 6.66 kHz) gives a page under 5 MB."""
    # The page size depends on the number of chunks, averaging times and bags, not on the
    # identification settings: the demo's chunk size, a cheap order search.
    rate = 1e9 / 150_150
    bag = write_bag(tmp_path / 'bag', int(140 * rate), rate, seed=6)
    out = tmp_path / 'out'
    assert analyze_main([str(bag), '--out', str(out), '--chunk-size', '10000', '--memory', '50',
                         '--order-grid', '0:2:0.1', '--quiet', '--jobs', '1',
                         '--no-figures']) == 0
    size = (out / 'report.html').stat().st_size
    assert size <= DEMO_LIMIT_BYTES, size


# --- gyro_noise_thermal compare | apply ------------------------------------------------------

# slow (both tests on it): compare of two methods, a fit and two applies with figures and pages
# (10-20 s); the browser checks the same pages in test_report_html_browser.py.
@pytest.fixture(scope='module')
def thermal_outputs(tmp_path_factory):
    """Compare two toy methods and apply one (figures and pages written)."""
    return make_thermal_outputs(tmp_path_factory.mktemp('thermal'))


def make_thermal_outputs(tmp):
    """Run compare (two toy methods), fit and apply (with and without --no-html) under tmp."""
    from _thermal_toy import FirstOrderLowPass, LinearInT, write_thermal_bag
    from gyro_noise_ros.cli.thermal import main as thermal_main
    from gyro_noise_ros.thermal import methods

    methods.register_method('toy_linear', LinearInT)
    methods.register_method('toy_lowpass', FirstOrderLowPass)
    try:
        bags = []
        for seed in (1, 2):
            # the toy drift of test_thermal_cli: linear in T over a heating and cooling half-cosine
            rng = np.random.default_rng(seed)
            n = 6000
            t = np.arange(n) / 20.0
            temp_t = np.arange(0.0, t[-1] + 1.0, 1.0)
            temp = 10.0 + 15.0 * (1 - np.cos(2 * np.pi * temp_t / (t[-1] + 1.0)))
            gyro = rng.normal(0.0, 2e-3, (n, 3)) + np.outer(np.interp(t, temp_t, temp) - 25.0,
                                                            [2e-4, -1e-4, 5e-5])
            write_thermal_bag(tmp / f'run{seed}', t, gyro, temp_t, temp)
            bags.append(str(tmp / f'run{seed}'))
        quick = ['--f-lo-hz', '0.5', '--quiet']
        assert thermal_main(['compare', *bags, '--out', str(tmp / 'c'), '--methods',
                             'toy_linear,toy_lowpass', *quick]) == 0
        assert thermal_main(['fit', bags[0], '--method', 'toy_linear', '--out',
                             str(tmp / 'm'), '--quiet']) == 0
        assert thermal_main(['apply', bags[1], '--model', str(tmp / 'm' / 'model.json'),
                             '--out', str(tmp / 'a'), '--no-bag', *quick]) == 0
        assert thermal_main(['apply', bags[1], '--model', str(tmp / 'm' / 'model.json'),
                             '--out', str(tmp / 'a2'), '--no-bag', '--no-html',
                             *quick]) == 0
    finally:
        methods._registered.pop('toy_linear', None)
        methods._registered.pop('toy_lowpass', None)
    return tmp, bags


@pytest.mark.slow
def test_thermal_compare_page_is_compare_json(thermal_outputs):
    tmp, bags = thermal_outputs
    doc = json.loads((tmp / 'c' / 'compare.json').read_text())
    page = check_static(tmp / 'c' / 'report.html', doc, min_numbers=40)
    shown = {n[0] for n in page.nums}
    for name in ('toy_linear', 'toy_lowpass'):
        for axis in 'xyz':
            assert f'/methods/{name}/axes/{axis}/processed/residual_drift_deg_s' in shown
    text = page.sections['in-short']
    assert doc['best_held_out']['method'] in text
    for m in doc['methods'].values():
        for v in m['axes'].values():
            assert v['verdict']['text'] in text
    for bag in bags:
        assert bag in page.sections['method']
    # the verdict line is compare.md's; the card ranks the methods by x noise floor
    from gyro_noise_ros.thermal.report import compare_verdict

    level, line = compare_verdict(doc)
    assert (tmp / 'c' / 'compare.md').read_text().startswith(
        f'# Held-out comparison\n\n**{level}**: {line}')
    html = (tmp / 'c' / 'report.html').read_text()
    assert f'<div id="verdict" class="verdict verdict-{level.lower()}"' in html
    assert f'<span class="level">{level}</span>' in html
    assert {f'/ranking/{i}/mean_over_floor' for i in range(2)} <= shown
    assert all(r['method'] in page.sections['card'] for r in doc['ranking'])


@pytest.mark.slow
def test_thermal_apply_page_is_metrics_json(thermal_outputs):
    tmp, _ = thermal_outputs
    doc = json.loads((tmp / 'a' / 'metrics.json').read_text())
    page = check_static(tmp / 'a' / 'report.html', doc, min_numbers=20)
    assert {f'/axes/{a}/processed/residual_drift_deg_s' for a in 'xyz'} <= {
        n[0] for n in page.nums}
    assert (tmp / 'a' / 'report.html').read_text().count('<div class="figure">') == 4
    # the verdict line is report.md's; the card holds the yardstick
    from gyro_noise_ros.thermal.report import apply_verdict

    level, line = apply_verdict(doc)
    assert f'**{level}**: {line}' in (tmp / 'a' / 'report.md').read_text()
    assert f'<span class="level">{level}</span>' in (tmp / 'a' / 'report.html').read_text()
    assert {f'/yardstick/over_floor/{a}' for a in range(3)} <= {n[0] for n in page.nums}
    assert 'x noise floor' in page.sections['card']
    assert not (tmp / 'a2' / 'report.html').exists() and (tmp / 'a2' / 'metrics.json').exists()


# --- gyro_noise_calibrate ----------------------------------------------------------------------

def make_calibration(tmp):
    """Calibrate an emulated six-position record into tmp/cal (and tmp/cal_nohtml)."""
    from _reliability_common import six_position_record, write_bag as write_six
    from gyro_noise_ros.calibration.emulate import SensorErrors
    from gyro_noise_ros.cli.calibrate import main as calibrate_main

    record = six_position_record(dwell_s=20.0, seed=21,
                                 errors=SensorErrors(gyro_bias_rad_s=(0.01, -0.02, 0.005)))
    bag = write_six(tmp / 'six', *record)
    assert calibrate_main([str(bag), '--gravity', '9.81', '--out', str(tmp / 'cal')]) == 0
    assert calibrate_main([str(bag), '--gravity', '9.81', '--out', str(tmp / 'cal_nohtml'),
                           '--no-html']) == 0
    return tmp / 'cal', bag


def test_calibrate_page_is_calibration_json(tmp_path):
    out, bag = make_calibration(tmp_path)
    doc = json.loads((out / 'calibration.json').read_text())
    page = check_static(out / 'report.html', doc, min_numbers=40)
    shown = {n[0]: n for n in page.nums}
    # the SI values are shown in calibration.md's units, and checked through their scale
    assert shown['/accel/bias_m_s2/0'][3] == pytest.approx(1 / 9.80665e-3)
    assert '/gyro/bias_rad_s/2' in shown and '/gravity_check/dwells/0/z' in shown
    assert 'gyro_noise_calibrate' in page.sections['method']
    assert hashlib.sha256(next(p for p in sorted(bag.rglob('*')) if p.is_file())
                          .read_bytes()).hexdigest() in page.sections['method']
    assert not (tmp_path / 'cal_nohtml' / 'report.html').exists()
    assert (tmp_path / 'cal_nohtml' / 'calibration.json').exists()


# --- gyro_noise_reliability --------------------------------------------------------------------

def make_reliability(tmp):
    """Before/after static records (instability doubled) into tmp/rel (and tmp/rel_nohtml)."""
    from _reliability_common import static_record, write_bag as write_rec
    from gyro_noise_ros.calibration.emulate import SensorErrors
    from gyro_noise_ros.cli.reliability import main as reliability_main

    rate = 10.0
    n_acc, n_gyr = 0.02 / np.sqrt(rate), 2e-3 / np.sqrt(rate)
    # test_reliability_cli's sensor: an interval ~0.6 s .. ~125 s, closed by a 3000 s record
    errors = SensorErrors(accel_bias_instability_m_s2=n_acc / 2 / 0.664,
                          accel_random_walk_m_s2_sqrt_s=n_acc / 5,
                          gyro_bias_instability_rad_s=n_gyr / 2 / 0.664,
                          gyro_random_walk_rad_s_sqrt_s=n_gyr / 5)
    bags = [str(write_rec(tmp / name, *static_record(errors=e, rate_hz=rate, duration_s=3000.0,
                                                     seed=seed)))
            for name, e, seed in (('before', errors, 1),
                                  ('after', errors.stressed(instability_factor=2.0), 2))]
    # --static off: this sensor's bias walk is cut as motion by the static-segment rule
    # (test_reliability_cli.WHOLE)
    args = ['--before-static', bags[0], '--after-static', bags[1], '--no-figures', '--static',
            'off']
    assert reliability_main([*args, '--out', str(tmp / 'rel')]) == 0
    assert reliability_main([*args, '--out', str(tmp / 'rel_nohtml'), '--no-html']) == 0
    return tmp / 'rel', bags


def test_reliability_page_is_reliability_json(tmp_path):
    out, bags = make_reliability(tmp_path)
    doc = json.loads((out / 'reliability.json').read_text())
    page = check_static(out / 'report.html', doc, min_numbers=30)
    shown = {n[0] for n in page.nums}
    for ch in ('accel_x', 'gyro_z'):
        assert f'/bias_instability_interval/{ch}/width_before_s' in shown
        assert f'/bias_instability_interval/{ch}/verdict' in shown
    for ch, e in doc['bias_instability_interval'].items():
        assert f'{ch}: {e["verdict"]}' in page.sections['in-short']
    # the verdict line is the fixed-tau verdict (overall): its level, each sensor's sentence
    text = (out / 'report.html').read_text()
    line = text[text.index('<div id="verdict"'):]
    line = line[:line.index('</div>')]
    levels = {'beyond': 'error', 'undetermined': 'info', 'within': 'ok'}
    worst = min((levels[e['verdict']] for e in doc['overall'].values()),
                key=('error', 'info', 'ok').index)
    assert f'verdict-{worst}' in line
    for sensor, e in doc['overall'].items():
        assert html.escape(e['sentence'], quote=False) in line, (sensor, line)
    assert not (tmp_path / 'rel_nohtml' / 'report.html').exists()


# --- gyro_noise_excitation ---------------------------------------------------------------------

def make_excitation(tmp):
    """Check a sine dwell before and after (5 % second harmonic after) into tmp/exc(_nohtml)."""
    from gyro_noise_ros.cli.excitation import main as excitation_main

    g, fs = 9.80665, 100.0
    t = np.arange(3000) / fs
    bags = []
    for name, amp, h2, seed in (('b', 0.3 * g, 0.0, 0), ('a', 0.28 * g, 0.05, 1)):
        rng = np.random.default_rng(seed)
        accel = np.zeros((t.size, 3))
        accel[:, 2] = g
        accel[:, 0] = (amp * np.sin(2 * np.pi * 8.0 * t + 0.4)
                       + h2 * amp * np.sin(4 * np.pi * 8.0 * t + 1) + rng.normal(0, 0.04, t.size))
        with ImuBagWriter(tmp / name, temperature_topic=None) as w:
            w.write_imu(T0_NS + np.round(t * 1e9).astype(np.int64), np.zeros((t.size, 3)), accel)
        bags.append(str(tmp / name))
    args = [*bags, '--sensor', 'accel', '--axis', 'x', '--dwell', '8', '--no-figures']
    assert excitation_main([*args, '--out', str(tmp / 'exc')]) == 0
    assert excitation_main([*args, '--out', str(tmp / 'exc_nohtml'), '--no-html']) == 0
    return tmp / 'exc', bags


def test_excitation_page_is_excitation_json(tmp_path):
    out, _ = make_excitation(tmp_path)
    doc = json.loads((out / 'excitation.json').read_text())
    page = check_static(out / 'report.html', doc, min_numbers=30)
    shown = {n[0]: n for n in page.nums}
    # SI in the JSON, mg on the page (the unit policy, excitation.md's unit), checked through
    # the scale
    assert shown['/before/amplitude_m_s2'][3] == pytest.approx(1 / 9.80665e-3)
    assert '/change/amplitude_relative' in shown
    # the first screen: a 5 % second harmonic after the stress is a defect beyond the tolerance
    html = (out / 'report.html').read_text()
    assert '<span class="level">ERROR</span>' in html and 'after: DISTORTED' in html
    card = page.sections['card']
    assert 'DISTORTED' in card and 'beyond the' in card and '/after/thd' in shown
    assert not (tmp_path / 'exc_nohtml' / 'report.html').exists()


def test_page_pieces_nan_pointers_markdown(tmp_path):
    from gyro_noise_ros.htmlreport.page import (Num, Page, pointer, resolve_pointer, Table,
                                                write_report_html)

    doc = {'a/b': {'~x': [1.5, float('nan')]}, 'none': None, 'ok': True}
    p = pointer('a/b', '~x', 1)
    assert p == '/a~1b/~0x/1' and resolve_pointer(doc, pointer('a/b', '~x', 0)) == 1.5
    with pytest.raises(KeyError):
        resolve_pointer(doc, '/missing')
    # a NaN in a tool's JSON (json.dumps writes it) never fails the page
    page = Page(title='t', data=doc, in_short_markdown='## In short\n\n* **a**: `b` <c>\n  d',
                tables=(Table('T', ('Name', 'Value'),
                              (('a', Num(p, '.3g')), ('n', Num('/none')), ('o', Num('/ok')))),))
    text = write_report_html(page, tmp_path / 'r.html').read_text()
    assert '>nan</span>' in text and '>n/a</span>' in text and '>yes</span>' in text
    assert ('<ul><li><strong>a</strong>: <code>b</code> &lt;c&gt; d</li></ul>'
            in markdown_to_html(page.in_short_markdown))
    # no figure: no BokehJS at all
    assert 'Bokeh' not in text


# --- gyro_noise_explain ------------------------------------------------------------------------

def make_explain(tmp):
    """Explain one axis of a CSV record of the paper's noise (small ensemble) into tmp/exp."""
    from gyro_noise_ros.cli.explain import main as explain_main
    from gyro_noise_ros.core.simulate import simulate_fractional_noise

    rate = 1000.0
    rng = np.random.default_rng(12)
    n = 14500
    gyro = np.stack([simulate_fractional_noise(n, 1.3, -0.4, 1e-3, rng=rng, memory=60)
                     for _ in range(3)], 1)
    path = tmp / 'rec.csv'
    lines = ['time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s']
    lines += [f'{k / rate!r},{float(g[0])!r},{float(g[1])!r},{float(g[2])!r}'
              for k, g in enumerate(gyro)]
    path.write_text('\n'.join(lines) + '\n')
    common = [str(path), '--axis', 'x', '--ensemble', '4', '--max-steps', '1', '--static',
              'off', '--quiet']
    assert explain_main([*common, '--out', str(tmp / 'exp')]) == 0
    assert explain_main([*common, '--out', str(tmp / 'exp_nohtml'), '--no-html']) == 0
    return tmp / 'exp', path


def test_explain_page_is_explain_json(tmp_path):
    out, _ = make_explain(tmp_path)
    doc = json.loads((out / 'explain.json').read_text())
    page = check_static(out / 'report.html', doc, min_numbers=12)
    shown = {n[0] for n in page.nums}
    assert {'/gap_initial', '/gap_final', '/baseline/alpha'} <= shown
    # the verdict line is report.md's verdict; the figures report.md shows are embedded
    html = (out / 'report.html').read_text()
    assert '<div id="verdict" class="verdict verdict-ok"' in html
    assert 'consistent with the baseline model' in html.split('<section id="card">')[0]
    assert html.count('<img class="png"') == 1 and 'src="data:image/png;base64,' in html
    assert 'gyro_noise_explain' in page.sections['method']
    assert not (tmp_path / 'exp_nohtml' / 'report.html').exists()
