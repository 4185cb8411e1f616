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
Benchmark.

Size and browser load time of gyro_noise_analyze's report.html: a 12 h record against the demo's.

Usage:
    python bench/bench_report_html.py [--hours 12] [--demo-s 140] [--repeats 3]

What grows with the record length on the page is the per-chunk series (one point per chunk and
axis: 28,771 chunks per axis for 12 h at 6.66 kHz and 10,000-sample chunks) and the Allan curve's
averaging times (dense, ~10 per decade up to half the record); the tables do not. So both pages are
built by ``htmlreport.analyze.analyze_page`` from the summary.json document of one real (short)
analysis and from per-chunk arrays and Allan curves of the two lengths (seeded white noise and a
bias ramp; the numbers' values do not change the page size). A full 12 h analysis would take hours
on two cores and measure the analysis, not the page.

Prints, for each page: its size (bytes), the number of points drawn, and the load time in headless
Chromium (the median over ``--repeats`` of navigation start to BokehJS idle, every figure drawn),
and the 12 h / demo ratios. Needs ``/usr/bin/chromium`` and the playwright package (the browser
tests' requirements).
"""

import argparse
import json
import os
from pathlib import Path
import shlex
import statistics
import sys
import tempfile
import time
import types

from gyro_noise_ros.app.analyze import analyze_bags, AnalyzeParams
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.core.engine import EngineConfig
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.htmlreport.analyze import analyze_page
from gyro_noise_ros.htmlreport.page import write_report_html
import numpy as np

RATE_HZ = 1e9 / 150_150
CHUNK = 10_000
CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update',
                 '--disable-sync']


def _small_doc(tmp):
    """Return the summary.json document of a real short analysis (the page's tables)."""
    rng = np.random.default_rng(1)
    n = 4 * 600
    t = np.arange(n) / 200.0
    with ImuBagWriter(tmp / 'bag', imu_topic='/imu/data_raw', temperature_topic=None) as w:
        w.write_imu(1_700_000_000 * 10**9 + np.round(t * 1e9).astype(np.int64),
                    rng.normal(0.0, 1e-3, (n, 3)),
                    np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0.0, 0.01, (n, 3)))
    config = EngineConfig(chunk_size=600, memory=50, alphas=make_grid(0.0, 2.0, 0.1))
    result = analyze_bags(AnalyzeParams(paths=(str(tmp / 'bag'),), out_dir=str(tmp / 'out'),
                                        labels=('run',), config=config, figures=False,
                                        html=False))
    return json.loads(json.dumps(result.as_dict()))


def _arrays(duration_s, rng):
    """Per-chunk rows and Allan curves of a record of ``duration_s`` (three axes)."""
    chunks = int(duration_s * RATE_HZ // CHUNK)
    t = (np.arange(chunks) + 0.5) * CHUNK / RATE_HZ
    per_chunk, allan = {}, {}
    m = np.unique(np.round(np.logspace(0, np.log10(duration_s * RATE_HZ / 2),
                                       int(10 * np.log10(duration_s * RATE_HZ / 2)))))
    tau = m / RATE_HZ
    for axis in 'xyz':
        rows = np.column_stack([t, 1e-3 + 1e-9 * t + rng.normal(0, 1e-5, chunks),
                                1e-6 * (1 + rng.normal(0, 0.05, chunks)),
                                rng.normal(0.1, 0.02, chunks), rng.normal(0.1, 0.02, chunks)])
        per_chunk[axis] = [('run', rows)]
        adev = 1e-3 / np.sqrt(tau * RATE_HZ) + 1e-6
        allan[('run', axis)] = (types.SimpleNamespace(
            tau_s=tau, adev=adev, ci_low=adev * 0.9, ci_high=adev * 1.1,
            n_terms=np.maximum(1, (duration_s * RATE_HZ - 2 * m)).astype(np.int64)), None, None)
    return per_chunk, allan, chunks


def _load_ms(browser, path, repeats):
    times = []
    for _ in range(repeats):
        page = browser.new_page(viewport={'width': 1200, 'height': 900})
        page.goto(path.resolve().as_uri())
        page.wait_for_function(
            '() => window.Bokeh !== undefined && Bokeh.documents.length > 0 && '
            'Bokeh.documents.every(d => d.is_idle)', timeout=120_000)
        times.append(page.evaluate('performance.now()'))
        page.close()
    return statistics.median(times)


def main(argv=None):
    """Run the benchmark and print its table."""
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    p.add_argument('--hours', type=float, default=12.0)
    p.add_argument('--demo-s', type=float, default=140.0)
    p.add_argument('--repeats', type=int, default=3)
    args = p.parse_args(argv)
    from playwright.sync_api import sync_playwright

    print('command:', shlex.join(['python', *sys.argv]))
    rng = np.random.default_rng(7)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        doc = _small_doc(tmp)
        results = {}
        for name, seconds in (('demo', args.demo_s), ('12h', args.hours * 3600.0)):
            per_chunk, allan, chunks = _arrays(seconds, rng)
            t0 = time.perf_counter()
            path = write_report_html(analyze_page(doc, per_chunk=per_chunk, allan_store=allan),
                                     tmp / f'{name}.html')
            build_s = time.perf_counter() - t0
            results[name] = {'chunks': chunks, 'bytes': os.path.getsize(path), 'path': path,
                             'build_s': build_s}
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path='/usr/bin/chromium', args=CHROMIUM_ARGS)
            try:
                for r in results.values():
                    r['load_ms'] = _load_ms(browser, r['path'], args.repeats)
            finally:
                browser.close()
    print(f"{'page':6} {'chunks/axis':>12} {'bytes':>10} {'build (s)':>10} {'load (ms)':>10}")
    for name, r in results.items():
        print(f"{name:6} {r['chunks']:12d} {r['bytes']:10d} {r['build_s']:10.2f} "
              f"{r['load_ms']:10.0f}")
    a, b = results['12h'], results['demo']
    print(f"ratio 12h/demo: size {a['bytes'] / b['bytes']:.2f}, "
          f"load {a['load_ms'] / b['load_ms']:.2f} (12 h page loads in "
          f"{a['load_ms'] / 1000:.2f} s)")
    return 0


if __name__ == '__main__':
    sys.exit(main())
