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
The board's port: validation of the name at start, and a stable hardware id (pure, no ROS).

A port is a device path (``/dev/ttyACM0``, ``/dev/serial/by-id/...``) or a pyserial URL
(``socket://127.0.0.1:PORT`` for the emulator). A network URL must name host and port: pyserial
accepts ``socket://127.0.0.1`` without opening it, and the driver would then retry it forever
with a type error as message, so it is refused at start instead.
"""

import os
from urllib.parse import urlsplit

import serial
from serial.tools import list_ports

from ..errors import ParameterError

_NETWORK_SCHEMES = ('socket', 'rfc2217')


def validate_port(port: str) -> str:
    """
    Check that a port name can be opened by pyserial (without opening it).

    Parameters
    ----------
    port : str
        Device path or pyserial URL.

    Returns
    -------
    str
        The port, stripped.

    Raises
    ------
    ParameterError
        Empty, unknown URL scheme, or a network URL without host or port number.

    """
    port = str(port).strip()
    if not port:
        raise ParameterError("parameter 'port' is empty: give a device path or a pyserial URL")
    parts = urlsplit(port)
    if parts.scheme in _NETWORK_SCHEMES:
        try:
            number = parts.port
        except ValueError as err:
            raise ParameterError(f"parameter 'port' = {port!r}: bad port number: {err}") from err
        if not parts.hostname or number is None:
            raise ParameterError(f"parameter 'port' = {port!r} must name host and port, e.g. "
                                 f'{parts.scheme}://127.0.0.1:5760')
    try:
        serial.serial_for_url(port, do_not_open=True)
    except (ValueError, serial.SerialException) as err:
        raise ParameterError(f"parameter 'port' = {port!r} is not usable: {err}") from err
    return port


def usb_serial_number(port: str) -> str | None:
    """
    Return the USB serial number of the device behind a port path, if there is one.

    Parameters
    ----------
    port : str
        Device path (symlinks such as ``/dev/serial/by-id/...`` are resolved) or URL.

    Returns
    -------
    str or None
        The serial number pyserial reports for the device; None for URLs and unknown devices.

    """
    if '://' in port:
        return None
    device = os.path.realpath(port)
    for info in list_ports.comports():
        if os.path.realpath(info.device) == device and info.serial_number:
            return str(info.serial_number)
    return None


def hardware_id_for(port: str, frame_id: str) -> str:
    """
    Return a stable ``hardware_id`` for the diagnostics of the sensor on ``port`` (path or URL).

    The sensor and board identity, never the port path (``/dev/ttyACM0`` changes with the plug
    order): ``lsm6dso32/portenta_h7/<USB serial number>`` when the device reports one, otherwise
    ``lsm6dso32/portenta_h7/<frame_id>`` (the frame names the sensor on the robot).
    """
    return f'lsm6dso32/portenta_h7/{usb_serial_number(port) or frame_id}'
