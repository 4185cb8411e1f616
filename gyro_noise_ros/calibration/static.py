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
Static-dwell detection for the six-position calibration (paper 001 section 3.1).

A recording is cut into consecutive windows of ``window_s`` seconds (by sample count at the
recording's rate). A window is **static** when

* every accelerometer axis has a standard deviation below ``accel_std_max_m_s2`` (a rotation or a
  handling bump moves the specific force by far more than the sensor noise), and
* every gyro axis has a window mean within ``gyro_rate_max_rad_s`` of the recording's reference
  rate (the median of the window means: the gyro bias, since a calibration recording is mostly
  static), so a slow turn about the vertical axis, which leaves the accelerometer unchanged, is
  not taken as static, and
* every sample in it is finite (NaN/Inf windows are never static; they are counted).

Consecutive static windows whose mean specific force differs by less than ``merge_tol_m_s2`` form
one dwell; ``trim_windows`` windows are dropped at each end of a dwell so that the settling after a
rotation does not leak into the mean. Each dwell is classified by the axis and sign of gravity:
REP-103 accelerometers read +g on the axis pointing up, so a dwell whose mean is close to +g on x
is orientation ``+x``. Its tilt is the angle between the mean vector and that axis.

Only window sums are kept, so a recording of any length streams in constant memory.
"""

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputDataError, ParameterError

#: The six orientations in the order the estimators use.
ORIENTATIONS = ('+x', '-x', '+y', '-y', '+z', '-z')

DEFAULT_WINDOW_S = 1.0
#: 0.1 m/s^2 (~10 mg) per-axis standard deviation: the LSM6DSO32 at 6.66 kHz has ~4 mg of white
#: noise (70 ug/sqrt(Hz)), a hand or a rotation moves the specific force by tenths of g.
DEFAULT_ACCEL_STD_MAX_M_S2 = 0.1
#: 0.02 rad/s (~1.1 deg/s) from the reference rate: slower than any deliberate rotation between
#: dwells, above the gyro noise of a 1 s window mean.
DEFAULT_GYRO_RATE_MAX_RAD_S = 0.02
DEFAULT_MERGE_TOL_M_S2 = 0.2
DEFAULT_TRIM_WINDOWS = 1
DEFAULT_MIN_STATIC_S = 10.0
#: A dwell whose mean lies farther than this from its axis is "tilted" (fixture not square).
DEFAULT_MAX_TILT_DEG = 10.0


@dataclass(frozen=True)
class DetectorSettings:
    """
    Thresholds of the static-dwell detector (see the module docstring).

    Attributes
    ----------
    window_s : float
        Window length (s).
    accel_std_max_m_s2 : float
        Largest per-axis accelerometer standard deviation of a static window (m/s^2).
    gyro_rate_max_rad_s : float
        Largest distance of a static window's gyro mean from the reference rate (rad/s).
    merge_tol_m_s2 : float
        Largest change of the mean specific force between windows of one dwell (m/s^2).
    trim_windows : int
        Windows dropped at each end of a dwell.
    min_static_s : float
        Shortest usable dwell (s), after trimming.
    max_tilt_deg : float
        Largest angle between a dwell's mean specific force and its axis (deg).

    """

    window_s: float = DEFAULT_WINDOW_S
    accel_std_max_m_s2: float = DEFAULT_ACCEL_STD_MAX_M_S2
    gyro_rate_max_rad_s: float = DEFAULT_GYRO_RATE_MAX_RAD_S
    merge_tol_m_s2: float = DEFAULT_MERGE_TOL_M_S2
    trim_windows: int = DEFAULT_TRIM_WINDOWS
    min_static_s: float = DEFAULT_MIN_STATIC_S
    max_tilt_deg: float = DEFAULT_MAX_TILT_DEG

    def __post_init__(self):
        for name in ('window_s', 'accel_std_max_m_s2', 'gyro_rate_max_rad_s', 'merge_tol_m_s2',
                     'max_tilt_deg'):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ParameterError(f'{name} must be finite and > 0, got {value!r}')
        if not (np.isfinite(self.min_static_s) and self.min_static_s >= 0):
            raise ParameterError(f'min_static_s must be finite and >= 0, '
                                 f'got {self.min_static_s!r}')
        if int(self.trim_windows) != self.trim_windows or self.trim_windows < 0:
            raise ParameterError(f'trim_windows must be an integer >= 0, '
                                 f'got {self.trim_windows!r}')


@dataclass(frozen=True)
class Windows:
    """
    Per-window statistics of one recording (what the detector and the estimators need).

    Attributes
    ----------
    t_start_s : numpy.ndarray
        Stamp of each window's first sample (s).
    t_end_s : numpy.ndarray
        Stamp of each window's last sample (s).
    n : numpy.ndarray
        Samples per window (int64).
    accel_mean_m_s2, accel_std_m_s2 : numpy.ndarray
        (w, 3) mean and standard deviation of the specific force (m/s^2); NaN in non-finite
        windows.
    gyro_mean_rad_s, gyro_std_rad_s : numpy.ndarray
        (w, 3) mean and standard deviation of the angular rate (rad/s); NaN in non-finite windows.
    finite : numpy.ndarray
        bool, every sample of the window finite.
    rate_hz : float
        Sample rate used to size the windows (Hz).
    source : str
        Name of the recording (for messages).

    """

    t_start_s: np.ndarray
    t_end_s: np.ndarray
    n: np.ndarray
    accel_mean_m_s2: np.ndarray
    accel_std_m_s2: np.ndarray
    gyro_mean_rad_s: np.ndarray
    gyro_std_rad_s: np.ndarray
    finite: np.ndarray
    rate_hz: float
    source: str = ''

    @property
    def non_finite_samples(self):
        """int: samples in windows holding NaN/Inf (an upper bound of the NaN/Inf count)."""
        return int(self.n[~self.finite].sum())


class WindowAccumulator:
    """
    Stream (stamp, accel, gyro) batches into per-window statistics in constant memory.

    Parameters
    ----------
    rate_hz : float
        Sample rate (Hz).
    window_s : float, keyword-only
        Window length (s); windows hold ``max(2, round(window_s * rate_hz))`` samples.
    source : str, keyword-only
        Name of the recording (for messages).

    """

    def __init__(self, rate_hz, *, window_s=DEFAULT_WINDOW_S, source=''):
        if not (np.isfinite(rate_hz) and rate_hz > 0):
            raise ParameterError(f'rate_hz must be finite and > 0, got {rate_hz!r}')
        self.rate_hz = float(rate_hz)
        self.size = max(2, int(round(window_s * rate_hz)))
        self.source = source
        self._rows = []
        self._pend_t = np.empty(0)
        self._pend = np.empty((0, 6))

    def update(self, t_s, accel_m_s2, gyro_rad_s):
        """
        Ingest a batch.

        Parameters
        ----------
        t_s : array_like
            (n,) stamps (s).
        accel_m_s2 : array_like
            (n, 3) specific force (m/s^2).
        gyro_rad_s : array_like
            (n, 3) angular rate (rad/s).

        """
        t = np.asarray(t_s, dtype=np.float64).reshape(-1)
        data = np.hstack([np.asarray(accel_m_s2, dtype=np.float64).reshape(-1, 3),
                          np.asarray(gyro_rad_s, dtype=np.float64).reshape(-1, 3)])
        if data.shape[0] != t.shape[0]:
            raise ParameterError(f'{t.shape[0]} stamps for {data.shape[0]} samples')
        t = np.concatenate([self._pend_t, t])
        data = np.concatenate([self._pend, data])
        full = (t.shape[0] // self.size) * self.size
        if full:
            self._add(t[:full], data[:full])
        self._pend_t, self._pend = t[full:], data[full:]

    def _add(self, t, data):
        w = t.shape[0] // self.size
        blocks = data.reshape(w, self.size, 6)
        tb = t.reshape(w, self.size)
        finite = np.all(np.isfinite(blocks), axis=(1, 2))
        with np.errstate(invalid='ignore'):
            mean = blocks.mean(axis=1)
            std = blocks.std(axis=1, ddof=1)
        self._rows.append((tb[:, 0], tb[:, -1], np.full(w, self.size), mean, std, finite))

    def result(self):
        """
        Return the windows so far (a trailing partial window of >= 2 samples is included).

        Returns
        -------
        Windows

        """
        rows = list(self._rows)
        if self._pend_t.shape[0] >= 2:
            t, data = self._pend_t, self._pend
            finite = bool(np.all(np.isfinite(data)))
            with np.errstate(invalid='ignore'):
                rows.append((t[:1], t[-1:], np.array([t.shape[0]]), data.mean(axis=0)[None],
                             data.std(axis=0, ddof=1)[None], np.array([finite])))
        if not rows:
            return Windows(np.empty(0), np.empty(0), np.empty(0, np.int64), np.empty((0, 3)),
                           np.empty((0, 3)), np.empty((0, 3)), np.empty((0, 3)),
                           np.empty(0, bool), self.rate_hz, self.source)
        cols = [np.concatenate([r[i] for r in rows]) for i in range(6)]
        mean, std = cols[3], cols[4]
        return Windows(cols[0], cols[1], cols[2].astype(np.int64), mean[:, :3], std[:, :3],
                       mean[:, 3:], std[:, 3:], cols[5], self.rate_hz, self.source)


@dataclass(frozen=True)
class Dwell:
    """
    One static dwell.

    Attributes
    ----------
    orientation : str
        One of :data:`ORIENTATIONS` (the axis and sign of gravity).
    t_start_s, duration_s : float
        First stamp (s) and length (s) of the samples used (after trimming).
    samples : int
        Samples used.
    accel_mean_m_s2, gyro_mean_rad_s : numpy.ndarray
        (3,) mean specific force (m/s^2) and angular rate (rad/s).
    accel_sem_m_s2, gyro_sem_rad_s : numpy.ndarray
        (3,) standard error of those means from the spread of the window means (m/s^2, rad/s):
        std(window means, ddof=1) / sqrt(windows), which keeps noise correlated within a window.
    accel_std_m_s2 : numpy.ndarray
        (3,) sample standard deviation inside the dwell (pooled over windows, m/s^2).
    tilt_deg : float
        Angle between the mean specific force and the orientation's axis (deg).
    source : str
        Recording the dwell comes from.

    """

    orientation: str
    t_start_s: float
    duration_s: float
    samples: int
    accel_mean_m_s2: np.ndarray
    gyro_mean_rad_s: np.ndarray
    accel_sem_m_s2: np.ndarray
    gyro_sem_rad_s: np.ndarray
    accel_std_m_s2: np.ndarray
    tilt_deg: float
    source: str = ''

    def describe(self):
        """
        Return a one-phrase description (orientation, start, duration, recording).

        Returns
        -------
        str

        """
        where = f' in {self.source}' if self.source else ''
        return (f'{self.orientation} at t={self.t_start_s:.1f} s for {self.duration_s:.1f} s'
                f'{where} (tilt {self.tilt_deg:.1f} deg)')

    def as_dict(self):
        """
        Return the dwell as JSON-ready values (units in the keys).

        Returns
        -------
        dict

        """
        return {'orientation': self.orientation, 't_start_s': self.t_start_s,
                'duration_s': self.duration_s, 'samples': self.samples,
                'source': self.source, 'tilt_deg': self.tilt_deg,
                'accel_mean_m_s2': self.accel_mean_m_s2.tolist(),
                'accel_sem_m_s2': self.accel_sem_m_s2.tolist(),
                'gyro_mean_rad_s': self.gyro_mean_rad_s.tolist(),
                'gyro_sem_rad_s': self.gyro_sem_rad_s.tolist()}


@dataclass(frozen=True)
class Detection:
    """
    Result of :func:`find_dwells` on one recording.

    Attributes
    ----------
    dwells : tuple of Dwell
        Dwells at least ``min_static_s`` long.
    short : tuple of Dwell
        Static stretches shorter than ``min_static_s`` (reported, never used).
    static_fraction : float
        Fraction of the (finite) windows that were static.
    non_finite_samples : int
        Samples in windows holding NaN/Inf.
    reference_gyro_rad_s : numpy.ndarray
        (3,) reference rate of the gyro criterion (rad/s).

    """

    dwells: tuple
    short: tuple
    static_fraction: float
    non_finite_samples: int
    reference_gyro_rad_s: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))


def classify(accel_mean_m_s2):
    """
    Return the orientation and tilt of a mean specific force.

    Parameters
    ----------
    accel_mean_m_s2 : array_like
        (3,) mean specific force (m/s^2); REP-103: +g on the axis pointing up.

    Returns
    -------
    (str, float)
        Orientation (one of :data:`ORIENTATIONS`) and tilt (deg) from that axis.

    """
    a = np.asarray(accel_mean_m_s2, dtype=np.float64)
    i = int(np.argmax(np.abs(a)))
    norm = float(np.linalg.norm(a))
    sign = '+' if a[i] >= 0 else '-'
    tilt = float(np.degrees(np.arccos(np.clip(abs(a[i]) / norm, -1.0, 1.0)))) if norm > 0 else 90.0
    return sign + 'xyz'[i], tilt


def _dwell(win, lo, hi, orientation, tilt):
    sl = slice(lo, hi)
    n = win.n[sl].astype(np.float64)
    total = n.sum()
    w = n / total
    am = (win.accel_mean_m_s2[sl] * w[:, None]).sum(axis=0)
    gm = (win.gyro_mean_rad_s[sl] * w[:, None]).sum(axis=0)
    k = hi - lo
    if k >= 2:
        a_sem = win.accel_mean_m_s2[sl].std(axis=0, ddof=1) / np.sqrt(k)
        g_sem = win.gyro_mean_rad_s[sl].std(axis=0, ddof=1) / np.sqrt(k)
    else:
        a_sem = win.accel_std_m_s2[lo] / np.sqrt(n[0])
        g_sem = win.gyro_std_rad_s[lo] / np.sqrt(n[0])
    # pooled within-window variance plus the spread of window means about the dwell mean
    var = (((n - 1)[:, None] * win.accel_std_m_s2[sl] ** 2).sum(axis=0)
           + (n[:, None] * (win.accel_mean_m_s2[sl] - am) ** 2).sum(axis=0)) / max(total - 1, 1)
    # the dwell spans whole windows: from the first stamp to one sample period past the last
    duration = float(win.t_end_s[hi - 1] - win.t_start_s[lo] + 1.0 / win.rate_hz)
    return Dwell(orientation, float(win.t_start_s[lo]), duration, int(total), am, gm, a_sem, g_sem,
                 np.sqrt(var), float(tilt), win.source)


def find_dwells(windows, settings=DetectorSettings()):
    """
    Find and classify the static dwells of one recording.

    Parameters
    ----------
    windows : Windows
        Per-window statistics (:class:`WindowAccumulator`).
    settings : DetectorSettings
        Thresholds.

    Returns
    -------
    Detection

    Raises
    ------
    InputDataError
        No finite window, or an accelerometer that reads zero (no ``linear_acceleration``).

    """
    win = windows
    name = f' {win.source!r}' if win.source else ''
    if win.n.size == 0 or not np.any(win.finite):
        raise InputDataError(f'recording{name} holds no finite samples (all NaN/Inf or empty)')
    fin = win.finite
    norm = np.linalg.norm(win.accel_mean_m_s2[fin], axis=1)
    if np.median(norm) < 1.0:
        raise InputDataError(f'recording{name}: the accelerometer reads ~0 (median |a| '
                             f'{np.median(norm):.3g} m/s^2): no linear_acceleration recorded?')
    ref = np.median(win.gyro_mean_rad_s[fin], axis=0)
    with np.errstate(invalid='ignore'):
        quiet = np.all(win.accel_std_m_s2 < settings.accel_std_max_m_s2, axis=1)
        still = np.all(np.abs(win.gyro_mean_rad_s - ref) < settings.gyro_rate_max_rad_s, axis=1)
    static = fin & quiet & still
    step = np.zeros(win.n.size, dtype=bool)
    step[1:] = np.all(np.abs(np.diff(win.accel_mean_m_s2, axis=0)) < settings.merge_tol_m_s2,
                      axis=1)
    dwells, short = [], []
    trim = int(settings.trim_windows)
    i, w = 0, win.n.size
    while i < w:
        if not static[i]:
            i += 1
            continue
        j = i + 1
        while j < w and static[j] and step[j]:
            j += 1
        lo, hi = i + trim, j - trim
        if hi > lo:
            n = win.n[lo:hi].astype(np.float64)
            mean = (win.accel_mean_m_s2[lo:hi] * (n / n.sum())[:, None]).sum(axis=0)
            orientation, tilt = classify(mean)
            d = _dwell(win, lo, hi, orientation, tilt)
            (dwells if d.duration_s >= settings.min_static_s else short).append(d)
        i = j
    return Detection(tuple(dwells), tuple(short), float(static[fin].mean()),
                     win.non_finite_samples, ref)


def select_six(detections, settings=DetectorSettings()):
    """
    Pick exactly one dwell per orientation out of one or more recordings.

    Parameters
    ----------
    detections : sequence of Detection
        One per recording.
    settings : DetectorSettings
        ``max_tilt_deg`` and ``min_static_s`` are used here.

    Returns
    -------
    dict
        Orientation -> Dwell, for all six orientations.

    Raises
    ------
    InputDataError
        A recording that never stops moving, a tilted dwell, two dwells for one orientation, or a
        missing orientation (the message names the dwells concerned).

    """
    dwells = [d for det in detections for d in det.dwells]
    short = [d for det in detections for d in det.short]
    if not dwells:
        if short:
            raise InputDataError(
                f'no static dwell of at least --min-static-s {settings.min_static_s:g} s; shorter '
                f'ones: {"; ".join(d.describe() for d in short)}')
        raise InputDataError(
            'no static dwell found: the recording never stops moving (accelerometer std >= '
            f'{settings.accel_std_max_m_s2:g} m/s^2 or gyro away from its median by >= '
            f'{settings.gyro_rate_max_rad_s:g} rad/s in every {settings.window_s:g} s window)')
    tilted = [d for d in dwells if d.tilt_deg > settings.max_tilt_deg]
    if tilted:
        raise InputDataError(f'dwell tilted more than {settings.max_tilt_deg:g} deg from any '
                             f'axis: '
                             f'{"; ".join(d.describe() for d in tilted)}')
    chosen = {}
    for o in ORIENTATIONS:
        mine = [d for d in dwells if d.orientation == o]
        if len(mine) > 1:
            raise InputDataError(f'{len(mine)} dwells claim orientation {o}: '
                                 f'{"; ".join(d.describe() for d in mine)}')
        if mine:
            chosen[o] = mine[0]
    missing = [o for o in ORIENTATIONS if o not in chosen]
    if missing:
        near = [d for d in short if d.orientation in missing]
        extra = (f'; shorter than --min-static-s {settings.min_static_s:g} s: '
                 f'{"; ".join(d.describe() for d in near)}') if near else ''
        raise InputDataError(f'orientation(s) {", ".join(missing)} missing; found: '
                             f'{"; ".join(d.describe() for d in chosen.values())}{extra}')
    return chosen
