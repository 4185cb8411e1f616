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

from collections.abc import Iterable
from dataclasses import dataclass
import math
from typing import TYPE_CHECKING

from ..units import RAD_TO_DEG

if TYPE_CHECKING:  # for the hints only: the driver and compensator import this module lightly
    from .results import AxisSummary, ChunkResult
    from .stamps import StreamCounts

#: Levels in increasing severity, with diagnostic_msgs/DiagnosticStatus byte values.
LEVELS = ('OK', 'WARN', 'ERROR', 'STALE')
LEVEL_BYTE = {'OK': 0, 'WARN': 1, 'ERROR': 2, 'STALE': 3}


@dataclass(frozen=True)
class TaskStatus:
    """
    What one diagnostic task reports per period: the shape every node's status is built from.

    Each node keeps cumulative counters it bumps cheaply on the hot path; on the diagnostics
    timer a pure function or task object (``link.health.LinkTask``, ``core.health.axis_status``,
    ``diagnostics.compensation.CompensationTask``) takes their differences, picks the level
    from explicit limits held in a thresholds dataclass and returns this; the node only wraps it
    in a ``diagnostic_msgs/DiagnosticStatus`` (ros/diagnostics' diagnostic_updater tasks).

    Attributes
    ----------
    level : str
        One of :data:`LEVELS`.
    message : str
        One sentence naming the worst item.
    values : tuple of (str, str)
        Readable keys with the unit in parentheses and their formatted values, in a stable order.

    """

    level: str
    message: str
    values: tuple

    @property
    def level_byte(self) -> int:
        """int: The level as a DiagnosticStatus byte value (0 OK ... 3 STALE)."""
        return LEVEL_BYTE[self.level]


def worst(checks: Iterable[tuple[str, str]], ok_message: str) -> tuple[str, str]:
    """
    Pick the level and message of the worst failed check (the first one among equals).

    Parameters
    ----------
    checks : iterable of (str, str)
        Level (one of :data:`LEVELS`) and one-sentence message of each check that did not pass.
    ok_message : str
        Message when no check is worse than OK.

    Returns
    -------
    (str, str)
        Level and message.

    """
    level, message = 'OK', ok_message
    for check_level, check_message in checks:
        if LEVELS.index(check_level) > LEVELS.index(level):
            level, message = check_level, check_message
    return level, message


def fmt(value: float | int | None, digits: int = 4) -> str:
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


def last_chunk_items(result: 'ChunkResult') -> list[tuple[str, str]]:
    """
    Return the items of the latest chunk of one axis, from its numbers in SI (``result``).

    ``Last chunk``, bias and variance in deg/s, both orders and f values, samples lost in the chunk
    and the chunk's mean temperature (degC), as (readable key, value) pairs.

    """
    return [
        ('Last chunk', f'{result.chunk} ({result.status})'),
        ('Bias (deg/s)', fmt(result.bias_rad_s * RAD_TO_DEG)),
        ('Variance ((deg/s)^2)', fmt(result.variance_rad2_s2 * RAD_TO_DEG ** 2)),
        ('Last chunk fractional order, variance method', fmt(result.alpha_var, 3)),
        ('Last chunk fractional order, correlation method', fmt(result.alpha_corr, 3)),
        ('Last chunk f, variance method', fmt(result.f_var)),
        ('Last chunk f, correlation method', fmt(result.f_corr)),
        ('Last chunk samples lost', str(result.samples_lost)),
        ('Temperature (degC)', fmt(result.temperature_c, 4)),
    ]


#: Keys of :func:`allan_items`, in order.
ALLAN_KEYS = ('ADEV at 1 s (deg/s)', 'Bias stability (deg/s)', 'Bias stability tau (s)',
              'Angle random walk (deg/sqrt(h))', 'Bias instability (deg/h)')


def allan_items(summary: 'AxisSummary | None') -> list[tuple[str, str]]:
    """
    Return an axis' Allan deviation items, all read by :func:`.readout.read_allan`.

    Parameters
    ----------
    summary : results.AxisSummary or None
        With ``readout`` filled in; None or no readout gives ``'n/a'`` values (the keys stay,
        so dashboards see a stable set).

    Returns
    -------
    list of (str, str)
        The :data:`ALLAN_KEYS` with their values: ADEV at 1 s (``n/a`` until the run is 4 s long:
        taus stop at a quarter of the record, no extrapolation), the bias stability (``<=``
        before it when the curve has not turned up yet: an upper bound) and its tau, the angle
        random walk N and the bias instability B = bias stability / 0.664.

    """
    out = dict.fromkeys(ALLAN_KEYS, 'n/a')
    r = None if summary is None else getattr(summary, 'readout', None)
    if r is not None:
        out['ADEV at 1 s (deg/s)'] = fmt(r.adev_1s_rad_s * RAD_TO_DEG)
        bound = '<=' if r.bias_stability_upper_bound else ''
        out['Bias stability (deg/s)'] = bound + fmt(r.bias_stability_rad_s * RAD_TO_DEG)
        out['Bias stability tau (s)'] = fmt(r.bias_stability_tau_s)
        # rad/sqrt(s) -> deg/sqrt(h): sqrt(3600 s) = 60 sqrt(s) per sqrt(h)
        out['Angle random walk (deg/sqrt(h))'] = fmt(r.arw_rad_per_sqrt_s * RAD_TO_DEG * 60.0)
        out['Bias instability (deg/h)'] = bound + fmt(
            r.bias_instability_rad_s * RAD_TO_DEG * 3600.0)
    return list(out.items())


def stream_items(counts: 'StreamCounts', *, chunk_size: int,
                 mean_temperature_c: float) -> list[tuple[str, str]]:
    """
    Return the stream counters of one axis as (readable key, value) items.

    ``counts`` holds the samples, rate (Hz) and gaps of the stream; ``chunk_size`` is in samples,
    ``mean_temperature_c`` the run's mean temperature (degC; NaN if unknown).

    """
    return [
        ('Samples received', str(counts.samples)),
        ('Sample rate (Hz)', fmt(counts.rate_hz, 6)),
        ('Gaps', str(counts.gaps)),
        ('Chunk size (samples)', str(chunk_size)),
        ('Mean temperature (degC)', fmt(mean_temperature_c, 4)),
    ]
