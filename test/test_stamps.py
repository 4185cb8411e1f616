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
Stamps as a time base: equal stamps (packets stamped once), decreasing stamps, stamp gaps.

The live engine and gyro_noise_analyze share these rules (core/engine.py, core/timebase.py,
core/segments.py, app/analyze.py).
"""

import csv
import json
import math

from gyro_noise_ros.app import analyze as analyze_app
from gyro_noise_ros.cli import analyze
from gyro_noise_ros.core.engine import EngineConfig, NoiseEngine
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.core.segments import WindowStats
from gyro_noise_ros.core.timebase import estimate_rate
from gyro_noise_ros.errors import InputDataError
import numpy as np
import pytest
import yaml

FAST = ['--chunk-size', '2000', '--memory', '100', '--order-grid', '0:2:0.1', '--jobs', '1',
        '--axis', 'x', '--no-figures', '--quiet']
SIGMA = 0.01  # rad/s, white noise of every axis
T0 = 1000.0  # s, first stamp


def _packet_stamps(n, rate_hz, rng, *, joined=0.013, last=True, latency_s=(0.2e-3, 1.2e-3)):
    """
    Stamp ``n`` samples at ``rate_hz`` the way a host-stamped driver does.

    A fraction ``joined`` of the samples travel in the same USB packet as the next sample and
    share one stamp: the packet's last sample's time (``last``) or its first one's, plus one
    latency per packet (uniform in ``latency_s``).
    """
    t = np.arange(n) / rate_hz
    join = rng.random(n) < joined
    join[-1] = False
    packet = np.concatenate(([0], np.cumsum(~join[:-1])))
    ends = np.flatnonzero(~join)
    starts = np.concatenate(([0], ends[:-1] + 1))
    anchor = t[ends] if last else t[starts]
    latency = rng.uniform(*latency_s, packet[-1] + 1)
    return T0 + anchor[packet] + latency[packet]


def _write_csv(path, t_s, gyro):
    with open(path, 'w', newline='') as fh:
        w = csv.writer(fh)
        w.writerow(['time_s', 'gyro_x_rad_s', 'gyro_y_rad_s', 'gyro_z_rad_s'])
        for t, g in zip(t_s, gyro):
            w.writerow([f'{t:.6f}', *(f'{v:.8e}' for v in g)])
    return path


def _run(tmp_path, t_s, gyro, *extra):
    src = _write_csv(tmp_path / 'imu.csv', t_s, gyro)
    out = tmp_path / 'out'
    rc = analyze.main([str(src), '--out', str(out), *FAST, *extra])
    return rc, out


def test_packet_stamped_200hz_record_is_a_normal_time_base(tmp_path):
    # 65,536 samples at 200 Hz, 1.3 % of them sharing their packet's stamp (none decreasing):
    # once refused as "not a time base".
    rng = np.random.default_rng(11)
    n, rate = 65536, 200.0
    t = _packet_stamps(n, rate, rng)
    steps = np.diff(t)
    assert np.all(steps >= 0) and 0.012 < np.mean(steps == 0) < 0.015
    rc, out = _run(tmp_path, t, rng.normal(0.0, SIGMA, (n, 3)))
    assert rc == 0
    bag = json.loads((out / 'summary.json').read_text())['bags'][0]
    assert bag['rate_hz'] == pytest.approx(rate, rel=0.01)
    assert (bag['samples_lost'], bag['gaps'], bag['out_of_order_stamps']) == (0, 0, 0)
    assert bag['equal_stamps'] == int(np.sum(steps == 0))
    # White noise: ARW = sigma / sqrt(rate); within 10 % (about 3 times the scatter of an ADEV
    # read over 5 minutes of data)
    density = yaml.safe_load((out / 'imu.yaml').read_text())['gyroscope_noise_density']
    assert density == pytest.approx(SIGMA / math.sqrt(rate), rel=0.10)


@pytest.mark.parametrize('last', [True, False])
def test_packets_in_regular_stamps_are_no_loss_and_real_loss_is_exact(last):
    # 0.3 % of samples share a stamp (too few to call the stamps bursty), so the engine reads
    # loss from single steps; the samples of a packet fill the long step beside it whichever
    # sample's time the packet carries, also when a packet straddles two batches. Three real
    # holes away from any packet are counted exactly.
    rng = np.random.default_rng(12 if last else 13)
    n, rate = 60_000, 500.0
    # latency scatter 0.2 ms, a tenth of the period: a device-like regular clock
    t = _packet_stamps(n, rate, rng, joined=0.003, last=last, latency_s=(0.2e-3, 0.4e-3))
    keep = np.ones(n, dtype=bool)
    holes = []
    for start, size in ((15_000, 3), (30_000, 40), (45_000, 1)):
        while np.any(np.diff(t[start - 3:start + size + 3]) == 0):
            start += 7  # keep the hole clear of packets
        keep[start:start + size] = False
        holes.append(size)
    stamps = np.rint(t[keep] * 1e9).astype(np.int64)
    gyro = rng.normal(0.0, SIGMA, (stamps.size, 3))
    zeros = int(np.sum(np.diff(stamps) == 0))
    assert zeros > 100
    for batches in (np.array([stamps.size]), rng.integers(1, 400, stamps.size)):
        engine = NoiseEngine(EngineConfig(chunk_size=5000, memory=50,
                                          alphas=make_grid(0, 2, 0.5), axes=('x',),
                                          allan=False))
        bounds = np.concatenate(([0], np.cumsum(batches)))
        bounds = bounds[bounds < stamps.size].tolist() + [stamps.size]
        for a, b in zip(bounds[:-1], bounds[1:]):
            engine.ingest(stamps[a:b], gyro[a:b])
        engine.flush()
        c = engine.counts()
        assert not c.bursty
        assert (c.samples_lost, c.gaps, c.out_of_order) == (sum(holes), 3, 0)
        assert c.equal_stamps == zeros
        assert sorted(g[2] for g in c.longest_gaps) == sorted(holes)


def test_one_hour_stamp_gap_is_a_gap_not_motion(tmp_path, capsys):
    # 62.5 s, a stamp gap of one hour, 150 s more: once "12500 samples in motion".
    rng = np.random.default_rng(14)
    rate, before, after, missing = 200.0, 12_500, 30_000, 720_000
    k = np.concatenate([np.arange(before), before + missing + np.arange(after)])
    t = T0 + k / rate + rng.normal(0.0, 20e-6, k.size)
    rc, out = _run(tmp_path, t, rng.normal(0.0, SIGMA, (k.size, 3)))
    assert rc == 0
    bag = json.loads((out / 'summary.json').read_text())['bags'][0]
    assert bag['left_out']['motion'] == 0 and 'static_segment_s' not in bag['left_out']
    assert (bag['samples_lost'], bag['gaps']) == (missing, 1)
    (gap,) = bag['longest_gaps']
    assert gap['missing_samples'] == missing
    assert gap['start_s'] == pytest.approx((before - 1) / rate, abs=1e-3)
    assert gap['length_s'] == pytest.approx((missing + 1) / rate, abs=1e-3)
    err = capsys.readouterr().err
    assert 'in motion' not in err
    assert '1 stamp gap(s), 720000 sample(s) missing; the longest 3600' in err


def test_window_without_data_does_not_end_a_static_run():
    rng = np.random.default_rng(15)
    stats = WindowStats()
    for start in (0.0, 3600.0):  # two static stretches of 60 s, an hour apart
        t = start + np.arange(6000) / 100.0
        stats.update(np.rint(t * 1e9).astype(np.int64), rng.normal(0.0, SIGMA, (6000, 3)))
    seg = stats.segment()
    assert seg.static_throughout and len(seg.segments) == 1
    # motion still ends a run
    t = 7200.0 + np.arange(1000) / 100.0
    stats.update(np.rint(t * 1e9).astype(np.int64), rng.normal(1.0, 0.5, (1000, 3)))
    t = 7210.0 + np.arange(3000) / 100.0
    stats.update(np.rint(t * 1e9).astype(np.int64), rng.normal(0.0, SIGMA, (3000, 3)))
    assert len(stats.segment().segments) == 2


def test_decreasing_stamps_are_refused_or_counted_in_one_line():
    rng = np.random.default_rng(16)
    stamps = np.rint((T0 + np.arange(5000) / 100.0) * 1e9).astype(np.int64)
    gyro = rng.normal(0.0, SIGMA, (stamps.size, 3))
    cfg = EngineConfig(chunk_size=1000, memory=50, alphas=make_grid(0, 2, 0.5), allan=False)
    shuffled = stamps.copy()
    idx = rng.choice(stamps.size - 1, 300, replace=False)
    shuffled[idx], shuffled[idx + 1] = stamps[idx + 1], stamps[idx]
    with pytest.raises(InputDataError, match='go backwards') as err:
        NoiseEngine(cfg).ingest(shuffled, gyro)
    assert '\n' not in str(err.value)
    few = stamps.copy()
    few[[1000, 1001]] = few[[1001, 1000]]  # one decreasing step in 4999: counted
    engine = NoiseEngine(cfg)
    engine.ingest(few, gyro)
    assert (engine.counts().out_of_order, engine.counts().equal_stamps) == (1, 0)
    assert not estimate_rate(shuffled).usable
    assert 'go backwards' in estimate_rate(shuffled).warnings[0]


def test_stamps_that_never_advance_are_not_a_time_base():
    same = np.full(2000, 123_000_000_000, dtype=np.int64)
    est = estimate_rate(same, rate_hz=100.0)
    assert not est.usable and 'all 2000 stamps are equal' in est.warnings[0]
    with pytest.raises(InputDataError, match='stamps are equal'):
        NoiseEngine(EngineConfig(chunk_size=1000, memory=50, alphas=make_grid(0, 2, 0.5),
                                 allan=False)).ingest(same, np.zeros((2000, 3)))
    # the analyze tool then tries the log time; a packet of equal stamps is not that case
    assert analyze_app._stamps_unusable(same)
    assert not analyze_app._stamps_unusable(np.repeat(np.arange(100) * 10_000_000, 8))
