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
import json

from _html_report import check_static, parse_report
from gyro_noise_ros import report
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
    shown = {p for p, _, _ in page.nums}
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
    md = report.in_short_markdown(doc)
    assert md in (out / 'summary.md').read_text()
    text = (out / 'report.html').read_text()
    assert markdown_to_html(md) in text
    # "In short" comes first, then figures, tables, method
    order = [text.index(f'<section id="{s}">') for s in ('in-short', 'figures', 'tables',
                                                         'method')]
    assert order == sorted(order)


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
    # BokehJS once, inline; four figures: Allan, bias, variance, orders
    assert text.count('<div class="figure">') == 4
    assert text.count('Bokeh=') + text.count('Bokeh =') >= 1
    assert '<script src=' not in text and '<link ' not in text


def test_no_html_writes_none(tmp_path):
    bag = write_bag(tmp_path / 'bag', 2 * 600, 200.0, seed=3)
    out = tmp_path / 'out'
    assert analyze_main([str(bag), '--out', str(out), '--no-html', *FAST]) == 0
    assert (out / 'summary.json').is_file() and not (out / 'report.html').exists()


def test_interrupted_page_leaves_nothing_that_looks_finished(tmp_path, monkeypatch):
    import gyro_noise_ros.cli.analyze as cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    # report.html is written inside the staged output: an interrupt while writing it publishes
    # none of the run's files
    monkeypatch.setattr(cli, 'write_analyze_html', interrupted)
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

