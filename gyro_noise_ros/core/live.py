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
Pure pieces of the live analyzer (``noise_analyzer``): configuration from parameters, temperature.

The node (:mod:`gyro_noise_ros.nodes.analyzer`) only adapts ROS to these and to
:class:`~gyro_noise_ros.core.engine.NoiseEngine`; everything here runs and is tested without ROS.
"""

from dataclasses import fields

import numpy as np

from .engine import AXES, EngineConfig
from .fractional import make_grid
from .health import HealthThresholds
from ..errors import ParameterError

#: Numeric per-chunk topics of the analyzer: name -> (ChunkResult field, unit).
CHUNK_TOPICS = {
    'bias': ('bias_rad_s', 'rad/s'),
    'variance': ('variance_rad2_s2', '(rad/s)^2'),
    'alpha_var': ('alpha_var', '-'),
    'alpha_corr': ('alpha_corr', '-'),
    'f_var': ('f_var', '-'),
    'f_corr': ('f_corr', '-'),
}


def parse_axes(text):
    """
    Parse the ``axes`` parameter (``'x,y,z'``, ``'z'``, ``'xyz'``) into a tuple of axis names.

    Parameters
    ----------
    text : str
        The parameter value.

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        Unknown, repeated or no axis.

    """
    raw = str(text).replace(' ', '')
    names = raw.split(',') if ',' in raw else list(raw)
    names = [n for n in names if n]
    if not names or any(n not in AXES for n in names) or len(set(names)) != len(names):
        raise ParameterError(f"parameter 'axes' = {text!r} must name distinct axes among x, y, z "
                             "(e.g. 'x,y,z' or 'z')")
    return tuple(names)


def engine_config_from(params):
    """
    Build the :class:`EngineConfig` from the analyzer's parameter values.

    Parameters
    ----------
    params : dict
        Name to value (``chunk_size``, ``axes``, ``order_grid_*``, ``memory``, ``demean``,
        ``max_lag``, ``rate_hz``, ``gap_factor``, ``gap_policy``, ``allan``, ``history_chunks``).

    Returns
    -------
    EngineConfig

    Raises
    ------
    ParameterError
        An inconsistent combination (e.g. chunk_size below memory + 2), naming the parameters.

    """
    alphas = make_grid(params['order_grid_start'], params['order_grid_stop'],
                       params['order_grid_step'])
    try:
        return EngineConfig(
            chunk_size=params['chunk_size'], axes=parse_axes(params['axes']), alphas=alphas,
            memory=params['memory'], demean=params['demean'],
            max_lag=None if params['max_lag'] < 0 else params['max_lag'],
            rate_hz=params['rate_hz'] or None, gap_factor=params['gap_factor'],
            gap_policy=params['gap_policy'], allan=params['allan'],
            history_chunks=params['history_chunks'])
    except ParameterError as err:
        raise ParameterError(f'parameters chunk_size/memory/max_lag/order grid: {err}') from err


def thresholds_from(params):
    """
    Build :class:`HealthThresholds` from the parameter values (same names).

    Parameters
    ----------
    params : dict
        Name to value, a superset of the threshold names.

    Returns
    -------
    HealthThresholds

    """
    return HealthThresholds(**{f.name: params[f.name] for f in fields(HealthThresholds)})


class TemperatureTrack:
    """
    The latest temperature messages of a live stream, interpolated at sample stamps.

    Linear between messages, held constant after the latest (the offline tool, which sees the
    whole bag, interpolates towards the next one there instead).
    """

    def __init__(self):
        self.stamp_ns = None
        self.temperature_c = None

    def add(self, stamp_ns, temperature_c):
        """
        Add a batch of temperature messages (any order).

        Parameters
        ----------
        stamp_ns : numpy.ndarray of int64
            Header stamps (ns).
        temperature_c : numpy.ndarray
            Temperatures (degC).

        """
        stamp_ns = np.asarray(stamp_ns, np.int64)
        temperature_c = np.asarray(temperature_c, np.float64)
        if not stamp_ns.size:
            return
        if self.stamp_ns is not None:
            # Keep the previous latest message so samples between two batches are interpolated.
            stamp_ns = np.concatenate((self.stamp_ns[-1:], stamp_ns))
            temperature_c = np.concatenate((self.temperature_c[-1:], temperature_c))
        order = np.argsort(stamp_ns, kind='stable')
        self.stamp_ns, self.temperature_c = stamp_ns[order], temperature_c[order]

    def at(self, stamp_ns):
        """
        Return the temperature at sample stamps.

        Parameters
        ----------
        stamp_ns : numpy.ndarray of int64
            Sample stamps (ns).

        Returns
        -------
        numpy.ndarray or float or None
            degC per stamp; one float when only one message is known; None before any.

        """
        if self.stamp_ns is None:
            return None
        if self.stamp_ns.size == 1:
            return float(self.temperature_c[0])
        return np.interp(np.asarray(stamp_ns).astype(np.float64),
                         self.stamp_ns.astype(np.float64), self.temperature_c)
