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
The ``imu_compensator``'s diagnostics task (pure, no ROS): ``'<node>: compensation'``.

Tick on the hot path, run on the timer (diagnostic_updater's shape): the node bumps the counters
of :class:`CompensationTask` (``counts``, :meth:`~CompensationTask.tick_data`,
:meth:`~CompensationTask.tick_temperature`) as it takes and publishes messages, and its
:class:`~gyro_noise_ros.thermal.live.TemperatureGate` counts the samples it holds, drops and
releases late; once per diagnostics period :meth:`~CompensationTask.run` measures the output rate
from the difference of the published count, picks the level from the explicit limits of
:class:`CompensationThresholds` and returns the status with its key/values
(``docs/compensation.md``):

- ERROR: no ``imu/data_raw`` yet, or none for ``stale_after_s``; a temperature beyond the
  thermal model's range + margin (the offset is not extrapolated).
- WARN: a temperature outside the trained range but within the margin; Imu messages dropped
  because no temperature came within ``temperature_wait_s``; samples compensated with a held
  offset because no newer temperature came within ``max_temperature_wait_s``, in the period
  since the previous published status (the count stays in the values); no temperature yet; the
  newest temperature older than ``temperature_timeout_s`` (the offset is held).

The message is the sentence of the worst check (the first among equals), else
``'Compensating.'``.
"""

from collections.abc import Iterable
from dataclasses import dataclass, fields
import math

import numpy as np
from numpy.typing import NDArray

from ..calibration.apply import Calibration
from ..core.items import TaskStatus, worst
from ..errors import ParameterError
from ..thermal.live import (LiveDriftEvaluator, RANGE_MARGIN, RANGE_NAMES, RANGE_OUTSIDE,
                            TemperatureGate)
from ..units import RAD_TO_DEG

#: Degrees per radian (the diagnostics show deg/s; SI inside).
#: Milli-g per m/s^2 (standard gravity 9.80665 m/s^2).
_M_S2_TO_MG = 1e3 / 9.80665


@dataclass(frozen=True)
class CompensationThresholds:
    """
    Limits of the compensator's status.

    The node fills the first four from its parameters of the same names, whose table
    (``nodes/compensator.PARAMETERS``, ``config/imu_compensator.yaml``) describes them.

    Attributes
    ----------
    stale_after_s : float
        ERROR after this long without ``imu/data_raw`` (s).
    temperature_timeout_s : float
        WARN when the newest temperature is older than this (s).
    temperature_wait_s : float
        How long Imu messages wait for the first temperature before they are dropped (s); named
        in the WARN that counts them.
    max_temperature_wait_s : float
        How long a sample newer than the latest temperature waits for the next one before it is
        compensated with the latest offset (s); named in the WARN that counts them.
    rate_interval_s : float
        Shortest interval over which the output rate is measured (s).

    """

    stale_after_s: float = 5.0
    temperature_timeout_s: float = 2.0
    temperature_wait_s: float = 2.0
    max_temperature_wait_s: float = 4.0
    rate_interval_s: float = 0.5

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ParameterError(f'{f.name} must be a finite number >= 0, got {value!r}')


def vector_text(values: Iterable[float], scale: float = 1.0) -> str:
    """
    Format a vector for a diagnostic value: ``'x, y, z'`` with 6 significant digits.

    ``values`` are the components (SI), multiplied by ``scale`` first (e.g. degrees per radian).

    """
    return ', '.join(f'{v * scale:.6g}' for v in values)


def outside_share(ev: LiveDriftEvaluator) -> str:
    """
    Return the share (%) of evaluated temperature messages outside the trained range of T or dT.

    Parameters
    ----------
    ev : thermal.live.LiveDriftEvaluator
        The gyro's evaluator.

    Returns
    -------
    str
        ``'n/a'`` before any evaluated message.

    """
    evaluated = sum(ev.knots_by_status.values())
    if not evaluated:
        return 'n/a'
    return f'{100.0 * ev.knots_outside / evaluated:.3g}'


def calibration_items(calibration: Calibration, source: str) -> list[tuple[str, str]]:
    """
    Return the key/values of the calibration in use.

    Parameters
    ----------
    calibration : calibration.apply.Calibration
        Gyro and accelerometer bias and scale factor, gravity.
    source : str
        ``'parameters'`` or ``'file <path>'``.

    Returns
    -------
    list of (str, str)

    """
    cal = calibration
    return [('Calibration source', source),
            ('Gyro bias (deg/s)', vector_text(cal.gyro.bias, RAD_TO_DEG)),
            ('Gyro scale factor (%)', vector_text(cal.gyro.scale_factor, 100.0)),
            ('Accelerometer bias (m/s^2)', vector_text(cal.accel.bias)),
            ('Accelerometer scale factor (%)', vector_text(cal.accel.scale_factor, 100.0)),
            ('Calibration gravity (m/s^2)', f'{cal.gravity_m_s2:.6g}')]


class CompensationTask:
    """
    The compensator's diagnostics: counters ticked on the hot path, judged on the timer.

    Parameters
    ----------
    thresholds : CompensationThresholds
        The limits.
    calibration : calibration.apply.Calibration, keyword-only
        The calibration in use (reported).
    calibration_source : str, keyword-only
        Where it came from (reported).
    out_of_range_action : str, keyword-only
        What the model does beyond its range + margin (named in the ERROR).
    now : float, keyword-only
        Monotonic time of the start (s): the output rate's first interval starts there.
    temperature_sync : str, keyword-only
        How samples get their thermal offset (reported): ``'latest'`` or ``'interpolate'``.

    Attributes
    ----------
    counts : dict of str to int
        ``received``, ``published``, ``undecodable`` and ``temperatures`` messages; the node adds
        to them.

    """

    def __init__(self, thresholds: CompensationThresholds, *, calibration: Calibration,
                 calibration_source: str, out_of_range_action: str, now: float,
                 temperature_sync: str = 'latest') -> None:
        self.thresholds = thresholds
        self.temperature_sync = temperature_sync
        self.calibration = calibration
        self.calibration_source = calibration_source
        self.out_of_range_action = out_of_range_action
        self.counts = dict.fromkeys(('received', 'published', 'undecodable', 'temperatures'), 0)
        self.last_data_s: float | None = None
        self.last_temperature_s: float | None = None
        self._late_reported = 0  # the hold's late count up to the previous published status
        # Largest stamp of a compensated sample minus the stamp of the offset it got (ns), since
        # the previous published status: the age of a held offset.
        self._offset_age_ns = 0
        self._rate = (now, 0, math.nan)  # time, published count, Hz

    def tick_data(self, now: float) -> None:
        """Note that Imu messages arrived at monotonic time ``now`` (s)."""
        self.last_data_s = now

    def tick_temperature(self, now: float) -> None:
        """Note that the thermal evaluator took a temperature at monotonic time ``now`` (s)."""
        self.last_temperature_s = now

    def tick_offset_age(self, age_ns: int) -> None:
        """Note a compensated sample ``age_ns`` newer than the temperature of its offset (ns)."""
        if age_ns > self._offset_age_ns:
            self._offset_age_ns = age_ns

    def output_rate_hz(self, now: float) -> float:
        """
        Return the output rate, re-measured when ``rate_interval_s`` has passed since the last.

        Parameters
        ----------
        now : float
            Monotonic time (s).

        Returns
        -------
        float
            Published messages per second over the last measured interval (NaN before one).

        """
        t0, n0, _ = self._rate
        if now - t0 >= self.thresholds.rate_interval_s:
            n1 = self.counts['published']
            self._rate = (now, n1, (n1 - n0) / (now - t0))
        return self._rate[2]

    def run(self, now: float, *, thermal: LiveDriftEvaluator | None = None,
            thermal_accel: LiveDriftEvaluator | None = None,
            offset: NDArray[np.float64] | None = None,
            accel_offset: NDArray[np.float64] | None = None,
            hold: TemperatureGate | None = None,
            transport_missing: int = 0, record: bool = False) -> TaskStatus:
        """
        Judge the period ending at ``now`` and return the status (module doc lists the checks).

        Parameters
        ----------
        now : float
            Monotonic time (s).
        thermal, thermal_accel : thermal.live.LiveDriftEvaluator or None, keyword-only
            The gyro's and the accelerometer's thermal evaluators (None: no such model).
        offset, accel_offset : numpy.ndarray or None, keyword-only
            Offsets subtracted from the latest sample (rad/s, m/s^2); None before one.
        hold : thermal.live.TemperatureGate or None, keyword-only
            The samples' hold for a temperature at or after their stamp: its ``dropped``,
            ``waiting``, ``longest_wait_s`` and ``late`` are reported (None: all zero).
        transport_missing : int, keyword-only
            Messages lost before the node (DDS sequence gaps).
        record : bool, keyword-only
            This status is published (the node's timer): the late samples it reports are not
            reported again in the next one.

        Returns
        -------
        TaskStatus

        """
        rate_hz = self.output_rate_hz(now)
        checks: list[tuple[str, str]] = []
        since = None if self.last_data_s is None else now - self.last_data_s
        if since is None or since > self.thresholds.stale_after_s:
            checks.append(('ERROR', 'No imu/data_raw ' + ('yet.' if since is None else
                                                          f'for {since:.1f} s.')))
        values = calibration_items(self.calibration, self.calibration_source)
        if thermal is None:
            values.append(('Thermal model', 'none'))
        else:
            age = (None if self.last_temperature_s is None
                   else now - self.last_temperature_s)
            values += self._thermal_items(thermal, thermal_accel, offset, accel_offset, age,
                                          hold)
            checks += self._thermal_checks(thermal, age, hold, record)
            if record:
                self._offset_age_ns = 0
        c = self.counts
        values += [('Messages received', str(c['received'])),
                   ('Messages published', str(c['published'])),
                   ('Output rate (Hz)', f'{rate_hz:.1f}'),
                   ('Messages undecodable', str(c['undecodable'])),
                   ('Messages dropped before the node', str(transport_missing))]
        level, message = worst(checks, 'Compensating.')
        return TaskStatus(level, message, tuple(values))

    def _thermal_items(self, ev: LiveDriftEvaluator, accel_ev: LiveDriftEvaluator | None,
                       offset: NDArray[np.float64] | None,
                       accel_offset: NDArray[np.float64] | None,
                       age: float | None,
                       hold: TemperatureGate | None) -> list[tuple[str, str]]:
        """Return the key/values of the thermal model, its inputs and its counts."""
        return [
            ('Thermal model', ev.name),
            ('Temperature sync', self.temperature_sync),
            ('Newest sample past its offset (ms)', f'{self._offset_age_ns / 1e6:.1f}'),
            ('Thermal model range (degC)', f'{ev.range_lo_c:.4g} to {ev.range_hi_c:.4g}, '
             f'margin {ev.margin_c:.3g}'),
            ('Temperature (degC)', f'{ev.temperature_c:.4g}'),
            ('Temperature rate (degC/s)', f'{ev.rate_c_s:.4g}'),
            ('Temperature age (s)', 'n/a' if age is None else f'{age:.2f}'),
            ('Temperature range status', 'n/a' if ev.status is None else RANGE_NAMES[ev.status]),
            ('Thermal offset (deg/s)', 'n/a' if offset is None else
             vector_text(offset, RAD_TO_DEG)),
            ('Temperature messages', str(self.counts['temperatures'])),
            ('Temperature messages rejected', str(ev.rejected)),
            ('Temperature messages beyond range + margin', str(ev.knots_by_status[RANGE_OUTSIDE])),
            ('Thermal model rate range (degC/s)', 'unknown' if ev.rate_range_c_s is None
             else f'{ev.rate_range_c_s[0]:.4g} to {ev.rate_range_c_s[1]:.4g}'),
            ('Temperature messages outside the trained rate range', str(ev.knots_rate_outside)),
            ('Share outside the trained range of T or dT (%)', outside_share(ev)),
            ('Temperature messages waiting for the rate window', str(ev.pending)),
            ('Accelerometer thermal offset (mg)',
             'none' if accel_ev is None else 'n/a' if accel_offset is None
             else vector_text(accel_offset, _M_S2_TO_MG)),
            ('Messages dropped waiting for the first temperature',
             str(0 if hold is None else hold.dropped)),
            ('Messages waiting for a temperature', str(0 if hold is None else hold.waiting)),
            ('Longest wait for a temperature (s)',
             f'{0.0 if hold is None else hold.longest_wait_s:.3f}'),
            ('Messages compensated with a held offset', str(0 if hold is None else hold.late)),
        ]

    def _thermal_checks(self, ev: LiveDriftEvaluator, age: float | None,
                        hold: TemperatureGate | None, record: bool) -> list[tuple[str, str]]:
        """Return the failed checks of the thermal model's range, its input and the hold."""
        th = self.thresholds
        checks: list[tuple[str, str]] = []
        if ev.status == RANGE_OUTSIDE:
            checks.append(('ERROR', f'Temperature {ev.temperature_c:.1f} degC is beyond the '
                           'model range + margin: offset not extrapolated '
                           f'({self.out_of_range_action}).'))
        elif ev.status == RANGE_MARGIN:
            checks.append(('WARN', f'Temperature {ev.temperature_c:.1f} degC is outside the '
                           'trained range (within the margin).'))
        dropped, late = (0, 0) if hold is None else (hold.dropped, hold.late)
        if dropped:
            checks.append(('WARN', f'{dropped} messages dropped: no temperature '
                           f'within {th.temperature_wait_s:g} s of them.'))
        if late > self._late_reported:
            # WARN for the period in which it happened (the count stays in the values).
            checks.append(('WARN', f'{late - self._late_reported} messages compensated with a '
                           'held offset: no newer temperature within '
                           f'{th.max_temperature_wait_s:g} s.'))
            if record:
                self._late_reported = late
        if age is None:
            checks.append(('WARN', 'No imu/temperature yet: Imu messages held, then dropped.'))
        elif age > th.temperature_timeout_s:
            checks.append(('WARN', f'Temperature is {age:.1f} s old: offset held.'))
        return checks
