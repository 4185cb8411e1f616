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

"""Sample rate, jitter and loss from stamps (core.timebase): real recordings, known patterns."""

import json

from _realdata import real_data
from gyro_noise_ros.cli import analyze
from gyro_noise_ros.core.engine import EngineConfig, NoiseEngine
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.core.timebase import estimate_rate, TimebaseTracker
import numpy as np
import pytest

MPU = ('mpu6050_static_sunsided', 'mpu6050_static_10min.csv')
PX4_CSV = ('px4_ulog_sample_static', 'sensor_combined.csv')


def _mpu_stamps():
    d = np.genfromtxt(real_data(*MPU), delimiter=',', names=True)
    return d['t_s']


def test_mpu6050_bursty_host_stamps_give_the_mean_rate_and_no_loss():
    t = _mpu_stamps()
    # SOURCE.md: 65,067 host-receive stamps, none non-monotonic, mean rate (n - 1) / span =
    # 99.317 Hz, median step 2 ms (the old estimator said 495.8 Hz).
    mean_rate = (t.size - 1) / (t[-1] - t[0])
    est = estimate_rate(t, unit='s')
    assert est.method == 'block_median' and est.bursty
    # 0.1 %: the block median's own standard error here is ~0.07 Hz (0.07 %).
    assert est.rate_hz == pytest.approx(mean_rate, rel=1e-3)
    assert abs(est.rate_hz - mean_rate) < 3 * est.stamp_rate_se_hz
    assert est.median_step_rate_hz > 400  # the old estimator, reported and wrong
    assert any('median stamp step' in w for w in est.warnings)
    assert est.loss_samples == 0 and est.out_of_order == 0 and est.usable
    assert 0.001 < est.jitter_s < 0.1


def test_px4_rate_matches_the_firmware_integration_intervals_and_loss_the_step_count():
    d = np.genfromtxt(real_data(*PX4_CSV), delimiter=',', names=True)
    stamps = d['timestamp_us'].astype(np.int64) * 1000
    est = estimate_rate(stamps)
    # Independent: each sample is the average over gyro_integral_dt (4.0 or 4.8 ms), so the true
    # mean rate is 1 / mean(integral dt) = 248.56 Hz; the median step says 250 Hz.
    truth = 1.0 / np.mean(d['gyro_integral_dt_s'])
    assert est.method == 'step_mean' and not est.bursty
    assert est.rate_hz == pytest.approx(truth, rel=1e-4)
    assert est.median_step_rate_hz == pytest.approx(250.0, rel=1e-6)
    # Independent count of the dropouts with the step rule on this regular clock: 51 samples in
    # 8 holes. The deficit against elapsed time agrees within its resolution.
    steps = np.diff(stamps)
    big = steps > 1.5 * np.median(steps)
    by_steps = int(np.sum(np.rint(steps[big] / np.median(steps)) - 1))
    assert by_steps == 51
    assert abs(est.loss_samples - by_steps) <= est.loss_resolution_samples


def _device_clock(n, rate, rng, *, drop=0, drift_ppm=0.0, jitter_s=0.0):
    k = np.arange(n, dtype=np.float64)
    t = k / rate * (1.0 + drift_ppm * 1e-6 * k / n)
    t = t + rng.normal(0.0, jitter_s, n) if jitter_s else t
    keep = np.ones(n, bool)
    if drop:
        keep[rng.choice(np.arange(1, n - 1), drop, replace=False)] = False
    return np.rint(t[keep] * 1e9).astype(np.int64), keep


def test_device_clock_with_random_loss_counts_it_exactly():
    rng = np.random.default_rng(1)
    stamps, _ = _device_clock(200_000, 6660.0, rng, drop=100, jitter_s=2e-6)
    est = estimate_rate(stamps)
    assert est.method == 'step_mean' and not est.bursty
    assert est.rate_hz == pytest.approx(6660.0, rel=1e-6)
    assert est.loss_samples == 100  # resolution here is ~2 samples
    assert est.mean_rate_hz < est.rate_hz  # the mean rate is biased by the loss


def test_slow_clock_drift_is_averaged():
    rng = np.random.default_rng(2)
    # 100 ppm of rate change over the record (two free-running clocks): the mean rate is the truth.
    stamps, _ = _device_clock(100_000, 100.0, rng, drift_ppm=100.0, jitter_s=1e-5)
    est = estimate_rate(stamps)
    assert est.rate_hz == pytest.approx(est.mean_rate_hz, rel=1e-4)
    assert est.loss_samples == 0


def _host_bursts(n, rate, rng, *, holes=()):
    """Deliver samples at ``rate`` in bursts (the host reads a buffer every 20-120 ms)."""
    t_true = np.arange(n) / rate
    keep = np.ones(n, bool)
    for start, length in holes:
        keep[start:start + length] = False
    reads = np.cumsum(rng.uniform(0.02, 0.12, int(t_true[-1] / 0.02) + 10))
    slot = np.searchsorted(reads, t_true)  # each sample arrives at the next read
    arrival = reads[slot] + np.arange(n) * 1e-6 % 1e-4  # a few us apart inside a burst
    return np.rint(arrival[keep] * 1e9).astype(np.int64)


def test_bursty_host_stamps_tell_jitter_from_loss():
    rng = np.random.default_rng(3)
    clean = estimate_rate(_host_bursts(120_000, 100.0, rng))
    assert clean.bursty and clean.method == 'block_median'
    assert clean.rate_hz == pytest.approx(100.0, rel=2e-3)  # ~4 se of this record
    assert clean.loss_samples == 0
    lossy = estimate_rate(_host_bursts(120_000, 100.0, rng, holes=((30_000, 400), (80_000, 600))))
    # 1000 samples really missing: found as a deficit against elapsed time, within the resolution.
    assert lossy.rate_hz == pytest.approx(100.0, rel=2e-3)
    assert abs(lossy.loss_samples - 1000) <= lossy.loss_resolution_samples


def test_usb_packets_sharing_one_stamp():
    # 1 kHz samples in USB packets of 32, each stamped with its packet's arrival (+ 1 ms jitter).
    rng = np.random.default_rng(4)
    n = 64_000
    packet = np.arange(n) // 32
    arrival = (packet + 1) * 32e-3 + rng.uniform(0, 1e-3, packet.max() + 1)[packet]
    est = estimate_rate(np.rint(arrival * 1e9).astype(np.int64))
    assert est.bursty and est.rate_hz == pytest.approx(1000.0, rel=1e-3)
    assert est.loss_samples == 0


def test_sequence_counter_gives_exact_loss():
    rng = np.random.default_rng(5)
    stamps, keep = _device_clock(50_000, 500.0, rng, drop=37)
    seq = np.flatnonzero(keep)
    est = estimate_rate(stamps, sequence=seq)
    assert est.method == 'sequence' and est.loss_samples == 37
    assert est.rate_hz == pytest.approx(500.0, rel=1e-6)


def test_shuffled_stamps_are_unusable_and_configured_rate_is_compared():
    rng = np.random.default_rng(6)
    stamps, _ = _device_clock(5000, 100.0, rng)
    est = estimate_rate(rng.permutation(stamps), rate_hz=100.0)
    assert not est.usable and 'go backwards' in est.warnings[0]
    est = estimate_rate(stamps, rate_hz=102.0)
    assert est.method == 'configured' and est.rate_hz == 102.0
    assert any('configured rate' in w for w in est.warnings)


def test_streaming_tracker_with_merges_matches_the_batch_estimate():
    rng = np.random.default_rng(7)
    stamps, _ = _device_clock(100_000, 6660.0, rng, drop=20, jitter_s=2e-6)
    tracker = TimebaseTracker(max_blocks=64)  # forces several pair merges
    for i in range(0, stamps.size, 777):
        tracker.update(stamps[i:i + 777])
    a, b = tracker.estimate(), estimate_rate(stamps)
    assert a.samples == b.samples and a.block_samples > b.block_samples
    assert a.rate_hz == pytest.approx(b.rate_hz, rel=1e-6)
    assert a.loss_samples == b.loss_samples == 20


def test_a_live_feed_of_small_batches_holds_bounded_block_rows():
    # A live analyzer feeds a batch per drain (133 stamps at 6.66 kHz every 20 ms): the tracker
    # keeps its blocks in arrays of bounded size, not one object per batch (the analyzer's RSS
    # once crawled with them, and summed their sizes at every update), and estimates as the
    # whole record does.
    rng = np.random.default_rng(7)
    stamps, _ = _device_clock(100_000, 6660.0, rng, drop=20, jitter_s=2e-6)
    live = TimebaseTracker(max_blocks=64)
    for i in range(0, stamps.size, 133):
        live.update(stamps[i:i + 133])
    a, b = live.estimate(), estimate_rate(stamps)
    assert a.rate_hz == pytest.approx(b.rate_hz, rel=1e-6)
    assert a.loss_samples == b.loss_samples == 20
    assert live._nb <= 64 and live._blocks.shape[0] <= 2 * 64 + 133
    assert all(not isinstance(v, list) for v in vars(live).values())


def test_engine_counts_use_the_whole_run_estimate_and_rescale_allan():
    rng = np.random.default_rng(8)
    stamps = _host_bursts(30_000, 100.0, rng)
    gyro = rng.normal(0.0, 1e-3, (stamps.size, 3))
    engine = NoiseEngine(EngineConfig(chunk_size=2000, memory=50, alphas=make_grid(0, 2, 0.1),
                                      axes=('x',), allan=True))
    for i in range(0, stamps.size, 1000):
        for job in engine.ingest(stamps[i:i + 1000], gyro[i:i + 1000]):
            engine.record(engine.analyze(job))
    counts = engine.counts()
    assert counts.bursty and counts.rate_method == 'block_median'
    assert counts.rate_hz == pytest.approx(100.0, rel=3e-3)
    assert counts.samples_lost == 0 and counts.gaps == 0
    allan = engine.summary()['x'].allan
    np.testing.assert_allclose(allan.tau_s, allan.m / counts.rate_hz)


@pytest.mark.parametrize('extra', [[], ['--rate-hz', '99.317'], ['--gap-policy', 'drop']])
def test_analyze_on_mpu6050_csv_reports_rate_and_no_loss(tmp_path, extra):
    path = real_data(*MPU)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--chunk-size', '10000', '--no-allan', *extra])
    assert rc == 0
    doc = json.loads((tmp_path / 'summary.json').read_text())
    bag = doc['bags'][0]
    assert bag['rate_hz'] == pytest.approx(99.317, rel=1e-3)
    assert bag['samples_lost'] == 0 and bag['gaps'] == 0 and bag['stamps_bursty']
    # 65,067 samples: six chunks of 10,000 analysed on every axis, whatever the gap policy.
    assert all(a['chunks'] == 6 for a in bag['axes'].values())
    assert bag['timebase']['median_step_rate_hz'] > 400
