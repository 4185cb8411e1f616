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
Allan analysis of a long static record, every accelerometer and gyro axis (paper 001 step 1/3).

:class:`StaticRecord` takes ``(t, accel, gyro)`` batches and keeps, per channel, a streaming
overlapping Allan accumulator on the dense tau grid (:class:`gyro_noise_ros.core.allan.
AllanAccumulator`), and the 1 s window statistics of the static-dwell detector. Its
:meth:`StaticRecord.finish` gives, per channel, the Allan deviation, the paper's bias-instability
interval and the fitted noise terms, or the reason why not:

* a channel holding NaN/Inf samples stops at the first one: undetermined (the Allan variance of a
  record with holes would be made up);
* an all-zero (or constant) channel: undetermined;
* a record that is not static (fewer than ``STATIC_FRACTION_MIN`` of its windows pass the
  detector, or its static windows do not all share one orientation): every channel undetermined;
* too few samples for five taus: undetermined ("record too short").
"""

from dataclasses import dataclass, replace

import numpy as np

from .interval import bias_instability_interval, DEFAULT_C, DEFAULT_MIN_EDF, undetermined
from .static import classify, DetectorSettings, find_dwells, WindowAccumulator
from ..core.allan import AllanAccumulator, fit_noise_terms
from ..errors import GyroNoiseError

CHANNELS = ('accel_x', 'accel_y', 'accel_z', 'gyro_x', 'gyro_y', 'gyro_z')
#: Fraction of the 1 s windows that must be static for a "static" record.
STATIC_FRACTION_MIN = 0.9
#: Terms fitted beside the interval: white noise, flicker floor, random walk (IEEE 952).
TERMS = ('angle_random_walk', 'bias_instability', 'rate_random_walk')


def unit_of(channel):
    """
    Return the unit suffix of a channel (``m_s2`` for accel, ``rad_s`` for gyro).

    Parameters
    ----------
    channel : str
        One of :data:`CHANNELS`.

    Returns
    -------
    str

    """
    return 'm_s2' if channel.startswith('accel') else 'rad_s'


@dataclass(frozen=True)
class ChannelResult:
    """
    Allan analysis of one channel of a static record.

    Attributes
    ----------
    channel : str
        One of :data:`CHANNELS`.
    allan : AllanResult or None
        Allan deviation (None when undetermined before any tau).
    interval : Interval
        Bias-instability interval (paper 001 section 6).
    terms : dict or None
        ``{'noise_density': (value, lo, hi), 'bias_instability': ..., 'random_walk': ...}`` in the
        channel's unit (per sqrt(Hz), flat, per sqrt(s)); lo/hi from refitting the confidence
        bounds of the Allan deviation (an approximate bracket).

    """

    channel: str
    allan: object
    interval: object
    terms: object = None


def _fit(allan):
    try:
        fits = [fit_noise_terms(a, terms=TERMS) for a in (
            allan, replace(allan, avar=np.asarray(allan.ci_low) ** 2),
            replace(allan, avar=np.asarray(allan.ci_high) ** 2))]
    except GyroNoiseError:
        return None
    names = (('noise_density', 'angle_random_walk_rad_per_sqrt_s'),
             ('bias_instability', 'bias_instability_rad_per_s'),
             ('random_walk', 'rate_random_walk_rad_per_s_sqrt_s'))
    out = {}
    for key, attr in names:
        vals = [float(getattr(f, attr)) for f in fits]
        out[key] = (vals[0], min(vals[1], vals[2]), max(vals[1], vals[2]))
    return out


class StaticRecord:
    """
    Stream one static record into per-channel Allan accumulators and window statistics.

    Parameters
    ----------
    rate_hz : float
        Sample rate (Hz).
    c : float, keyword-only
        Level factor of the interval.
    settings : DetectorSettings, keyword-only
        Static-window thresholds.
    source : str, keyword-only
        Record name for messages.
    min_edf : float, keyword-only
        Least EDF of a tau that may hold sigma_min.

    """

    def __init__(self, rate_hz, *, c=DEFAULT_C, settings=DetectorSettings(), source='',
                 min_edf=DEFAULT_MIN_EDF):
        self.rate_hz = float(rate_hz)
        self.c = c
        self.min_edf = min_edf
        self.settings = settings
        self.source = source
        self._acc = [AllanAccumulator(self.rate_hz, taus='dense') for _ in CHANNELS]
        self._bad = [''] * len(CHANNELS)
        self._win = WindowAccumulator(self.rate_hz, window_s=settings.window_s, source=source)
        self.samples = 0
        self.duration_s = 0.0

    def update(self, t_s, accel_m_s2, gyro_rad_s):
        """
        Ingest a batch.

        Parameters
        ----------
        t_s : array_like
            (n,) stamps (s).
        accel_m_s2, gyro_rad_s : array_like
            (n, 3) specific force (m/s^2) and angular rate (rad/s).

        """
        data = np.hstack([np.asarray(accel_m_s2, np.float64), np.asarray(gyro_rad_s, np.float64)])
        self._win.update(t_s, data[:, :3], data[:, 3:])
        for k in range(len(CHANNELS)):
            if self._bad[k]:
                continue
            col = data[:, k]
            finite = np.isfinite(col)
            if not finite.all():
                first = self.samples + int(np.argmin(finite))
                self._bad[k] = (f'NaN/Inf samples in the record (first at sample {first}): the '
                                f'Allan deviation would be made up')
                continue
            self._acc[k].update(col)
        self.samples += data.shape[0]
        if len(t_s):
            self.duration_s = float(t_s[-1])

    def static_check(self):
        """
        Return why the record is not a static record, or '' when it is.

        Returns
        -------
        dict
            ``{'static_fraction': float, 'orientation': str or None, 'problem': str,
            'accel_problem': str}``.

        """
        win = self._win.result()
        out = {'static_fraction': float('nan'), 'orientation': None, 'problem': '',
               'accel_problem': ''}
        try:
            det = find_dwells(win, self.settings)
        except GyroNoiseError as err:
            msg = str(err)
            if 'accelerometer reads' in msg:
                # no specific force: accel channels are undetermined, the gyro may be fine
                out['accel_problem'] = msg
                return out
            out['problem'] = msg
            return out
        out['static_fraction'] = det.static_fraction
        if det.static_fraction < STATIC_FRACTION_MIN:
            out['problem'] = (f'record is not static: only {100 * det.static_fraction:.0f} % of '
                              f'its {self.settings.window_s:g} s windows are static '
                              f'(need {100 * STATIC_FRACTION_MIN:.0f} %)')
            return out
        fin = win.usable
        mean = np.nanmean(win.accel_mean_m_s2[fin], axis=0)
        out['orientation'] = classify(mean)[0]
        kinds = {d.orientation for d in det.dwells + det.short}
        if len(kinds) > 1:
            out['problem'] = (f'record is not static: it holds dwells in {len(kinds)} '
                              f'orientations ({", ".join(sorted(kinds))})')
        return out

    def finish(self):
        """
        Return the per-channel results and the static check.

        Returns
        -------
        (dict, dict)
            ``{channel: ChannelResult}`` and the :meth:`static_check` document.

        """
        check = self.static_check()
        out = {}
        for k, ch in enumerate(CHANNELS):
            reason = self._bad[k] or check['problem']
            if not reason and ch.startswith('accel'):
                reason = check['accel_problem']
            if reason:
                out[ch] = ChannelResult(ch, None, undetermined(reason, self.c))
                continue
            try:
                allan = self._acc[k].result()
            except GyroNoiseError as err:
                out[ch] = ChannelResult(ch, None, undetermined(f'record too short: {err}', self.c))
                continue
            if not np.any(np.asarray(allan.adev) > 0):
                out[ch] = ChannelResult(ch, allan, undetermined('constant signal (all-zero '
                                                                'Allan deviation)', self.c))
                continue
            iv = bias_instability_interval(allan.tau_s, allan.adev, c=self.c, edf=allan.edf,
                                           min_edf=self.min_edf)
            out[ch] = ChannelResult(ch, allan, iv, _fit(allan))
        return out, check
