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
Tests of gyro_noise_analyze.

Tiny recordings from the conftest factory (rosbag2 sqlite3 and MCAP, ROS 1), every output file,
every exit code.
"""

import csv
import json
import math
import sys

from gyro_noise_ros.cli.analyze import main
from gyro_noise_ros.core.engine import analyze_chunk, EngineConfig, NoiseEngine
from gyro_noise_ros.core.fractional import make_grid
from gyro_noise_ros.core.simulate import simulate_fractional_noise
import numpy as np
import pytest
import yaml

SIZE, MEMORY, GRID = 600, 50, '0:2:0.1'
FAST = ['--chunk-size', str(SIZE), '--memory', str(MEMORY), '--order-grid', GRID, '--quiet']
PERIOD_NS = 150_150
T0 = 1_700_000_000 * 10**9
DEG = 180.0 / math.pi
ACCEL_SIGMA = 0.01  # m/s^2, white


def sim(n, seed=0, drift_rad_s2=0.0):
    rng = np.random.default_rng(seed)
    gyro = np.stack([simulate_fractional_noise(n, 1.4, -0.3, 1e-3, rng=rng, memory=MEMORY)
                     for _ in range(3)], 1)
    stamps = T0 + np.arange(n, dtype=np.int64) * PERIOD_NS
    gyro += drift_rad_s2 * ((stamps - T0) / 1e9)[:, None]
    accel = np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0.0, ACCEL_SIGMA, (n, 3))
    return stamps, gyro, accel


def write_ros2(make_record, path, stamps, gyro, accel, *, storage='sqlite3',
               topics=('/imu/data_raw',), temperature=None):
    """
    Write a rosbag2 record through the factory, received at the nominal period.

    Receive times always increase (readers deliver in receive-time order); the header stamps may
    not. One Temperature message every 100 Imu samples, stamped like that sample.
    """
    kw = {}
    if temperature is not None:
        kw = {'temperature_c': temperature[::100], 'temperature_stamps_ns': stamps[::100]}
    return make_record(path, gyro, stamps_ns=stamps, accel_m_s2=accel, storage=storage,
                       imu_topic=topics[0], extra_imu={t: (gyro, accel) for t in topics[1:]},
                       log_ns=T0 + np.arange(len(stamps), dtype=np.int64) * PERIOD_NS, **kw)


def read_csv(path):
    with open(path, newline='') as fh:
        return list(csv.DictReader(fh))


def engine_results(stamps, gyro, temperature=None, **kw):
    """Run the engine directly on the arrays: what the tool must reproduce from the bag."""
    cfg = EngineConfig(chunk_size=SIZE, memory=MEMORY, alphas=make_grid(0, 2, 0.1), allan=False,
                       **kw)
    engine = NoiseEngine(cfg)
    jobs = engine.ingest(stamps, gyro, temperature) + engine.flush()
    return [analyze_chunk(j) for j in jobs]


@pytest.fixture(scope='module')
def sqlite_bag(tmp_path_factory, make_record):
    n = 3 * SIZE + 77
    stamps, gyro, accel = sim(n, seed=1)
    temperature = 22.0 + 0.001 * np.arange(n)
    path = write_ros2(make_record, tmp_path_factory.mktemp('bags') / 'seq_ref', stamps, gyro,
                      accel, temperature=temperature)
    return path, stamps, gyro, temperature


def test_every_output_file_of_one_bag(sqlite_bag, tmp_path, capsys):
    path, stamps, gyro, temperature = sqlite_bag
    out = tmp_path / 'out'
    assert main([str(path), '--out', str(out), '--jobs', '1', *FAST[:-1]]) == 0
    printed = capsys.readouterr().out
    assert 'seq_ref: 1877 samples' in printed and 'wrote' in printed

    rows = read_csv(out / 'chunks.csv')
    for col in ('bag', 'axis', 'chunk', 't_start_s', 'samples', 'samples_lost', 'alpha_var',
                'f_var', 'alpha_corr', 'f_corr', 'bias_deg_s', 'variance_deg2_s2', 'tie_var',
                'tie_corr', 'var_min_deg2_s2', 'j_min_deg2_s2', 'temperature_c'):
        assert col in rows[0]
    assert len(rows) == 3 * 3
    # The tool interpolates the 1-in-100 temperature messages; the engine gets the same
    # interpolation here.
    t_idx = np.arange(0, len(stamps), 100)
    interp = np.interp(stamps.astype(float), stamps[t_idx].astype(float), temperature[t_idx])
    direct = {(r.chunk, r.axis): r for r in engine_results(stamps, gyro, interp)}
    for row in rows:
        r = direct[(int(row['chunk']), row['axis'])]
        assert row['bag'] == 'seq_ref' and row['status'] == 'ok'
        # CSV floats are written with repr: the exact same numbers come back.
        assert float(row['bias_deg_s']) == r.bias_rad_s * DEG
        assert float(row['variance_deg2_s2']) == r.variance_rad2_s2 * DEG ** 2
        assert (float(row['alpha_var']), float(row['f_var'])) == (r.alpha_var, r.f_var)
        assert (float(row['alpha_corr']), float(row['f_corr'])) == (r.alpha_corr, r.f_corr)
        assert float(row['temperature_c']) == r.temperature_c
        assert int(row['samples']) == SIZE and float(row['t_start_s']) == r.t_start_s

    doc = json.loads((out / 'summary.json').read_text())
    assert doc['tool'] == 'gyro_noise_analyze' and doc['options']['chunk_size'] == SIZE
    (bag,) = doc['bags']
    assert (bag['label'], bag['topic'], bag['storage']) == ('seq_ref', '/imu/data_raw', 'sqlite3')
    assert (bag['samples'], bag['samples_lost'], bag['out_of_order_stamps'],
            bag['tail_samples']) == (1877, 0, 0, 77)
    assert bag['rate_hz'] == pytest.approx(1e9 / PERIOD_NS)
    z = bag['axes']['z']
    zs = [r for r in direct.values() if r.axis == 'z']
    assert z['chunks'] == 3 and z['nan_samples'] == 0
    assert z['alpha_var_mean'] == pytest.approx(np.mean([r.alpha_var for r in zs]), rel=1e-12)
    assert z[
        'mean_variance_deg2_s2'] == pytest.approx(np.mean([r.variance_rad2_s2 for r in zs])
                                                  * DEG ** 2, rel=1e-12)
    for key in ('offset_drift_deg_s_per_h', 'offset_drift_stderr_deg_s_per_h',
                'variance_of_variances_deg4_s4', 'alpha_var_variance', 'alpha_corr_mean',
                'alpha_corr_variance', 'temperature_mean_c', 'allan'):
        assert key in z
    assert z['allan']['angle_random_walk_rad_per_sqrt_s'] > 0

    md = (out / 'summary.md').read_text()
    for title in ('offset drift of the chunk bias (paper 000 Table 3)',
                  'variance within chunks (paper 000 Table 4)',
                  'fractional order, variance method (paper 000 Table 5)',
                  'fractional order, correlation method (paper 000 Table 6)',
                  '(deg/s)/h', '(deg/s)^2', '| seq_ref |'):
        assert title in md

    allan = read_csv(out / 'allan.csv')
    assert set(allan[0]) == {'bag', 'axis', 'tau_s', 'adev_deg_s', 'ci_low_deg_s', 'ci_high_deg_s',
                             'n'}
    z_rows = [r for r in allan if r['axis'] == 'z']
    assert float(z_rows[0]['tau_s']) == pytest.approx(PERIOD_NS / 1e9)
    assert all(float(r['ci_low_deg_s']) <= float(r['adev_deg_s']) <= float(r['ci_high_deg_s'])
               for r in z_rows)

    imu = yaml.safe_load((out / 'imu.yaml').read_text())
    assert imu[
        'rostopic'] == '/imu/data_raw' and imu['update_rate'] == pytest.approx(1e9 / PERIOD_NS)
    assert imu['gyroscope_noise_density'] == max(
        bag['axes'][a]['allan_datasheet']['arw_rad_per_sqrt_s'] for a in 'xyz')
    assert 'gyroscope_random_walk' in imu
    # White accelerometer noise: ADEV = sigma / sqrt(tau fs), so the noise density is sigma /
    # sqrt(fs). The -1/2 region of 1877 samples starts at the short taus (thousands of averages
    # each); the largest of three axes is reported, so allow 15 %.
    assert imu['accelerometer_noise_density'] == pytest.approx(
        ACCEL_SIGMA * math.sqrt(PERIOD_NS / 1e9), rel=0.15)
    assert 'accelerometer_random_walk' in imu
    assert set(bag['accelerometer_allan']) == {'x', 'y', 'z'}

    curves = np.load(out / 'curves.npz')
    assert curves[
        'seq_ref/z/var'].shape == (3, 21) and list(curves['seq_ref/z/chunk']) == [0, 1, 2]
    for png in ('bias.png', 'variance.png', 'allan.png', 'curves_seq_ref_x.png',
                'curves_seq_ref_z.png'):
        assert (out / png).read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_three_storages_in_order_with_labels_and_two_jobs(sqlite_bag, tmp_path, make_record):
    sq, stamps, gyro, _ = sqlite_bag
    mc = write_ros2(make_record, tmp_path / 'mc', stamps, gyro, np.zeros_like(gyro),
                    storage='mcap')
    r1 = make_record(tmp_path / 'old.bag', gyro, stamps_ns=stamps, accel_m_s2=np.zeros_like(gyro),
                     storage='ros1')
    out = tmp_path / 'out'
    assert main([str(r1), str(mc), str(sq), '--label', 'ROS1', 'MCAP', 'SQL', '--jobs', '2',
                 '--axis', 'y', '--no-figures', '--out', str(out), *FAST]) == 0
    rows = read_csv(out / 'chunks.csv')
    assert [r['bag'] for r in rows] == ['ROS1'] * 3 + ['MCAP'] * 3 + ['SQL'] * 3
    assert {r['axis'] for r in rows} == {'y'}
    # Same samples in three containers, analysed in worker processes: identical numbers.
    cols = ('bias_deg_s', 'variance_deg2_s2', 'alpha_var', 'f_var', 'alpha_corr', 'f_corr',
            'j_min_deg2_s2')
    for k in range(3):
        assert [rows[k][c] for c in cols] == [
            rows[3 + k][c] for c in cols] == [rows[6 + k][c] for c in cols]
    doc = json.loads((out / 'summary.json').read_text())
    assert [b['storage'] for b in doc['bags']] == ['ros1', 'mcap', 'sqlite3']
    md = (out / 'summary.md').read_text()
    assert md.index('| ROS1 |') < md.index('| MCAP |') < md.index('| SQL |')
    assert not list(out.glob('*.png'))


def test_a_record_shorter_than_one_chunk_gets_its_allan_deviation_alone(odd_bags, tmp_path,
                                                                        capsys):
    # 200 samples against a 600-sample chunk: the Allan deviation and its readout, said so; the
    # chunk tables leave the bag out (issue 29: the 17 s x-io record was refused)
    out = tmp_path / 'o'
    assert main([*FAST, str(odd_bags / 'short'), '--out', str(out)]) == 0
    err = capsys.readouterr().err
    assert 'Allan deviation only: 200 samples, shorter than one chunk of 600' in err
    doc = json.loads((out / 'summary.json').read_text())
    b = doc['bags'][0]
    assert b['allan_only'].startswith('200 samples') and b['chunks_cut'] == 0
    assert all(a['allan_datasheet']['arw_rad_per_sqrt_s'] > 0 for a in b['axes'].values())
    md = (out / 'summary.md').read_text()
    assert 'Allan deviation only' in md and 'offset drift of the chunk bias' not in md
    assert (out / 'allan.csv').read_text().count('\n') > 10 and (out / 'imu.yaml').is_file()


def test_labels_one_at_a_time_as_the_readme_gives_them(sqlite_bag, tmp_path, make_record):
    # README: --label ref --label H1 (appended), the same as --label ref H1
    sq, stamps, gyro, _ = sqlite_bag
    mc = write_ros2(make_record, tmp_path / 'mc', stamps, gyro, np.zeros_like(gyro),
                    storage='mcap')
    out = tmp_path / 'out'
    assert main([str(sq), str(mc), '--label', 'ref', '--label', 'H1', '--axis', 'z', '--jobs',
                 '1', '--no-figures', '--no-html', '--out', str(out), *FAST]) == 0
    assert [b['label'] for b in json.loads((out / 'summary.json').read_text())['bags']] == [
        'ref', 'H1']


def test_reference_adds_health_verdicts(tmp_path, make_record, capsys):
    n = 8 * SIZE
    stamps, gyro, accel = sim(n, seed=3)
    ref = write_ros2(make_record, tmp_path / 'ref', stamps, gyro, accel)
    # A strong bias ramp on every axis: 2 (deg/s) per second, far above the chunk-mean noise.
    stamps2, gyro2, accel2 = sim(n, seed=4, drift_rad_s2=math.radians(2.0))
    h1 = write_ros2(make_record, tmp_path / 'h1', stamps2, gyro2, accel2, storage='mcap')
    assert main([str(ref), '--out', str(tmp_path / 'r'), '--jobs', '1', '--no-figures',
                 *FAST]) == 0
    out = tmp_path / 'o'
    assert main([str(ref), str(h1), '--reference', str(tmp_path / 'r' / 'summary.json'), '--jobs',
                 '1', '--no-figures', '--out', str(out), *FAST]) == 0
    doc = json.loads((out / 'summary.json').read_text())
    ref_z, h1_z = doc['bags'][0]['axes']['z'], doc['bags'][1]['axes']['z']
    # The reference judged against itself is within every tolerance; the ramp is far beyond it.
    assert ref_z['health']['level'] == 'OK'
    # The reference (white noise) has a statistically-zero drift: no ratio of it is formed;
    # the two slopes are still compared, in standard errors of both.
    assert h1_z['health']['level'] == 'ERROR'
    assert 'standard errors of both' in h1_z['health']['message']
    items = {i['key']: i['value'] for i in h1_z['health']['items']}
    assert items['Offset drift / reference'] == 'n/a'
    # 8 chunks: too few for the robust chunk statistics (10), said, not judged
    assert items['Order deviation, variance method'] == 'undetermined'
    assert doc['options']['thresholds']['reference_warn_sigma'] == 5.0
    md = (out / 'summary.md').read_text()
    assert '### Health verdict against the reference' in md
    # the verdict line opens summary.md: ERROR, naming the bag and axis; the card shows each
    # gyro axis' level against the reference
    assert md.startswith('# gyro_noise_analyze summary\n\n**Verdict: ERROR**. ')
    assert 'h1 z against the reference: ' in md.split('\n')[2]
    assert '| Against the reference |' in md and '| ERROR |' in md
    # A two-bag summary as reference needs the bag named, and the message names the option.
    capsys.readouterr()
    assert main([str(h1), '--reference', str(out / 'summary.json'), '--out', str(tmp_path / 'x'),
                 *FAST]) == 2
    assert 'choose one with --reference-bag' in capsys.readouterr().err
    assert main([str(h1), '--reference', str(out / 'summary.json'), '--reference-bag', 'h1',
                 '--jobs', '1', '--no-figures', '--out', str(tmp_path / 'x'), *FAST]) == 0
    again = json.loads((tmp_path / 'x'
                        / 'summary.json').read_text())['bags'][0]['axes']['z']['health']
    assert again['level'] == 'OK'  # h1 judged against itself


def test_nan_gaps_and_out_of_order_are_counted_not_fatal(tmp_path, capsys, make_record):
    stamps, gyro, accel = sim(3 * SIZE + 20, seed=5)
    gyro[SIZE + 3, 0] = np.nan
    stamps = np.delete(stamps, np.arange(2 * SIZE + 10, 2 * SIZE + 15))  # 5 samples lost
    gyro, accel = np.delete(gyro, np.arange(2 * SIZE + 10, 2 * SIZE + 15), 0), accel[:len(stamps)]
    stamps[50], stamps[51] = stamps[51], stamps[50]
    bag = write_ros2(make_record, tmp_path / 'bad', stamps, gyro, accel)
    out = tmp_path / 'o'
    assert main([str(bag), '--out', str(out), '--gap-policy', 'drop', '--jobs', '1',
                 '--no-figures', *FAST]) == 0
    doc = json.loads((out / 'summary.json').read_text())
    b = doc['bags'][0]
    # said in one line, counted, never reordered
    assert '1 stamp(s) earlier than the latest before them' in capsys.readouterr().err
    # The swap is one out-of-order stamp and a one-sample hole seen before the late sample (engine
    # doc).
    assert (b['samples_lost'], b['gaps'], b['out_of_order_stamps']) == (5 + 1, 1 + 1, 1)
    assert b['axes']['x']['nan_samples'] == 1 and b['axes']['x']['chunks_nan'] == 1
    # Chunk 0 holds the swap's hole and chunk 2 the 5-sample gap: both dropped; chunk 1 stays.
    assert b['axes']['y']['chunks_dropped'] == 2 and b['axes']['y']['chunks'] == 1
    statuses = {(r['axis'], r['chunk']): r['status'] for r in read_csv(out / 'chunks.csv')}
    assert statuses[('x', '1')] == 'nan' and statuses[('y', '1')] == 'ok'
    assert statuses[('y', '0')] == statuses[('y', '2')] == 'dropped'
    # the verdict line says the loss first: WARN
    first = (out / 'summary.md').read_text().split('\n')[2]
    assert first.startswith('**Verdict: WARN**. ') and '6 sample(s) lost in 2 gap(s)' in first


@pytest.fixture(scope='module')
def odd_bags(tmp_path_factory, make_record):
    d = tmp_path_factory.mktemp('odd')
    stamps, gyro, accel = sim(200, seed=6)
    write_ros2(make_record, d / 'two', stamps, gyro, accel, topics=('/a/imu', '/b/imu'))
    write_ros2(make_record, d / 'short', stamps, gyro, accel, temperature=np.full(200, 20.0))
    make_record(d / 'empty', np.zeros((0, 3)))  # the Imu topic, no message
    stamps, gyro, accel = sim(3000, seed=7)
    write_ros2(make_record, d / 'cut', stamps, gyro, accel, storage='mcap')
    (mcap,) = (d / 'cut').glob('*.mcap')
    mcap.write_bytes(mcap.read_bytes()[:mcap.stat().st_size // 2])
    (d / 'notabag.txt').write_text('hello')
    return d


@pytest.mark.parametrize('args, code, text', [
    (['missing'], 3, 'no such file or folder'),
    (['notabag.txt'], 3, 'not a bag'),
    (['two'], 3, 'choose one with --topic'),
    (['two', '--topic', '/c/imu'], 3, "topic '/c/imu' is not in bag"),
    (['short', '--topic', '/imu/temperature'], 3, 'not sensor_msgs/msg/Imu'),
    (['empty'], 3, 'no messages'),
    (['cut'], 3, 'truncated MCAP'),
    (['short', '--order-grid', '0:2'], 2, 'START:STOP:STEP'),
    (['short', '--chunk-size', '40'], 2, 'chunk_size'),
    (['short', 'two', '--label', 'only-one'], 2, 'one name per bag'),
    (['short', '--reference', 'nothing.json'], 3, 'cannot be read'),
    (['short', '--jobs', '0'], 2, '--jobs'),
    (['short', '--axis', 'w'], 2, 'invalid choice'),
])
def test_bad_input_gives_one_line_and_documented_exit_code(
        odd_bags, tmp_path, capsys, args, code, text):
    argv = [str(odd_bags / args[0]) if not args[0].startswith('-') else args[0], *args[1:]]
    argv = [str(odd_bags / a) if a in ('two', 'nothing.json') and i > 0 else a for i,
            a in enumerate(argv)]
    assert main([*FAST, *argv, '--out', str(tmp_path / 'o')]) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert text in err[-1]
    if code != 2 or 'invalid choice' not in text:
        assert len(err) == 1 and err[0].startswith('gyro_noise_analyze: error: ')


def test_progress_only_on_a_terminal(sqlite_bag, tmp_path, capsys, monkeypatch):
    path = sqlite_bag[0]
    args = [str(path), '--axis', 'x', '--no-figures', '--no-allan', '--jobs', '1', *FAST[:-1]]
    assert main([*args, '--out', str(tmp_path / 'a')]) == 0
    # stderr is not a terminal under pytest: plain lines, one per 10 % (no carriage returns in a
    # log); one batch here.
    err = capsys.readouterr().err
    assert err.startswith('seq_ref: 100% 1877/1877 messages, 3 chunks') and err.count('\n') == 1
    assert '\r' not in err
    monkeypatch.setattr(sys.stderr, 'isatty', lambda: True)
    assert main([*args, '--out', str(tmp_path / 'b')]) == 0
    err = capsys.readouterr().err
    assert '\rseq_ref: 100.0% 1877/1877 messages, 3 chunks' in err and err.endswith('\n')
    assert main([*args, '--quiet', '--out', str(tmp_path / 'c')]) == 0
    assert capsys.readouterr().err == ''


def test_out_that_cannot_be_created_is_one_line_before_any_bag_is_opened(
        odd_bags, tmp_path, capsys, monkeypatch):
    from gyro_noise_ros.bag import inputs

    opened = []

    class Spy(inputs.ImuBagReader):

        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            opened.append(self)

    # analyze opens its inputs through the one input layer
    monkeypatch.setattr(inputs, 'ImuBagReader', Spy)
    blocker = tmp_path / 'file'
    blocker.write_text('x')
    assert main([*FAST, str(odd_bags / 'short'), '--out', str(blocker / 'o')]) == 6
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'cannot be created' in err[0]
    assert opened == []  # --out is refused before the (possibly long) opening of the inputs
