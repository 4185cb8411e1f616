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
gyro_noise_analyze's speed-ups (worker processes, warmed kernels, fast criteria) change no output.

* --jobs 1 and --jobs 2 write the same files (the workers inherit the warmed identifier; more
  chunks in flight);
* a static bag is read once (the static-segment statistics are gathered during the analysis)
  and gives the chunks of --static off; a bag with motion is read again, and whether the
  single-read attempt is abandoned at once, early or only at the end, the files are the same.
"""

import json

from gyro_noise_ros.app import analyze as analyze_app
from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
from gyro_noise_ros.cli import analyze
from gyro_noise_ros.core.simulate import FractionalNoise
import numpy as np
import pytest

RATE_HZ = 1000.0
ARGS = ['--chunk-size', '2000', '--memory', '100', '--order-grid', '0:2:0.1', '--quiet',
        '--no-figures', '--curves', '3']


def write_bag(path, n, motion_s=0.0, seed=0):
    rng = np.random.default_rng(seed)
    gyro = np.stack([FractionalNoise(1.3, -0.5, 1e-3, rng=rng, memory=100).generate(n)
                     for _ in range(3)], axis=1)
    t = np.arange(n) / RATE_HZ
    moving = t < motion_s
    gyro[moving, 2] += 0.8 * np.sin(2 * np.pi * 0.7 * t[moving])  # hand turning the sensor
    stamps = 1_700_000_000 * 10**9 + np.round(t * 1e9).astype(np.int64)
    with ImuBagWriter(path) as writer:
        writer.write_imu(stamps, gyro, np.tile([0.0, 0.0, 9.8], (n, 1)))
    return path


def outputs(out):
    doc = json.loads((out / 'summary.json').read_text())
    for key in ('created_utc', 'command'):
        doc.pop(key)
    doc['options'].pop('jobs')
    with np.load(out / 'curves.npz') as z:
        curves = {k: z[k] for k in z.files}
    return (out / 'chunks.csv').read_bytes() + (out / 'summary.md').read_bytes(), doc, curves


def assert_same(a, b):
    assert a[0] == b[0]
    assert a[1] == b[1]
    assert sorted(a[2]) == sorted(b[2])
    for k in a[2]:
        np.testing.assert_array_equal(a[2][k], b[2][k])


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp('speed')
    return (write_bag(d / 'static', 24_000, seed=1),
            write_bag(d / 'motion', 24_000, motion_s=6.0, seed=2))


@pytest.fixture
def reads(monkeypatch):
    """Count full reads of a bag (iter_batches calls)."""
    count = []
    real = ImuBagReader.iter_batches

    def spy(self, *a, **k):
        count.append(str(self.path))
        return real(self, *a, **k)

    monkeypatch.setattr(ImuBagReader, 'iter_batches', spy)
    return count


def run(bag, out, *extra):
    assert analyze.main([str(bag), '--out', str(out), *ARGS, *extra]) == 0
    return outputs(out)


@pytest.mark.parametrize('which', [0, 1])
def test_one_and_two_jobs_write_the_same_files(bags, tmp_path, which):
    assert_same(run(bags[which], tmp_path / 'a', '--jobs', '1'),
                run(bags[which], tmp_path / 'b', '--jobs', '2'))


def test_a_static_bag_is_read_once_and_analysed_as_with_static_off(bags, tmp_path, reads):
    auto = run(bags[0], tmp_path / 'a', '--jobs', '1')
    assert len(reads) == 1
    off = run(bags[0], tmp_path / 'b', '--jobs', '1', '--static', 'off')
    assert auto[0] == off[0]
    assert auto[1]['bags'][0]['left_out'] == off[1]['bags'][0]['left_out']


@pytest.fixture(scope='module')
def motion_reference(bags, tmp_path_factory):
    ref = run(bags[1], tmp_path_factory.mktemp('ref') / 'out', '--jobs', '2')
    assert ref[1]['bags'][0]['left_out']['motion'] > 0  # the motion was found and cut
    return ref


@pytest.mark.parametrize('moving', [True, False])
def test_a_bag_with_motion_gives_the_same_files_however_the_attempt_ends(
        bags, motion_reference, tmp_path, monkeypatch, reads, moving):
    # True: the single read is abandoned at the first batch; False: only after the whole bag
    monkeypatch.setattr(analyze_app._MotionWatch, 'moving', lambda self: moving)
    got = run(bags[1], tmp_path / 'got', '--jobs', '2')
    assert len(reads) == 3  # the attempt, the prepass and the analysis of the segment
    assert_same(motion_reference, got)
