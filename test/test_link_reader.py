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

"""The reader's port reads and counter snapshots (no ROS)."""

import dataclasses
import socket

from gyro_noise_ros.link import protocol as P
from gyro_noise_ros.link import reader
import numpy as np
import pytest
import serial


@pytest.fixture
def tcp_port():
    """Yield a socket:// port and the server side of its connection, which the test writes to."""
    server = socket.socket()
    server.bind(('127.0.0.1', 0))
    server.listen(1)
    ser = serial.serial_for_url(f'socket://127.0.0.1:{server.getsockname()[1]}', timeout=0)
    peer, _ = server.accept()
    try:
        yield ser, peer
    finally:
        ser.close()
        peer.close()
        server.close()


def test_a_socket_port_is_read_through_its_descriptor(tcp_port, monkeypatch):
    ser, peer = tcp_port
    fd = reader._selectable(ser)
    assert fd is not None and type(ser) in reader._UNBUFFERED
    monkeypatch.setattr(ser, 'read', lambda size: pytest.fail('pyserial read used'))
    assert reader.read_available(ser, fd, 0.01) == b''  # nothing yet: the wait ends
    frames = P.encode_samples(np.zeros(40, P.SAMPLE_DTYPE))
    peer.sendall(frames)
    got = b''
    while len(got) < len(frames):
        got += reader.read_available(ser, fd, 1.0)
    assert got == frames
    peer.close()  # the board side hangs up: readable, no data
    with pytest.raises(serial.SerialException, match='returned none'):
        reader.read_available(ser, fd, 1.0)


def test_a_port_with_a_buffer_of_its_own_is_read_through_pyserial():
    ser = serial.serial_for_url('loop://', timeout=0.01)
    try:
        assert type(ser) not in reader._UNBUFFERED
        ser.write(b'\xa5\x5a abc')
        assert reader.read_available(ser, reader._selectable(ser), 0.01) == b'\xa5\x5a abc'
    finally:
        ser.close()


def test_the_counter_snapshot_is_the_stats():
    dec = P.Decoder()
    samples = np.zeros(20, P.SAMPLE_DTYPE)
    samples['seq'] = np.r_[0:10, 12:22]  # a gap of two
    dec.feed(b'garbage' + P.encode_samples(samples) + b'\xa5\x5a\x01')
    counters = dec.counters()
    assert counters == dataclasses.asdict(dec.stats)
    assert counters['samples_ok'] == 20 and counters['samples_lost'] == 2
    counters['samples_ok'] = -1  # a copy: the decoder's own counters are not touched
    assert dec.stats.samples_ok == 20
