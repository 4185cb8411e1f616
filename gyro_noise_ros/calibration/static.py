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
Static-dwell detection for the six-position and multi-pose calibrations (paper 001 section 3.1).

A recording is cut into consecutive windows of ``window_s`` seconds (by sample count at the
recording's rate). A sample holding NaN/Inf in any channel is dropped (counted, never averaged);
a window keeping fewer than half of its samples is a **gap**. A window is **static** when

* every accelerometer axis has a standard deviation below ``accel_std_max_m_s2``, and
* every gyro axis has a window mean within ``gyro_rate_max_rad_s`` of the recording's reference
  rate (the median of the window means: the gyro bias), so a slow turn about the vertical axis,
  which leaves the accelerometer unchanged, is not taken as static, and
* it is not a gap.

Consecutive static windows whose mean specific force differs by less than ``merge_tol_m_s2`` form
one dwell (a gap between them does not split it); ``trim_windows`` windows are dropped at each
end so that the settling after a rotation does not leak into the mean. Each dwell is classified
by the axis and sign of gravity (REP-103: +g on the axis pointing up, so a mean close to +g on x
is orientation ``+x``); its tilt is the angle between the mean vector and that axis.

Only window sums are kept (and, per dwell, its window means for the noise model of
:mod:`~gyro_noise_ros.calibration.dwell_noise`), so a recording of any length streams in constant
memory. Defaults and their reasons: docs/reliability.md section 1.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
#: A six-position dwell whose mean lies farther than this from its axis is not taken as that
#: orientation at all. Smaller tilts are judged by the consistency test of
#: :func:`~gyro_noise_ros.calibration.sixpos.consistency` against the noise; 5 deg leaves room
#: for a 40 mg bias plus 1 % cross-axis terms (3 deg of apparent tilt) and keeps the error a tilt
#: can put on a bias before that test, g (1 - cos 5 deg) / 2, below 2 mg.
DEFAULT_MAX_TILT_DEG = 5.0
#: Least fraction of a window's samples that must be finite, else the window is a gap.
MIN_FINITE_FRACTION = 0.5
#: Least number of static poses of the multi-pose fit: 9 unknowns (3 biases, 3 scale factors,
#: 3 non-orthogonality terms).
MIN_POSES = 9


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

    def __post_init__(self) -> None:
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
        Samples per window (int64), finite or not.
    accel_mean_m_s2, accel_std_m_s2 : numpy.ndarray
        (w, 3) mean and standard deviation of the specific force over the window's finite samples
        (m/s^2); NaN in a window with fewer than two.
    gyro_mean_rad_s, gyro_std_rad_s : numpy.ndarray
        (w, 3) mean and standard deviation of the angular rate (rad/s), likewise.
    finite : numpy.ndarray
        bool, every sample of the window finite.
    rate_hz : float
        Sample rate used to size the windows (Hz).
    source : str
        Name of the recording (for messages).
    n_good : numpy.ndarray, optional
        Samples per window with all six channels finite (int64); ``n`` when not given.
    window_samples : int
        Samples of a whole window (0: unknown).

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
    n_good: np.ndarray | None = None
    window_samples: int = 0

    def __post_init__(self) -> None:
        if self.n_good is None:
            object.__setattr__(self, 'n_good', np.where(self.finite, self.n, 0))

    @property
    def usable(self) -> NDArray[np.bool_]:
        """numpy.ndarray: bool, the window keeps enough finite samples (else it is a gap)."""
        assert self.n_good is not None  # filled by __post_init__
        return (self.n_good >= 2) & (self.n_good >= MIN_FINITE_FRACTION * self.n)

    @property
    def non_finite_samples(self) -> int:
        """int: samples dropped because one of their channels is NaN/Inf."""
        assert self.n_good is not None  # filled by __post_init__
        return int((self.n - self.n_good).sum())

    @property
    def duration_s(self) -> float:
        """float: first to last stamp plus one sample period (s); 0 without windows."""
        if self.n.size == 0:
            return 0.0
        return float(self.t_end_s[-1] - self.t_start_s[0] + 1.0 / self.rate_hz)


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

    def __init__(self, rate_hz: float, *, window_s: float = DEFAULT_WINDOW_S,
                 source: str = '') -> None:
        if not (np.isfinite(rate_hz) and rate_hz > 0):
            raise ParameterError(f'rate_hz must be finite and > 0, got {rate_hz!r}')
        self.rate_hz = float(rate_hz)
        self.size = max(2, int(round(window_s * rate_hz)))
        self.source = source
        self._rows: list[tuple[NDArray[Any], ...]] = []
        self._pend_t = np.empty(0)
        self._pend = np.empty((0, 6))

    def update(self, t_s: ArrayLike, accel_m_s2: ArrayLike, gyro_rad_s: ArrayLike) -> None:
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
            self._rows.append(_window_stats(t[:full], data[:full], self.size))
        self._pend_t, self._pend = t[full:], data[full:]

    def result(self) -> Windows:
        """
        Return the windows so far (a trailing partial window of >= 2 samples is included).

        Returns
        -------
        Windows

        """
        rows = list(self._rows)
        if self._pend_t.shape[0] >= 2:
            rows.append(_window_stats(self._pend_t, self._pend, self._pend_t.shape[0]))
        if not rows:
            e3 = np.empty((0, 3))
            return Windows(np.empty(0), np.empty(0), np.empty(0, np.int64), e3, e3, e3, e3,
                           np.empty(0, bool), self.rate_hz, self.source, np.empty(0, np.int64),
                           self.size)
        cols = [np.concatenate([r[i] for r in rows]) for i in range(7)]
        mean, std = cols[3], cols[4]
        return Windows(cols[0], cols[1], cols[2].astype(np.int64), mean[:, :3], std[:, :3],
                       mean[:, 3:], std[:, 3:], cols[5], self.rate_hz, self.source,
                       cols[6].astype(np.int64), self.size)


def _window_stats(t: NDArray[np.float64], data: NDArray[np.float64],
                  size: int) -> tuple[NDArray[Any], ...]:
    """Per-window first/last stamp, count, mean and std over the rows finite in every channel."""
    w = t.shape[0] // size
    blocks = data[:w * size].reshape(w, size, 6)
    tb = t[:w * size].reshape(w, size)
    good = np.all(np.isfinite(blocks), axis=2)
    n_good = good.sum(axis=1)
    x = np.where(good[:, :, None], blocks, 0.0)
    with np.errstate(invalid='ignore', divide='ignore'):
        mean = x.sum(axis=1) / n_good[:, None]
        dev = np.where(good[:, :, None], blocks - mean[:, None, :], 0.0)
        std = np.sqrt((dev * dev).sum(axis=1) / (n_good[:, None] - 1))
    mean[n_good < 1] = np.nan
    std[n_good < 2] = np.nan
    return (tb[:, 0], tb[:, -1], np.full(w, size), mean, std, n_good == size, n_good)


@dataclass(frozen=True)
class Dwell:
    """
    One static dwell.

    Attributes
    ----------
    orientation : str
        One of :data:`ORIENTATIONS` (the axis and sign of gravity).
    t_start_s, duration_s : float
        First stamp (s) and span (s) of the windows used (after trimming; gaps inside included).
    samples : int
        Finite samples used.
    accel_mean_m_s2, gyro_mean_rad_s : numpy.ndarray
        (3,) mean specific force (m/s^2) and angular rate (rad/s).
    accel_sem_m_s2, gyro_sem_rad_s : numpy.ndarray
        (3,) spread of the window means / sqrt(windows) (m/s^2, rad/s): the standard error of
        the mean if the window means were independent. The calibration's uncertainties do not
        use it (they come from :mod:`~gyro_noise_ros.calibration.dwell_noise`, which sees the
        wander between windows); it is reported as the white-noise part.
    accel_std_m_s2 : numpy.ndarray
        (3,) sample standard deviation inside the dwell (pooled over windows, m/s^2).
    tilt_deg : float
        Angle between the mean specific force and the orientation's axis (deg).
    source : str
        Recording the dwell comes from.
    non_finite_samples : int
        Samples inside the dwell's span dropped for NaN/Inf.
    window_t_s, window_n : numpy.ndarray
        Centre stamp (s) and finite samples of each window used.
    window_accel_m_s2, window_gyro_rad_s : numpy.ndarray
        (k, 3) window means (the noise model's input).

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
    non_finite_samples: int = 0
    window_t_s: np.ndarray | None = field(default=None, repr=False, compare=False)
    window_n: np.ndarray | None = field(default=None, repr=False, compare=False)
    window_accel_m_s2: np.ndarray | None = field(default=None, repr=False, compare=False)
    window_gyro_rad_s: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def t_end_s(self) -> float:
        """float: end of the span used (s), one sample period after its last stamp."""
        return self.t_start_s + self.duration_s

    def describe(self) -> str:
        """
        Return a one-phrase description (orientation, start, duration, recording, NaN dropped).

        Returns
        -------
        str

        """
        where = f' in {self.source}' if self.source else ''
        nan = (f', {self.non_finite_samples} NaN/Inf samples dropped'
               if self.non_finite_samples else '')
        return (f'{self.orientation} at t={self.t_start_s:.1f} s for {self.duration_s:.1f} s'
                f'{where} (tilt {self.tilt_deg:.1f} deg{nan})')

    def as_dict(self) -> dict[str, Any]:
        """
        Return the dwell as JSON-ready values (units in the keys).

        Returns
        -------
        dict

        """
        return {'orientation': self.orientation, 't_start_s': self.t_start_s,
                'duration_s': self.duration_s, 'samples': self.samples,
                'non_finite_samples': self.non_finite_samples,
                'source': self.source, 'tilt_deg': self.tilt_deg,
                'accel_mean_m_s2': self.accel_mean_m_s2.tolist(),
                'accel_sem_m_s2': self.accel_sem_m_s2.tolist(),
                'gyro_mean_rad_s': self.gyro_mean_rad_s.tolist(),
                'gyro_sem_rad_s': self.gyro_sem_rad_s.tolist()}


def dwell_windows(values: Iterable[np.ndarray | None]) -> list[np.ndarray]:
    """
    Return the per-window arrays of dwells (``Dwell.window_t_s``, ...) as a list.

    :func:`find_dwells` fills them; only a dwell built by hand lacks them, and no noise model
    can be fitted to it.

    Parameters
    ----------
    values : iterable of numpy.ndarray
        One window array per dwell.

    Returns
    -------
    list of numpy.ndarray

    """
    out = []
    for v in values:
        assert v is not None, 'a dwell without its window means (find_dwells gives them)'
        out.append(v)
    return out


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
        Fraction of the usable (non-gap) windows that were static.
    non_finite_samples : int
        Samples dropped for NaN/Inf in the whole recording.
    reference_gyro_rad_s : numpy.ndarray
        (3,) reference rate of the gyro criterion (rad/s).
    gaps : tuple of (float, float, int)
        Runs of gap windows (mostly NaN/Inf): start (s), length (s), samples.
    source : str
        Name of the recording.

    """

    dwells: tuple[Dwell, ...]
    short: tuple[Dwell, ...]
    static_fraction: float
    non_finite_samples: int
    reference_gyro_rad_s: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    gaps: tuple[tuple[float, float, int], ...] = ()
    source: str = ''

    def describe_gaps(self, min_s: float = 0.0) -> str:
        """
        Return the NaN/Inf gaps at least ``min_s`` long as one phrase ('' without any).

        Parameters
        ----------
        min_s : float
            Shortest gap listed (s).

        Returns
        -------
        str

        """
        where = f' in {self.source}' if self.source else ''
        return '; '.join(f'{length:.1f} s of NaN/Inf samples at t={t0:.1f} s{where}'
                         for t0, length, _ in self.gaps if length >= min_s)


def classify(accel_mean_m_s2: ArrayLike) -> tuple[str, float]:
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


def _dwell(win: Windows, idx: NDArray[np.intp]) -> Dwell:
    """Build a Dwell from the usable window indices ``idx`` (increasing) of ``win``."""
    assert win.n_good is not None  # filled by Windows.__post_init__
    n = win.n_good[idx].astype(np.float64)
    total = n.sum()
    w = n / total
    am = (win.accel_mean_m_s2[idx] * w[:, None]).sum(axis=0)
    gm = (win.gyro_mean_rad_s[idx] * w[:, None]).sum(axis=0)
    k = idx.size
    if k >= 2:
        a_sem = win.accel_mean_m_s2[idx].std(axis=0, ddof=1) / np.sqrt(k)
        g_sem = win.gyro_mean_rad_s[idx].std(axis=0, ddof=1) / np.sqrt(k)
    else:
        a_sem = win.accel_std_m_s2[idx[0]] / np.sqrt(n[0])
        g_sem = win.gyro_std_rad_s[idx[0]] / np.sqrt(n[0])
    # pooled within-window variance plus the spread of window means about the dwell mean
    var = (((n - 1)[:, None] * win.accel_std_m_s2[idx] ** 2).sum(axis=0)
           + (n[:, None] * (win.accel_mean_m_s2[idx] - am) ** 2).sum(axis=0)) / max(total - 1, 1)
    lo, hi = int(idx[0]), int(idx[-1])
    # the dwell spans whole windows: from the first stamp to one sample period past the last
    duration = float(win.t_end_s[hi] - win.t_start_s[lo] + 1.0 / win.rate_hz)
    span = slice(lo, hi + 1)
    dropped = int((win.n[span] - win.n_good[span]).sum())
    orientation, tilt = classify(am)
    centre = (win.t_start_s[idx] + win.t_end_s[idx]) / 2.0
    return Dwell(orientation, float(win.t_start_s[lo]), duration, int(total), am, gm, a_sem, g_sem,
                 np.sqrt(var), float(tilt), win.source, dropped, centre,
                 win.n_good[idx].copy(), win.accel_mean_m_s2[idx].copy(),
                 win.gyro_mean_rad_s[idx].copy())


def _gaps(win: Windows, usable: NDArray[np.bool_]) -> tuple[tuple[float, float, int], ...]:
    out = []
    i, w = 0, usable.size
    while i < w:
        if usable[i]:
            i += 1
            continue
        j = i
        while j < w and not usable[j]:
            j += 1
        length = float(win.t_end_s[j - 1] - win.t_start_s[i] + 1.0 / win.rate_hz)
        out.append((float(win.t_start_s[i]), length, int(win.n[i:j].sum())))
        i = j
    return tuple(out)


def find_dwells(windows: Windows, settings: DetectorSettings = DetectorSettings()) -> Detection:
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
        No samples, a detector window longer than the recording, no finite window, or an
        accelerometer that reads zero (no ``linear_acceleration``).

    """
    win = windows
    name = f' {win.source!r}' if win.source else ''
    if win.n.size == 0:
        raise InputDataError(f'recording{name} holds fewer than two samples')
    if win.window_samples and int(win.n.sum()) < win.window_samples:
        raise InputDataError(
            f'recording{name} lasts {win.duration_s:.3g} s, shorter than one detector window '
            f'({{window_s}} {settings.window_s:g} s): give a shorter {{window_s}}',
            parameters=('window_s',))
    usable = win.usable
    if not np.any(usable):
        raise InputDataError(f'recording{name} holds no finite samples (all NaN/Inf)')
    norm = np.linalg.norm(win.accel_mean_m_s2[usable], axis=1)
    if np.median(norm) < 1.0:
        raise InputDataError(f'recording{name}: the accelerometer reads ~0 (median |a| '
                             f'{np.median(norm):.3g} m/s^2): no linear_acceleration recorded?')
    ref = np.median(win.gyro_mean_rad_s[usable], axis=0)
    with np.errstate(invalid='ignore'):
        quiet = np.all(win.accel_std_m_s2 < settings.accel_std_max_m_s2, axis=1)
        still = np.all(np.abs(win.gyro_mean_rad_s - ref) < settings.gyro_rate_max_rad_s, axis=1)
    static = usable & quiet & still
    dwells: list[Dwell] = []
    short: list[Dwell] = []
    trim = int(settings.trim_windows)
    i, w = 0, win.n.size
    while i < w:
        if not static[i]:
            i += 1
            continue
        run = [i]
        j = i + 1
        while j < w:
            k = j
            while k < w and not usable[k]:      # a gap does not end a dwell ...
                k += 1
            close = k < w and static[k] and np.all(
                np.abs(win.accel_mean_m_s2[k] - win.accel_mean_m_s2[run[-1]])
                < settings.merge_tol_m_s2)
            if not close:                       # ... unless the sensor moved across it
                break
            run.append(k)
            j = k + 1
        idx = np.asarray(run[trim:len(run) - trim], dtype=np.int64)
        if idx.size:
            d = _dwell(win, idx)
            (dwells if d.duration_s >= settings.min_static_s else short).append(d)
        i = run[-1] + 1
    return Detection(tuple(dwells), tuple(short), float(static[usable].mean()),
                     win.non_finite_samples, ref, _gaps(win, usable), win.source)


def _no_dwell(short: Sequence[Dwell], settings: DetectorSettings) -> InputDataError:
    if short:
        return InputDataError(
            f'no static dwell of at least {{min_static_s}} {settings.min_static_s:g} s; shorter '
            f'ones: {"; ".join(d.describe() for d in short)}', parameters=('min_static_s',))
    return InputDataError(
        'no static dwell found: the recording never stops moving (accelerometer std >= '
        f'{settings.accel_std_max_m_s2:g} m/s^2 or gyro away from its median by >= '
        f'{settings.gyro_rate_max_rad_s:g} rad/s in every {settings.window_s:g} s window)')


def select_six(detections: Sequence[Detection],
               settings: DetectorSettings = DetectorSettings()) -> dict[str, Dwell]:
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
        A recording that never stops moving, a dwell tilted beyond ``max_tilt_deg``, two dwells
        for one orientation, or a missing orientation (the message names the dwells concerned,
        and NaN/Inf stretches where a dwell could have been).

    """
    dwells = [d for det in detections for d in det.dwells]
    short = [d for det in detections for d in det.short]
    if not dwells:
        raise _no_dwell(short, settings)
    tilted = [d for d in dwells if d.tilt_deg > settings.max_tilt_deg]
    if tilted:
        raise InputDataError(f'dwell tilted more than {{max_tilt_deg}} {settings.max_tilt_deg:g} '
                             f'deg from any axis: '
                             f'{"; ".join(d.describe() for d in tilted)}',
                             parameters=('max_tilt_deg',))
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
        gaps = '; '.join(g for g in (det.describe_gaps(settings.min_static_s)
                                     for det in detections) if g)
        lead = (f'no finite dwell for orientation(s) {", ".join(missing)}: the recording holds '
                f'{gaps} (an all-NaN dwell?)' if gaps else
                f'orientation(s) {", ".join(missing)} missing')
        near = [d for d in short if d.orientation in missing]
        extra = (f'; shorter than {{min_static_s}} {settings.min_static_s:g} s: '
                 f'{"; ".join(d.describe() for d in near)}') if near else ''
        raise InputDataError(f'{lead}; found: '
                             f'{"; ".join(d.describe() for d in chosen.values())}{extra}',
                             parameters=('min_static_s',))
    return chosen


def select_poses(detections: Sequence[Detection], settings: DetectorSettings = DetectorSettings(),
                 *, min_poses: int = MIN_POSES) -> list[Dwell]:
    """
    Return every static dwell of the recordings as a pose of the multi-pose calibration.

    Parameters
    ----------
    detections : sequence of Detection
        One per recording.
    settings : DetectorSettings
        ``min_static_s`` is named in messages.
    min_poses : int, keyword-only
        Least number of poses.

    Returns
    -------
    list of Dwell
        In recording order.

    Raises
    ------
    InputDataError
        Fewer than ``min_poses`` dwells (the message counts them and names the short ones).

    """
    dwells = [d for det in detections for d in det.dwells]
    short = [d for det in detections for d in det.short]
    if not dwells:
        raise _no_dwell(short, settings)
    if len(dwells) < min_poses:
        extra = (f'; {len(short)} more shorter than {{min_static_s}} '
                 f'{settings.min_static_s:g} s' if short else '')
        gaps = '; '.join(g for g in (det.describe_gaps() for det in detections) if g)
        raise InputDataError(f'multi-pose calibration needs at least {min_poses} static poses, '
                             f'found {len(dwells)}{extra}'
                             + (f' (and {gaps})' if gaps else ''), parameters=('min_static_s',))
    return dwells
