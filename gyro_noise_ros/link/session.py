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
One connection to the board: the CONFIGURE handshake and the silence rule (pure, no ROS).

After every connect the host sends CONFIGURE and waits ``ack_timeout_s`` for the ACK echoing its
``command_id`` (``docs/portenta_link.md`` section 9). Samples decoded before that ACK are dropped:
they may carry the previous configuration's scaling; the sample counter's gap counts them as lost.
"""

from collections.abc import Callable
from dataclasses import dataclass
import threading
import time
from typing import Any

import numpy as np

from .protocol import encode_configure, MAX_SAMPLES_PER_FRAME
from ..errors import LinkError

_READ_SIZE = 1 << 16

#: Largest relative difference between the requested ODR and the one the ACK reports in force that
#: the host accepts: the board's own acceptance window for a request (docs/portenta_link.md).
ODR_TOLERANCE_RATIO = 0.005


@dataclass(frozen=True)
class LinkConfig:
    """
    Configuration the board acknowledged.

    Attributes
    ----------
    odr_hz : float
        Output data rate (Hz).
    gyro_fs_dps : int
        Gyroscope full scale (deg/s).
    accel_fs_g : int
        Accelerometer full scale (g).

    """

    odr_hz: float
    gyro_fs_dps: int
    accel_fs_g: int


def frame_interval_s(config: 'LinkConfig') -> float:
    """Return a link's longest normal silence (s): three full frames (a frame holds <= 128)."""
    return 3.0 * MAX_SAMPLES_PER_FRAME / config.odr_hz


def handshake(ser: Any, decoder: Any, *, command_id: int, odr_hz: float, gyro_fs_dps: int,
              accel_fs_g: int, ack_timeout_s: float, stop: threading.Event | None = None,
              now_ns: Callable[[], int] = time.time_ns
              ) -> tuple['LinkConfig', np.ndarray, int] | None:
    """
    Send CONFIGURE on an open port and wait for its ACK.

    Parameters
    ----------
    ser : serial.Serial
        Open port (``read`` returns within its timeout).
    decoder : protocol.Decoder
        The connection's decoder (its counters keep running).
    command_id : int
        Identifier echoed by the ACK.
    odr_hz : float
        Requested output data rate (Hz).
    gyro_fs_dps, accel_fs_g : int
        Requested full scales (deg/s, g).
    ack_timeout_s : float
        Wait for the ACK (s).
    stop : threading.Event, optional
        Abort (return None) when set.
    now_ns : callable
        Clock read when the bytes carrying the ACK arrived (ns).

    Returns
    -------
    (LinkConfig, numpy.ndarray, int) or None
        The acknowledged configuration, the samples that followed the ACK in the same read and
        the ``now_ns()`` of that read; None if ``stop`` was set.

    Raises
    ------
    LinkError
        No ACK within ``ack_timeout_s``; a NAK (the message names the refused settings); an ACK
        whose configuration in force differs from the request (ODR by more than
        :data:`ODR_TOLERANCE_RATIO`, or another full scale).

    """
    ser.write(encode_configure(command_id=command_id, odr_hz=odr_hz, gyro_fs_dps=gyro_fs_dps,
                               accel_fs_g=accel_fs_g))
    deadline = time.monotonic() + ack_timeout_s
    while True:
        if stop is not None and stop.is_set():
            return None
        if time.monotonic() > deadline:
            raise LinkError(f'no acknowledgement of the configuration within {ack_timeout_s} s')
        data = ser.read(_READ_SIZE)
        if not data:
            continue
        host_ns = now_ns()
        result = decoder.feed(data)
        for ack_index, ack in enumerate(result.acks):
            if ack.command_id != command_id:
                continue
            if not ack.ok:
                raise LinkError(f'the board refused odr {odr_hz} Hz, gyro {gyro_fs_dps} dps, '
                                f'accel {accel_fs_g} g: {ack.message}')
            config = LinkConfig(float(ack.odr_hz), int(ack.gyro_fs_dps), int(ack.accel_fs_g))
            if (abs(config.odr_hz - odr_hz) > ODR_TOLERANCE_RATIO * odr_hz
                    or (config.gyro_fs_dps, config.accel_fs_g) != (gyro_fs_dps, accel_fs_g)):
                raise LinkError(f'the board acknowledged odr {config.odr_hz:g} Hz, gyro '
                                f'{config.gyro_fs_dps} dps, accel {config.accel_fs_g} g for a '
                                f'request of {odr_hz:g} Hz, {gyro_fs_dps} dps, {accel_fs_g} g')
            return config, result.samples[result.ack_positions[ack_index]:], host_ns
