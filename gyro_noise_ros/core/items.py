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
Diagnostic items of one gyro axis: readable keys with units, formatted values (pure, no ROS).

One place for the number formatting and the unit conversion at the edge (rad -> deg) that the
analyzer node, the health verdicts and the reports show, so a key and its value read the same
everywhere. Each builder returns a list of ``(key, value)`` string pairs, keys with the unit in
parentheses as diagnostic_msgs conventions want (``'Bias (deg/s)'``); missing numbers read
``'nan'`` or ``'n/a'`` so dashboards keep a stable set of keys.
"""

import math

import numpy as np

#: Degrees per radian: SI inside, degrees only at the edges (keys say which).
DEG = 180.0 / math.pi


def fmt(value, digits=4):
    """
    Format a number with ``digits`` significant digits; ``'nan'`` for None, NaN or infinity.

    Parameters
    ----------
    value : float or int or None
        The number.
    digits : int
        Significant digits.

    Returns
    -------
    str

    """
    if value is None or not math.isfinite(value):
        return 'nan'
    return f'{value:.{digits}g}'


def last_chunk_items(result):
    """
    Return the items of the latest chunk of one axis.

    Parameters
    ----------
    result : engine.ChunkResult
        The chunk's numbers (SI).

    Returns
    -------
    list of (str, str)
        ``Last chunk``, bias and variance in deg/s, both orders and f values, samples lost in
        the chunk and the chunk's mean temperature.

    """
    return [
        ('Last chunk', f'{result.chunk} ({result.status})'),
        ('Bias (deg/s)', fmt(result.bias_rad_s * DEG)),
        ('Variance ((deg/s)^2)', fmt(result.variance_rad2_s2 * DEG ** 2)),
        ('Last chunk fractional order, variance method', fmt(result.alpha_var, 3)),
        ('Last chunk fractional order, correlation method', fmt(result.alpha_corr, 3)),
        ('Last chunk f, variance method', fmt(result.f_var)),
        ('Last chunk f, correlation method', fmt(result.f_corr)),
        ('Last chunk samples lost', str(result.samples_lost)),
        ('Temperature (degC)', fmt(result.temperature_c, 4)),
    ]


#: Keys of :func:`allan_items`, in order.
ALLAN_KEYS = ('ADEV at 1 s (deg/s)', 'ADEV minimum (deg/s)', 'ADEV minimum at tau (s)',
              'Angle random walk (deg/sqrt(h))', 'Bias instability (deg/h)')


def allan_items(summary):
    """
    Return an axis' Allan deviation items: ADEV at 1 s, its minimum, fitted noise terms.

    Parameters
    ----------
    summary : engine.AxisSummary or None
        With ``allan`` (and possibly ``noise_terms``) filled in; None or no Allan result gives
        ``'n/a'`` values (the keys stay, so dashboards see a stable set).

    Returns
    -------
    list of (str, str)
        The :data:`ALLAN_KEYS` with their values.

    """
    out = dict.fromkeys(ALLAN_KEYS, 'n/a')
    result = None if summary is None else summary.allan
    if result is not None:
        tau = np.asarray(result.tau_s, dtype=np.float64)
        adev = np.asarray(result.adev, dtype=np.float64)
        good = np.isfinite(adev) & (adev > 0)
        tau, adev = tau[good], adev[good]
        # Octave taus rarely hit 1 s exactly: interpolate in log-log (ADEV is a power law between
        # neighbouring octaves); no extrapolation, so 'n/a' until the run is 4 s long (tau <= N/4).
        if tau.size > 1 and tau[0] <= 1.0 <= tau[-1]:
            adev_1s = float(np.exp(np.interp(0.0, np.log(tau), np.log(adev))))
            out['ADEV at 1 s (deg/s)'] = fmt(adev_1s * DEG)
        if tau.size:
            i = int(np.argmin(adev))
            out['ADEV minimum (deg/s)'] = fmt(adev[i] * DEG)
            out['ADEV minimum at tau (s)'] = fmt(tau[i])
    terms = None if summary is None else summary.noise_terms
    if terms is not None:
        try:
            customary = terms.customary()
            arw = customary.angle_random_walk_deg_per_sqrt_h
            out['Angle random walk (deg/sqrt(h))'] = fmt(arw)
            out['Bias instability (deg/h)'] = fmt(customary.bias_instability_deg_per_h)
        except (AttributeError, TypeError, ValueError):
            pass
    return list(out.items())


def stream_items(counts, *, chunk_size, mean_temperature_c):
    """
    Return the stream counters of one axis.

    Parameters
    ----------
    counts : engine.StreamCounts
        Samples, rate and gaps of the stream.
    chunk_size : int
        Samples per chunk.
    mean_temperature_c : float
        Mean temperature of the run (degC; NaN if unknown).

    Returns
    -------
    list of (str, str)

    """
    return [
        ('Samples received', str(counts.samples)),
        ('Sample rate (Hz)', fmt(counts.rate_hz, 6)),
        ('Gaps', str(counts.gaps)),
        ('Chunk size (samples)', str(chunk_size)),
        ('Mean temperature (degC)', fmt(mean_temperature_c, 4)),
    ]
