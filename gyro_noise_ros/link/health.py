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
Verdict of the board link over one diagnostics period (pure, no ROS).

The driver keeps cumulative counters (tick on the hot path); once per diagnostics period its
:class:`LinkTask` takes their differences into a :class:`LinkWindow`, :func:`judge_link` picks
the level from the explicit limits in :class:`LinkThresholds` and :func:`link_items` gives the
key/values (run on the timer), returned as a :class:`gyro_noise_ros.core.items.TaskStatus`:

- OK without checks: the node is ``unconfigured`` or ``inactive`` (lifecycle states).
- ERROR: the port is not streaming (the message names the last error); no sample for
  ``silence_limit_s``; lost fraction in the window above ``loss_error_ratio``.
- WARN: lost fraction above ``loss_warn_ratio``; CRC errors or sensor FIFO overruns in the window;
  samples produced (published + lost) off the acknowledged ODR by more than
  ``rate_tolerance_ratio`` plus two frames; a board counter restart.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from .session import frame_interval_s
from ..core.items import TaskStatus, worst
from ..errors import ParameterError

# Lifecycle states in which not streaming is what was asked for (a manager drives the node).
_IDLE = {'unconfigured': 'Unconfigured (lifecycle): the port is closed.',
         'inactive': 'Inactive (lifecycle): the link is up, samples are not published.'}


def _limit(default: float, description: str, unit: str = '') -> Any:
    return field(default=default, metadata={'description': description, 'unit': unit,
                                            'min': 0.0, 'max': 1.0})


@dataclass(frozen=True)
class LinkThresholds:
    """
    Limits of the link verdict (field metadata gives each one's description and unit).

    Attributes
    ----------
    rate_tolerance_ratio : float
        Allowed relative difference between the measured and the acknowledged rate.
    loss_warn_ratio, loss_error_ratio : float
        Limits on the fraction of samples lost in one window.

    """

    rate_tolerance_ratio: float = _limit(
        0.02, 'WARN when the measured sample rate differs from the configured ODR by more than '
        'this')
    loss_warn_ratio: float = _limit(
        0.0, 'WARN when the fraction of samples lost in one diagnostics period exceeds this')
    loss_error_ratio: float = _limit(
        0.01, 'ERROR when the fraction of samples lost in one diagnostics period exceeds this')

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not 0.0 <= value <= 1.0:
                raise ParameterError(f'{f.name} must be in [0, 1], got {value!r}')
        if self.loss_warn_ratio > self.loss_error_ratio:
            raise ParameterError(f"parameter 'loss_warn_ratio' = {self.loss_warn_ratio} exceeds "
                                 f"'loss_error_ratio' = {self.loss_error_ratio}")


@dataclass(frozen=True)
class LinkWindow:
    """
    What happened on the link during one diagnostics window (differences of the counters).

    Attributes
    ----------
    state : str
        ``'streaming'``, ``'connecting'``, ``'configuring'``, ``'disconnected'``, ``'inactive'``,
        ``'unconfigured'``.
    last_error : str
        Why the link last failed (``'none'``).
    window_s : float
        Length of the window (s), from the later of the previous report and the stream start.
    published, lost, crc_errors, fifo_overruns, frames_ok, samples_ok : int
        Counter increments during the window.
    restarted : bool
        The board restarted its sample counter during the window.
    odr_hz : float or None
        The acknowledged output data rate (Hz); None before any acknowledgement.
    seconds_since_sample : float
        Time since the last decoded sample (s).
    silence_limit_s : float
        Silence that is an ERROR (s).

    """

    state: str
    last_error: str = 'none'
    window_s: float = 0.0
    published: int = 0
    lost: int = 0
    crc_errors: int = 0
    fifo_overruns: int = 0
    frames_ok: int = 0
    samples_ok: int = 0
    restarted: bool = False
    odr_hz: float | None = None
    seconds_since_sample: float = 0.0
    silence_limit_s: float = float('inf')

    @property
    def rate_hz(self) -> float:
        """float: Published samples per second in the window (NaN for an empty window)."""
        return self.published / self.window_s if self.window_s > 0 else float('nan')


@dataclass(frozen=True)
class LinkVerdict:
    """
    Verdict of the link over one window.

    Attributes
    ----------
    level : str
        'OK', 'WARN' or 'ERROR'.
    message : str
        One sentence naming the worst check (the first one among equals).
    checks : tuple of (str, str)
        (level, sentence) of every check that did not pass, in evaluation order.

    """

    level: str
    message: str
    checks: tuple


def judge_link(window: 'LinkWindow',
               thresholds: 'LinkThresholds | None' = None) -> 'LinkVerdict':
    """
    Judge one window of the link (module doc lists the checks).

    Parameters
    ----------
    window : LinkWindow
        Counter increments of the window.
    thresholds : LinkThresholds, optional
        The limits (default: the defaults of :class:`LinkThresholds`).

    Returns
    -------
    LinkVerdict

    """
    th = thresholds if thresholds is not None else LinkThresholds()
    w = window
    checks = []
    if w.state in _IDLE:
        return LinkVerdict('OK', _IDLE[w.state], ())
    if w.state == 'disconnected':
        checks.append(('ERROR', f'Link down: {w.last_error}.'))
    elif w.state != 'streaming':
        checks.append(('ERROR', f'Link {w.state}, not streaming (last error: {w.last_error}).'))
    else:
        if w.odr_hz is not None and w.seconds_since_sample >= w.silence_limit_s:
            checks.append(('ERROR', f'No samples for {w.seconds_since_sample:.1f} s.'))
        produced = w.published + w.lost
        if produced > 0:
            ratio = w.lost / produced
            text = f'{w.lost} samples lost in the last {w.window_s:.1f} s ({100 * ratio:.3g} %).'
            if ratio > th.loss_error_ratio:
                checks.append(('ERROR', text))
            elif ratio > th.loss_warn_ratio:
                checks.append(('WARN', text))
        if w.crc_errors > 0:
            checks.append(('WARN', f'{w.crc_errors} CRC errors in the last {w.window_s:.1f} s.'))
        if w.fifo_overruns > 0:
            # Samples the sensor dropped before the board read them: not in the counter.
            checks.append(('WARN', f'The sensor FIFO overran {w.fifo_overruns} times in the last '
                                   f'{w.window_s:.1f} s.'))
        # Lost samples count as produced (losses have their own check); two frames of slack
        # because a window's count is quantised by whole frames.
        per_frame = w.samples_ok / w.frames_ok if w.frames_ok else 1.0
        expected = w.odr_hz * w.window_s if w.odr_hz is not None else 0.0
        if expected > 0 and abs(produced - expected) > (th.rate_tolerance_ratio * expected
                                                        + 2.0 * per_frame):
            checks.append(('WARN', f'Sample rate {produced / w.window_s:.1f} Hz differs from the '
                                   f'configured {w.odr_hz:g} Hz.'))
        if w.restarted:
            checks.append(('WARN', 'The board restarted its sample counter.'))
    level, message = worst(checks, f'Streaming at {w.rate_hz:.0f} Hz, no loss.'
                           if w.state == 'streaming' else 'Link idle.')
    return LinkVerdict(level, message, tuple(checks))


#: Cumulative counters differenced over a window (node counters, then decoder counters).
_NODE_COUNTERS = ('published', 'lost', 'restarts')
_LINK_COUNTERS = ('crc_errors', 'fifo_overruns', 'frames_ok', 'samples_ok')


def counters(snapshot: Mapping[str, Any]) -> dict[str, int]:
    """
    Return the cumulative counters a window is the difference of.

    Parameters
    ----------
    snapshot : dict
        The driver's ``link_snapshot()`` (node counters and ``link``, the decoder's counters).

    Returns
    -------
    dict of str to int

    """
    link = snapshot['link']
    return {**{k: snapshot[k] for k in _NODE_COUNTERS}, **{k: link.get(k, 0)
                                                           for k in _LINK_COUNTERS}}


def window_between(prev: Mapping[str, Any], snapshot: Mapping[str, Any], *, now: float,
                   since: float, period_s: float) -> 'LinkWindow':
    """
    Build the :class:`LinkWindow` from one diagnostics report to the next.

    Parameters
    ----------
    prev : dict
        :func:`counters` at the previous report.
    snapshot : dict
        The driver's ``link_snapshot()`` now, with ``state`` as it should be reported.
    now : float
        ``time.monotonic()`` now (s).
    since : float
        Start of the window (``time.monotonic()``, s): the later of the previous report, the
        stream start and the activation.
    period_s : float
        Diagnostics period (s); no sample for a period (and three full frames) is an ERROR.

    Returns
    -------
    LinkWindow

    """
    cur = counters(snapshot)
    config = snapshot['config']
    return LinkWindow(
        state=snapshot['state'], last_error=snapshot['last_error'], window_s=now - since,
        restarted=cur['restarts'] > prev['restarts'],
        odr_hz=None if config is None else config.odr_hz,
        seconds_since_sample=now - (snapshot['last_sample_monotonic'] or now),
        silence_limit_s=(max(period_s, frame_interval_s(config)) if config is not None
                         else float('inf')),
        **{k: cur[k] - prev[k] for k in ('published', 'lost', *_LINK_COUNTERS)})


def link_items(snapshot: Mapping[str, Any], window: 'LinkWindow', *, port: str,
               drift_ppm: float | None) -> list[tuple[str, str]]:
    """
    Return the key/values of the ``'<node>: link'`` status (``docs/diagnostics.md``).

    Parameters
    ----------
    snapshot : dict
        The driver's ``link_snapshot()``, with ``state`` as it should be reported.
    window : LinkWindow
        The window of this report (for the sample rate).
    port : str
        The port parameter.
    drift_ppm : float
        Board clock rate against the host clock (ppm).

    Returns
    -------
    list of (str, object)

    """
    s, link, config = snapshot, snapshot['link'], snapshot['config']

    def fmt(x: float | None) -> str:
        return '-' if x is None else format(x, 'g')

    return [
        ('Connection', s['state']),
        ('Port', port),
        ('Configured rate (Hz)', fmt(config and config.odr_hz)),
        ('Gyro full scale (deg/s)', fmt(config and config.gyro_fs_dps)),
        ('Accel full scale (g)', fmt(config and config.accel_fs_g)),
        ('Sample rate (Hz)', f'{window.rate_hz:.1f}' if s['state'] == 'streaming' else '0.0'),
        ('Samples published', s['published']),
        ('Samples lost', s['lost']),
        ('Samples flagged lost by the board', link.get('samples_flagged_lost', 0)),
        # Equal consecutive counters are removed by the decoder, older ones by the tracker.
        ('Duplicates dropped', s['duplicates'] + link.get('duplicates', 0)),
        ('Samples dropped while inactive', s['discarded']),
        ('CRC errors', link.get('crc_errors', 0)),
        ('Resyncs', link.get('resyncs', 0)),
        ('Bytes discarded', link.get('bytes_discarded', 0)),
        ('Frames ok', link.get('frames_ok', 0)),
        ('Sensor FIFO overruns', link.get('fifo_overruns', 0)),
        ('Clock drift (ppm)', f'{drift_ppm:.1f}'),
        ('Connections', s['connections']),
        ('Counter restarts', s['restarts']),
        ('Temperature messages', s['temperatures']),
        ('Last error', s['last_error']),
    ]


class LinkTask:
    """
    The driver's ``'<node>: link'`` diagnostics task: the counters' differences, judged.

    Parameters
    ----------
    thresholds : LinkThresholds
        The limits; replace the attribute to change them at runtime (one swap).
    port : str, keyword-only
        The port parameter (reported).
    period_s : float, keyword-only
        Diagnostics period (s); no sample for a period (and three full frames) is an ERROR.
    now : float, keyword-only
        ``time.monotonic()`` at the start (s).
    snapshot : dict, keyword-only
        The driver's ``link_snapshot()`` at the start: the first window's counters.

    """

    def __init__(self, thresholds: LinkThresholds, *, port: str, period_s: float, now: float,
                 snapshot: dict) -> None:
        self.thresholds = thresholds
        self.port = port
        self.period_s = period_s
        self._prev = (now, counters(snapshot))

    def run(self, snapshot: dict, now: float, *, drift_ppm: float) -> TaskStatus:
        """
        Judge the window since the previous run and return the status.

        The lifecycle state decides what is reported: ``unconfigured`` whatever the link does,
        ``inactive`` for a streaming link the lifecycle has not activated. The window starts at
        the latest of the previous run, the stream start and the activation.

        Parameters
        ----------
        snapshot : dict
            The driver's ``link_snapshot()`` now (not modified).
        now : float
            ``time.monotonic()`` now (s).
        drift_ppm : float, keyword-only
            Board clock rate against the host clock (ppm, reported).

        Returns
        -------
        TaskStatus

        """
        (prev_time, prev), self._prev = self._prev, (now, counters(snapshot))
        s = dict(snapshot)
        if s['lifecycle'] == 'unconfigured':
            s['state'] = 'unconfigured'
        elif s['lifecycle'] == 'inactive' and s['state'] == 'streaming':
            s['state'] = 'inactive'
        since = max(prev_time, s['streaming_since'] or prev_time, s['activated_at'])
        window = window_between(prev, s, now=now, since=since, period_s=self.period_s)
        verdict = judge_link(window, self.thresholds)
        values = link_items(s, window, port=self.port, drift_ppm=drift_ppm)
        return TaskStatus(verdict.level, verdict.message,
                          tuple((k, v if isinstance(v, str) else str(v)) for k, v in values))
