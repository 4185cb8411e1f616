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

"""Thermal bag I/O: a bag into a ThermalRun, the refusals, the compensated copy."""

from _thermal_toy import T0_NS, write_thermal_bag
from gyro_noise_ros.bag import ImuBagReader
from gyro_noise_ros.bag.storage import BagSource
from gyro_noise_ros.errors import BagError, InputDataError
from gyro_noise_ros.thermal.bag_io import join_runs, read_thermal_run, write_compensated
import numpy as np
import pytest

RATE = 50.0


def _data(n=500, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    gyro = rng.normal(0.0, 1e-3, (n, 3))
    temp_t = np.arange(0.0, t[-1] + 1.0, 1.0)
    return t, gyro, temp_t, 20.0 + 0.5 * temp_t


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_reads_and_interpolates_temperature(tmp_path, storage):
    t, gyro, temp_t, temp = _data()
    path, _ = write_thermal_bag(tmp_path / 'b', t, gyro, temp_t, temp, storage=storage)
    run, info = read_thermal_run(path)
    np.testing.assert_allclose(run.t_s, t, atol=1e-9)
    np.testing.assert_array_equal(run.gyro_rad_s, gyro)
    # the temperature is a ramp, so linear interpolation reproduces it exactly
    np.testing.assert_allclose(run.temperature_c, 20.0 + 0.5 * t, atol=1e-9)
    assert run.rate_hz == pytest.approx(RATE) and run.name == 'b'
    assert info.topic == '/imu/data_raw' and info.temperature_topic == '/imu/temperature'
    assert info.temperature_samples == temp_t.size


def test_out_of_order_stamps_are_sorted_and_mapped_back(tmp_path):
    t, gyro, temp_t, temp = _data(100)
    perm = np.arange(100)
    perm[[10, 11]] = perm[[11, 10]]
    path, _ = write_thermal_bag(tmp_path / 'b', t[perm], gyro[perm], temp_t, temp)
    run, info = read_thermal_run(path)
    np.testing.assert_array_equal(run.gyro_rad_s, gyro)
    np.testing.assert_array_equal(info.order, perm.argsort())


def test_refusals(tmp_path):
    t, gyro, temp_t, temp = _data(500)
    path, _ = write_thermal_bag(tmp_path / 'none', t, gyro, temp_t, temp, temperature_topic=None)
    with pytest.raises(BagError, match='no sensor_msgs/msg/Temperature topic'):
        read_thermal_run(path)
    bad = gyro.copy()
    bad[7, 2] = np.nan
    path, _ = write_thermal_bag(tmp_path / 'nan', t, bad, temp_t, temp)
    with pytest.raises(InputDataError, match='1 Imu message.*NaN'):
        read_thermal_run(path)
    bad_t = temp.copy()
    bad_t[1] = np.inf
    path, _ = write_thermal_bag(tmp_path / 'nant', t, gyro, temp_t, bad_t)
    with pytest.raises(InputDataError, match='NaN/Inf temperature'):
        read_thermal_run(path)
    path, _ = write_thermal_bag(tmp_path / 'apart', t, gyro, temp_t + 1000.0, temp)
    with pytest.raises(InputDataError, match='do not overlap'):
        read_thermal_run(path)
    path, _ = write_thermal_bag(tmp_path / 'half', t, gyro, temp_t[:3], temp[:3])
    with pytest.raises(InputDataError, match='does not cover'):
        read_thermal_run(path)
    keep = (temp_t < 0.5) | (temp_t > 2.5)
    path, _ = write_thermal_bag(tmp_path / 'hole', t, gyro, temp_t[keep], temp[keep])
    with pytest.raises(InputDataError, match='no temperature for 3 s'):
        read_thermal_run(path, max_gap_s=2.0)
    t_dup = t.copy()
    t_dup[5] = t_dup[4]
    path, _ = write_thermal_bag(tmp_path / 'dup', t_dup, gyro, temp_t, temp)
    with pytest.raises(InputDataError, match='repeats'):
        read_thermal_run(path)


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_compensated_copy_changes_only_angular_velocity(tmp_path, storage):
    t, gyro, temp_t, temp = _data(300)
    perm = np.arange(300)
    perm[[20, 21]] = perm[[21, 20]]
    path, accel = write_thermal_bag(tmp_path / 'b', t[perm], gyro[perm], temp_t, temp,
                                    storage=storage, extra_topic='/notes')
    run, info = read_thermal_run(path)
    processed = run.gyro_rad_s * 2.0 + 1.0
    counts = write_compensated(info, processed, tmp_path / 'out')
    assert counts == {'/imu/data_raw': 300, '/imu/temperature': temp_t.size, '/notes': 3}
    with ImuBagReader(tmp_path / 'out') as r:
        batch = next(r.iter_batches(10_000))
        stamps, temps = r.read_temperature()
    np.testing.assert_array_equal(batch.gyro, gyro[perm] * 2.0 + 1.0)
    np.testing.assert_array_equal(batch.accel, accel)
    np.testing.assert_array_equal(batch.stamp_ns, T0_NS + np.round(t[perm] * 1e9).astype(int))
    np.testing.assert_array_equal(temps, temp)
    src, out = BagSource(path), BagSource(tmp_path / 'out')
    try:
        a = b''.join(bytes(b[0][s:s + n]) for b in src.blocks('/notes')
                     for s, n in zip(b[1], b[2]))
        b_ = b''.join(bytes(b[0][s:s + n]) for b in out.blocks('/notes')
                      for s, n in zip(b[1], b[2]))
    finally:
        src.close()
        out.close()
    assert a == b_ and b'note 2' in a


def test_join_runs_leaves_a_gap_the_rate_window_never_straddles(tmp_path):
    t, gyro, temp_t, temp = _data(100)
    r1, _ = read_thermal_run(write_thermal_bag(tmp_path / 'a', t, gyro, temp_t, temp)[0])
    r2, _ = read_thermal_run(write_thermal_bag(tmp_path / 'b', t, gyro, temp_t, temp)[0])
    j = join_runs([r1, r2], gap_s=10.0)
    assert j.t_s.size == 200 and j.name == 'a+b'
    assert j.t_s[100] - j.t_s[99] == pytest.approx(10.0)
    assert np.all(np.diff(j.t_s) > 0)


def test_ros1_input_gives_a_ros2_copy(tmp_path, make_record):
    t, gyro, temp_t, temp = _data(120)
    path = make_record(tmp_path / 'r1.bag', gyro, t_s=t, temperature_c=temp,
                       temperature_t_s=temp_t, storage='ros1', t0_ns=T0_NS)
    run, info = read_thermal_run(path)
    assert info.storage == 'ros1'
    np.testing.assert_array_equal(run.gyro_rad_s, gyro)
    counts = write_compensated(info, -run.gyro_rad_s, tmp_path / 'out')
    assert counts == {'/imu/data_raw': 120, '/imu/temperature': temp_t.size}
    with ImuBagReader(tmp_path / 'out') as r:
        assert r.storage == 'sqlite3'
        np.testing.assert_array_equal(next(r.iter_batches()).gyro, -gyro)
        np.testing.assert_array_equal(r.read_temperature()[1], temp)


def _dense(n=3000, seed=0):
    """Return 60 s at 50 Hz, temperature at 10 Hz: 601 readings of a 15 -> 45 degC ramp."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    temp_t = np.arange(0.0, t[-1] + 0.1, 0.1)
    return t, rng.normal(0.0, 1e-3, (n, 3)), temp_t, 15.0 + 0.5 * temp_t


def test_implausible_temperatures_are_dropped_and_counted(tmp_path):
    # the cases: a 0x7FFF word (153 degC) and a 1e6 degC reading in a 15..45 degC run
    t, gyro, temp_t, temp = _dense()
    bad = temp.copy()
    bad[[100, 300]] = (25.0 + 32767.0 / 256.0, 1e6)
    path, _ = write_thermal_bag(tmp_path / 'b', t, gyro, temp_t, bad)
    run, info = read_thermal_run(path)
    assert info.temperature_samples == temp_t.size and info.temperature_dropped == 2
    # interpolated over the dropped readings: the ramp itself
    np.testing.assert_allclose(run.temperature_c, 15.0 + 0.5 * t, atol=1e-9)
    assert run.temperature_c.max() < 45.0
    assert info.temperature_period_s == pytest.approx(0.1) == run.temperature_period_s
    (note,) = info.notes
    assert '2 of 601 temperature readings' in note and 'first at 10.000 s' in note
    assert '1 saturated register words' in note and 'dropped' in note


def test_a_stream_with_many_implausible_readings_is_refused_naming_the_first(tmp_path):
    t, gyro, temp_t, temp = _dense()
    bad = temp.copy()
    bad[250::50] = 100.0    # 8 of 601 readings outside -40..85 degC: over 1 %
    path, _ = write_thermal_bag(tmp_path / 'b', t, gyro, temp_t, bad)
    with pytest.raises(InputDataError, match=r'8 of 601 .*first at 25\.000 s \(100 degC\); '
                                             r'more than 1 %'):
        read_thermal_run(path)


def test_kelvin_is_converted_with_a_note(tmp_path):
    t, gyro, temp_t, temp = _dense()
    path, _ = write_thermal_bag(tmp_path / 'k', t, gyro, temp_t, temp + 273.15)
    run, info = read_thermal_run(path)
    np.testing.assert_allclose(run.temperature_c, 15.0 + 0.5 * t, atol=1e-9)
    (warning,) = info.warnings
    assert 'kelvin' in warning and '288.15..318.15' in warning and not info.notes
