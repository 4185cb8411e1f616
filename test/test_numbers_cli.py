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

"""Bad input that once passed silently, and the inputs both tools read."""

import json

from _realdata import real_data
from gyro_noise_ros.cli import analyze, explain, importer
from gyro_noise_ros.explain.inputs import load_input
from gyro_noise_ros.link import protocol as p
from gyro_noise_ros.link.sdlog import SdLogWriter
import numpy as np
import pytest

MPU = ('mpu6050_static_sunsided', 'mpu6050_static_10min.csv')
ULOG = ('px4_ulog_sample_static', 'sample.ulg')


@pytest.mark.parametrize('fill', [np.nan, 0.25])
def test_analyze_refuses_all_nan_or_constant_angular_velocity(
        tmp_path, fill, capsys, make_record):
    n = 4000
    bag = make_record(tmp_path / 'b.mcap', np.full((n, 3), fill), storage='mcap',
                      stamps_ns=10 ** 18 + np.arange(n, dtype=np.int64) * 1_000_000,
                      accel_m_s2=np.zeros((n, 3)))
    rc = analyze.main([str(bag), '--out', str(tmp_path / 'o'), '--chunk-size', '1000', '--memory',
                       '50', '--order-grid', '0:2:0.1', '--jobs', '1', '--no-figures', '--quiet'])
    assert rc == 4  # README: 4 = the data cannot be analysed
    assert 'no chunk could be analysed' in capsys.readouterr().err


@pytest.mark.parametrize('grid', ['0:2:5', '1:1:0.1', '-1:2:0.1', '0:2:0.3', '0:2.5:0.1'])
def test_analyze_refuses_degenerate_or_out_of_domain_order_grids(tmp_path, grid, capsys):
    rc = analyze.main([str(tmp_path / 'missing.mcap'), '--out', str(tmp_path / 'o'),
                       f'--order-grid={grid}'])
    assert rc == 2 and '--order-grid' in capsys.readouterr().err


def test_analyze_falls_back_to_log_time_on_shuffled_header_stamps(
        tmp_path, capsys, make_record):
    rng = np.random.default_rng(0)
    n = 6000
    log = 10 ** 18 + np.arange(n, dtype=np.int64) * 1_000_000  # 1 kHz receive times
    header = rng.permutation(log)
    make_record(tmp_path / 'b.mcap', rng.normal(0, 1e-3, (n, 3)), stamps_ns=header, log_ns=log,
                accel_m_s2=np.zeros((n, 3)), storage='mcap')
    rc = analyze.main([str(tmp_path / 'b.mcap'), '--out', str(tmp_path / 'o'), '--chunk-size',
                       '1000', '--memory', '50', '--order-grid', '0:2:0.1', '--jobs', '1',
                       '--no-figures', '--quiet', '--no-allan'])
    assert rc == 0
    assert 'log time' in capsys.readouterr().err
    bag = json.loads((tmp_path / 'o' / 'summary.json').read_text())['bags'][0]
    assert bag['time_source'] == 'log' and bag['rate_hz'] == pytest.approx(1000.0, rel=1e-6)


def test_explain_and_analyze_read_the_same_csv_with_one_rate_estimator(tmp_path):
    path = real_data(*MPU)
    meas = load_input(path, axis='x')
    assert meas.timebase.method == 'block_median'
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--no-allan', '--axis', 'x'])
    assert rc == 0
    bag = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]
    # Same estimator on the same integer-ns stamps: equal to rounding.
    assert bag['rate_hz'] == pytest.approx(meas.rate_hz, rel=1e-9)


def test_both_tools_read_px4_ulog(tmp_path):
    path = real_data(*ULOG)
    meas = load_input(path, axis='z')
    # SOURCE.md: 17,070 sensor_combined samples; the rate is the firmware's mean integration rate.
    assert meas.n == 17070 and meas.rate_hz == pytest.approx(248.56, rel=1e-3)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--no-allan', '--chunk-size', '5000', '--static', 'off'])
    assert rc == 0
    bag = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]
    assert bag['storage'] == 'ulog' and bag['samples'] == 17070
    assert bag['rate_hz'] == pytest.approx(meas.rate_hz, rel=1e-9)


#: Folders of IMU recordings in ../shared/data/real (the clock data of allantools is not IMU).
IMU_FOLDERS = ('adis16405_static', 'mpu6050_static_sunsided', 'px4_ulog_sample_static',
               'xio_fusion_sensor_data')


def _analyze_reads(path):
    """Return (stamps, gyro) as gyro_noise_analyze's reader yields them, or the error raised."""
    from gyro_noise_ros.app import analyze as analyze_app
    from gyro_noise_ros.errors import GyroNoiseError

    try:
        with analyze_app._open(path, None, None, None) as reader:
            batches = list(reader.iter_batches())
    except GyroNoiseError as err:
        return err
    return (np.concatenate([b.stamp_ns for b in batches]),
            np.concatenate([b.gyro for b in batches]))


def test_explain_reads_every_real_record_that_analyze_reads():
    from gyro_noise_ros.app.explain import ExplainParams, prepare_explain
    from gyro_noise_ros.errors import GyroNoiseError

    files = sorted(p for folder in IMU_FOLDERS for p in real_data(folder).iterdir()
                   if p.name != 'SOURCE.md')
    read = 0
    for path in files:
        theirs = _analyze_reads(path)
        try:
            ours = prepare_explain(ExplainParams(path=path, static='off'))
        except GyroNoiseError as err:
            # what analyze refuses, explain refuses with the same words and exit code
            assert isinstance(theirs, GyroNoiseError), (path, err)
            assert (type(err), str(err)) == (type(theirs), str(theirs)), path
            continue
        assert not isinstance(theirs, Exception), (path, theirs)
        stamps, gyro = theirs
        for meas in ours.measurements:
            column = gyro[:, 'xyz'.index(meas.axis)]
            np.testing.assert_array_equal(meas.rate, column, err_msg=str(path))
            np.testing.assert_array_equal(meas.t_s, (stamps - stamps[0]) * 1e-9)
        read += 1
    # SOURCE.md: the MPU6050 CSV, the PX4 ULog and its sensor_combined.csv extract
    # (timestamp_us), and the x-io CSV ('Gyroscope X (deg/s)', refused by explain before)
    assert read == 4, [p.name for p in files]


@pytest.mark.slow  # explain on all three axes of a real record (5-10 s)
def test_explain_on_the_xio_csv_exits_as_analyze_does(tmp_path, capsys):
    path = real_data('xio_fusion_sensor_data', 'sensor_data.csv')
    # the longest static segment is 17 s (1,733 samples): too short for both tools (4)
    assert explain.main([str(path), '--axis', 'z', '--out', str(tmp_path / 'a')]) == 4
    assert 'too short to analyse: 1733 samples' in capsys.readouterr().err
    # the whole record (13,514 samples, hand motion included) is analysed when asked for
    assert explain.main([str(path), '--axis', 'z', '--static', 'off', '--ensemble', '4',
                         '--max-steps', '0', '--bootstrap', '0', '--quiet',
                         '--out', str(tmp_path / 'b')]) == 0
    data = json.loads((tmp_path / 'b' / 'explain.json').read_text())
    assert data['input']['samples'] == 13514 and data['input']['left_out']['motion'] == 0


def test_explain_validates_options_before_loading(tmp_path, capsys):
    # The input does not exist: a bad option must be reported first (exit 2, not 3).
    for bad in (['--ensemble', '2'], ['--max-steps', '-1'], ['--rate-hz', '-5']):
        assert explain.main([str(tmp_path / 'none.mcap'), '--out', str(tmp_path / 'o'), *bad]) == 2
        assert 'none.mcap' not in capsys.readouterr().err


def test_import_of_a_missing_file_exits_3(tmp_path, capsys):
    assert importer.main([str(tmp_path / 'S001F000.GNL'), '--out', str(tmp_path / 'b')]) == 3
    assert 'does not exist' in capsys.readouterr().err


def test_import_recovers_the_scales_from_the_ack_after_a_corrupt_header(tmp_path):
    rng = np.random.default_rng(1)
    n = 512
    samples = np.zeros(n, dtype=p.SAMPLE_DTYPE)
    samples['seq'] = np.arange(n)
    samples['t_us'] = np.arange(n) * 150
    samples['gyro'] = rng.integers(-300, 300, (n, 3))
    samples['accel'][:, 2] = 4096
    logs = tmp_path / 'sd'
    logs.mkdir()
    with SdLogWriter(logs, sequence_id=1, odr_hz=6667.0, gyro_fs_dps=500, accel_fs_g=8) as w:
        w.write_ack(p.Ack(command_id=1, ok=True, odr_hz=6667.0, gyro_fs_dps=500, accel_fs_g=8))
        w.write_samples(samples)
        paths = list(w.paths)
    clean_bag = tmp_path / 'clean'
    assert importer.main([*paths, '--out', str(clean_bag)]) == 0
    data = bytearray(open(paths[0], 'rb').read())
    assert data[3] == p.FRAME_LOG_HEADER
    data[8] ^= 0x10  # one flipped bit inside the header payload: its CRC fails
    open(paths[0], 'wb').write(bytes(data))
    bag = tmp_path / 'recovered'
    assert importer.main([*paths, '--out', str(bag)]) == 0
    from gyro_noise_ros.bag import ImuBagReader

    def gyro_of(path):
        with ImuBagReader(path) as reader:
            return np.concatenate([b.gyro for b in reader.iter_batches()])

    # The same scale (500 deg/s) as with the intact header: identical angular rates.
    np.testing.assert_array_equal(gyro_of(bag), gyro_of(clean_bag))


def test_px4_motion_is_skipped_and_said(tmp_path, capsys):
    path = real_data(*ULOG)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--no-allan', '--chunk-size', '5000'])
    assert rc == 0
    err = capsys.readouterr().err
    assert 'in motion' in err and 'left out' in err
    bag = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]
    # SOURCE.md (independent, 1 s rolling std of |w| < 0.005 rad/s): static from row 1700,
    # t = 6.87 s, to the end; a 1 s window grid puts the start within a second of it.
    a, b = bag['left_out']['static_segment_s']
    assert 6.0 <= a <= 7.9 and b >= 68.3
    assert abs(bag['left_out']['motion'] - 1700) < 250  # ~1 s of 248 Hz samples
    assert bag['samples'] + bag['left_out']['motion'] == 17070
    # Off: everything is analysed, handling included (variance ~1e5x the static one).
    rc = analyze.main([str(path), '--out', str(tmp_path / 'all'), '--jobs', '1', '--no-figures',
                       '--quiet', '--no-allan', '--chunk-size', '5000', '--static', 'off'])
    assert rc == 0
    whole = json.loads((tmp_path / 'all' / 'summary.json').read_text())['bags'][0]
    assert whole['samples'] == 17070
    moving, still = (d['axes']['x']['mean_variance_deg2_s2'] for d in (whole, bag))
    assert moving > 100 * still


def test_xio_static_segments_match_the_source_notes(tmp_path):
    path = real_data('xio_fusion_sensor_data', 'sensor_data.csv')
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--no-allan', '--chunk-size', '1000', '--memory', '100'])
    assert rc == 0
    bag = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]
    # SOURCE.md: static at t = 0.5-12.5 s and 117.2-134.8 s, the hand motion in between.
    a, b = bag['left_out']['static_segment_s']
    assert 116.0 <= a <= 119.0 and b >= 134.0
    segs = bag['left_out']['static_segments_s']
    assert any(s[0] <= 1.0 and 11.0 <= s[1] <= 14.0 for s in segs)


def test_start_end_window_on_mpu6050(tmp_path, capsys):
    path = real_data(*MPU)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--no-allan', '--start', '100', '--end', '400', '--chunk-size', '5000'])
    assert rc == 0
    bag = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]
    left = bag['left_out']
    # 300 s at the true mean rate 99.32 Hz; 1 % for the bursty stamps at the window edges.
    assert bag['samples'] == pytest.approx(300 * 99.32, rel=0.01)
    assert bag['samples'] + left['before_start'] + left['after_end'] + left['motion'] == 65067
    assert left['motion'] == 0  # a static recording
    assert 'before --start' in capsys.readouterr().err
    bad = ['--start', '5', '--end', '2']
    assert analyze.main([str(path), '--out', str(tmp_path / 'x'), *bad]) == 2


@pytest.mark.slow  # explain on three axes of a minute at 250 Hz (10-20 s)
def test_explain_runs_all_axes_in_one_report_on_a_minute_at_250_hz(tmp_path, capsys):
    # A minute of the real PX4 log at rest (the handling before is skipped automatically):
    # 15,246 samples, under the old 16,384-sample floor. The whole loop runs on every axis (6
    # members, 5 bootstrap records keep it short): a transient fitted on this record once printed
    # a time constant of 620 +/- 230 s from 62 s of data, which the time-scale rule must refuse.
    path = real_data(*ULOG)
    out = tmp_path / 'ex'
    rc = explain.main([str(path), '--out', str(out), '--ensemble', '6', '--bootstrap', '5',
                       '--quiet'])
    assert rc == 0
    captured = capsys.readouterr()
    assert 'in motion' in captured.err
    index = json.loads((out / 'explain.json').read_text())
    assert set(index['axes']) == {'x', 'y', 'z'}
    report = (out / 'report.md').read_text()
    assert all(f'axis {a}:' in report for a in 'xyz')
    assert '(axis_z/overview.png)' in report and (out / 'axis_z' / 'overview.png').is_file()
    from matplotlib.image import imread
    # 8 signature panels must be readable: at least 1600 px wide (200 px per panel).
    assert imread(out / 'axis_z' / 'overview.png').shape[1] >= 1600
    checked = 0
    for axis in 'xyz':
        data = json.loads((out / f'axis_{axis}' / 'explain.json').read_text())
        # The static segment only: 248.56 Hz (firmware integration rate) over ~61 s.
        assert data['input']['rate_hz'] == pytest.approx(248.56, rel=1e-3)
        assert 14_000 < data['input']['samples'] < 15_600
        assert data['input']['left_out']['motion'] > 0
        assert index['axes'][axis]['verdict'] == data['verdict']
        for step in data['steps']:
            for name, check in step['time_scales'].items():
                checked += 1
                low, high = check['resolvable']
                entry = step['uncertainty'][name]
                if entry['resolved']:
                    # a resolved time scale lies inside what 61 s of data resolve
                    assert low <= entry['ci95'][0] and entry['ci95'][1] <= high, (axis, step)
                else:
                    assert entry['note'].startswith('unresolved'), (axis, step)
                if not check['resolved']:
                    assert not entry['resolved']
                    # printed as the bound, never as a value
                    assert f'{name} = ' not in captured.out and f'{name} ' in captured.out
    # every axis names the 116 Hz line (its frequency is a time scale) at least
    assert checked >= 3


def test_mpu6050_two_mode_orders_and_a_summary_for_people(tmp_path):
    path = real_data(*MPU)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures', '--quiet',
                       '--axis', 'x'])
    assert rc == 0
    a = json.loads((tmp_path / 'summary.json').read_text())['bags'][0]['axes']['x']
    # Independent: split the chunk orders of chunks.csv at 0.5 (the model's 0/1 alias).
    import csv
    with open(tmp_path / 'chunks.csv', newline='') as fh:
        orders = np.array([float(r['alpha_var']) for r in csv.DictReader(fh) if r['axis'] == 'x'])
    low, high = orders[orders < 0.5], orders[orders >= 0.5]
    assert low.size >= 2 and high.size >= 2  # the issue: three chunks at 0.02, three at 1.02
    assert a['alpha_var_multimodal']
    modes = [(m['order'], m['chunks']) for m in a['alpha_var_modes']]
    assert modes == [(pytest.approx(low.mean()), low.size),
                     (pytest.approx(high.mean()), high.size)]
    md = (tmp_path / 'summary.md').read_text()
    assert md.index('## In short') < md.index('paper 000 Table 3')
    assert 'separate modes' in md and 'modes: ' in md
    assert 'deg/sqrt(h)' in md and '(SI, unit in the name)' in md and '68.3 %' in md
    # Table 3 shows the paper's magnitude and the signed slope beside it, never a bare abs().
    slope = a['offset_drift_deg_s_per_h']
    assert f'| {abs(slope):.6f} | {slope:+.6f} |' in md
    # "N standard errors, not significant" states the t needed with this many chunks.
    assert 'with 6 chunks a 3-sigma test needs' in md


def test_console_line_gives_order_modes_not_their_mean(tmp_path, capsys):
    rc = analyze.main([str(real_data(*MPU)), '--out', str(tmp_path), '--jobs', '1',
                       '--no-figures', '--axis', 'x'])
    assert rc == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith('  x:'))
    assert 'order var modes ' in line and '(3 chunks)' in line


def test_progress_lines_when_stderr_is_not_a_terminal(tmp_path, capsys):
    path = real_data(*MPU)
    rc = analyze.main([str(path), '--out', str(tmp_path), '--jobs', '1', '--no-figures',
                       '--no-allan', '--axis', 'z', '--batch-size', '5000'])
    assert rc == 0
    lines = [x for x in capsys.readouterr().err.splitlines() if '% ' in x and 'messages' in x]
    # 65,067 messages in batches of 5,000: one line per 10 % crossed, the last at 100 %.
    assert 9 <= len(lines) <= 11 and lines[-1].split(': ')[1].startswith('100%')


def test_quantisation_offset_is_reduced_modulo_the_step():
    from gyro_noise_ros.explain.signatures import find_lattice

    rng = np.random.default_rng(2)
    step = np.deg2rad(0.05)  # the ADIS16405 LSB
    x = (0.9 + 40 + np.round(rng.normal(0, 5, 20_000))) * step  # offset 0.9 step off the grid
    found_step, offset = find_lattice(x)
    assert found_step == pytest.approx(step, rel=1e-6)
    # Same lattice, reported in [-step/2, step/2): -0.1 step, not 40.9 or 0.9 steps.
    assert offset == pytest.approx(-0.1 * step, abs=1e-6 * step)
