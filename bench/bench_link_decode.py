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
Decoder throughput as a multiple of the LSM6DSO32 link rate (6667 samples/s; target >= 50x).

The stream is fed in 4096-byte pieces, like serial reads. Side by side, in the same process, a
naive baseline decoder (walks frames with struct, checks the CRC, unpacks every sample with struct:
the obvious first implementation) shows what the vectorised decoder buys. Also the clean stream
with 1 % of the frames corrupted, and the device-clock estimator per batch.

Run: .venv/bin/python bench/bench_link_decode.py [--seconds 60]
"""

import argparse
import struct
import sys
import time
import zlib

from gyro_noise_ros.link.clock import DeviceClock
from gyro_noise_ros.link.protocol import Decoder, encode_samples, SAMPLE_DTYPE
import numpy as np

LINK_RATE = 6667.0
_SAMPLE = struct.Struct('<II3h3hhBB')


def naive_decode(data):
    """
    Baseline.

    Frame walk with struct, CRC, per-sample struct.unpack (no resync needed: clean data).
    """
    out = []
    pos = 0
    n = len(data)
    while pos + 10 <= n:
        length = struct.unpack_from('<H', data, pos + 4)[0]
        end = pos + 6 + length
        if zlib.crc32(data[pos:end]) == struct.unpack_from('<I', data, end)[0]:
            for off in range(pos + 6, end, 24):
                out.append(_SAMPLE.unpack_from(data, off))
        pos = end + 4
    return len(out)


def make_stream(n, batch, rng):
    s = np.zeros(n, SAMPLE_DTYPE)
    s['seq'] = np.arange(n)
    s['t_us'] = (np.arange(n) * 1e6 / LINK_RATE).astype(np.uint32)
    s['gyro'] = rng.integers(-200, 200, (n, 3))
    s['accel'] = rng.integers(-9000, 9000, (n, 3))
    s['temp'] = 512
    return b''.join(encode_samples(s[i:i + batch]) for i in range(0, n, batch))


def timed(fn, repeat=3):
    best = float('inf')
    result = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def run_decoder(stream, piece=4096):
    dec = Decoder()
    count = 0
    for i in range(0, len(stream), piece):
        count += dec.feed(stream[i:i + piece]).samples.size
    count += dec.flush().samples.size
    return count


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--seconds', type=float, default=60.0, help='link time per stream (s)')
    args = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    n = int(args.seconds * LINK_RATE)
    print(f'command: {" ".join([sys.executable] + sys.argv)}')
    print(f'{n} samples = {args.seconds:g} s of link time at {LINK_RATE:g} Hz, fed in 4096-byte '
          'pieces')
    print(f'{"case":42s} {"decoder":>12s} {"x link":>8s} {"naive":>12s} {"x link":>8s} '
          f'{"speed-up":>8s}')
    for batch in (1, 16, 128):
        stream = make_stream(n, batch, rng)
        t_dec, got = timed(lambda: run_decoder(stream))
        assert got == n
        t_naive, got_naive = timed(lambda: naive_decode(stream), repeat=1)
        assert got_naive == n
        print(f'{f"clean, {batch} samples/frame":42s} {n / t_dec:10.0f}/s '
              f'{n / t_dec / LINK_RATE:7.1f}x '
              f'{n / t_naive:10.0f}/s {n / t_naive / LINK_RATE:7.1f}x {t_naive / t_dec:7.1f}x')
    stream = bytearray(make_stream(n, 16, rng))
    frame_len = 10 + 16 * 24
    for k in range(0, len(stream) // frame_len, 100):
        stream[k * frame_len + 40] ^= 0xFF
    stream = bytes(stream)
    t_dec, got = timed(lambda: run_decoder(stream))
    print(f'{"1 % of frames corrupted, 16 samples/frame":42s} {n / t_dec:10.0f}/s '
          f'{n / t_dec / LINK_RATE:7.1f}x')
    clock = DeviceClock(nominal_rate_hz=LINK_RATE)
    batches = n // 16
    t_us = (np.arange(16) * 150).astype(np.uint32)
    t0 = time.perf_counter()
    for b in range(batches):
        clock.update(t_us + np.uint32(b * 2400), 10 ** 18 + b * 2_400_000 + 500_000)
    t_clock = time.perf_counter() - t0
    print(f'{"DeviceClock.update, 16-sample batches":42s} {batches / t_clock:10.0f} batches/s '
          f'({t_clock / batches * 1e6:.1f} us each; the link needs {LINK_RATE / 16:.0f}/s)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
