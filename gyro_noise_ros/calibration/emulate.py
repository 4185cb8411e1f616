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
Scenario model of the reliability procedure for the emulator: motion, sensor errors, stress.

Pure (numpy/scipy, no I/O). The emulator (``link/emulator.py``) adds what a :class:`Scenario`
returns to its own noise; :func:`simulate` runs a scenario with white noise alone for tests.
Sensor model, accelerometer and gyro alike (the calibration's own model)::

    measured(t) = (I + diag(scale_factor) + misalignment) @ true(t) + bias + u(t) + noise(t)

``true`` is the specific force (m/s^2, REP-103: +g on the axis pointing up) and the angular rate
(rad/s) in the sensor frame. ``u`` is the slow bias variation that sets the Allan floor: a sum of
first-order Gauss-Markov processes with time constants spread evenly in log over
``FLICKER_TAU_S``, scaled to a two-sided PSD of B^2 / (2 pi f) (an Allan plateau of 0.664 B,
IEEE 952 bias instability B), plus a random walk of K per sqrt(s).

Motions (ENU, z up; Earth rate at a latitude and heading): :class:`SixPosition` (a dwell per
orientation, joined by (1 - cos) turns about a fixed body axis, no lever arm; a dwell may be
tilted), :class:`MultiPose` (any number of poses in arbitrary attitudes,
:func:`pose_attitudes`), :class:`Static`, and :class:`Excitation` (a sine dwell or up-and-down
sweep on one axis, paper 001 section 5.3; :meth:`Excitation.reference` is an ideal reference on
the shaker). :meth:`SensorErrors.stressed` moves the errors to the paper's "after" values
(Table 6) and multiplies the bias instability, which widens the bias-instability interval
(``portenta_emulator --stress`` uses 1.7: ~+125 % with its default noise levels, the paper's
420 s -> 945 s). Defaults and their reasons: docs/reliability.md section 4.
"""

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

from .sixpos import EARTH_RATE_RAD_S
from .static import ORIENTATIONS
from ..errors import ParameterError
from ..units import MG_TO_M_S2, STANDARD_GRAVITY_M_S2

#: Paper 001 Table 6, before the vibration test: biases (mg) and scale factors (%).
PAPER_BEFORE_BIAS_MG = (-4.9, -4.4, -4.7)
PAPER_BEFORE_SCALE_PCT = (-0.02, -0.07, -0.05)
#: Paper 001 Table 6, after the vibration test.
PAPER_AFTER_BIAS_MG = (-6.8, -8.3, -2.6)
PAPER_AFTER_SCALE_PCT = (-0.14, 0.01, -0.14)
#: Time constants spanned by the flicker-like bias variation (s).
FLICKER_TAU_S = (0.05, 20000.0)
FLICKER_PER_DECADE = 3

#: Two float64 arrays returned together: (rate, force), (phase, frequency), (phi, q).
_TwoArrays = tuple[NDArray[np.float64], NDArray[np.float64]]

_ATTITUDE = {'+z': Rotation.identity(), '-z': Rotation.from_euler('x', 180, degrees=True),
             '+x': Rotation.from_euler('y', -90, degrees=True),
             '-x': Rotation.from_euler('y', 90, degrees=True),
             '+y': Rotation.from_euler('x', 90, degrees=True),
             '-y': Rotation.from_euler('x', -90, degrees=True)}


def attitude(orientation: str) -> Rotation:
    """
    Return the sensor-to-world rotation of an orientation (its axis pointing up).

    Parameters
    ----------
    orientation : str
        One of ``+x -x +y -y +z -z``.

    Returns
    -------
    scipy.spatial.transform.Rotation

    """
    if orientation not in _ATTITUDE:
        raise ParameterError(f'orientation must be one of {ORIENTATIONS}, got {orientation!r}')
    return _ATTITUDE[orientation]


def _matrix(value: ArrayLike | None, name: str) -> NDArray[np.float64]:
    m = np.zeros((3, 3)) if value is None else np.array(value, dtype=np.float64)
    if m.shape == (6,):
        full = np.zeros((3, 3))
        full[~np.eye(3, dtype=bool)] = m
        m = full
    if m.shape != (3, 3) or not np.all(np.isfinite(m)):
        raise ParameterError(f'{name} must be 3x3 (or its 6 off-diagonal terms), got {value!r}')
    if np.any(np.diag(m) != 0):
        raise ParameterError(f'{name} must have a zero diagonal (scale factors are separate)')
    return m


def _vec(value: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f'{name} must be finite, got {value!r}')
    return arr


@dataclass(frozen=True)
class SensorErrors:
    """
    Systematic errors and bias variation of accelerometer and gyro (see the module docstring).

    Attributes
    ----------
    accel_bias_m_s2 : 3 floats
        Accelerometer bias (m/s^2).
    accel_scale_factor : 3 floats
        Dimensionless (-0.0002 = -0.02 %).
    accel_misalignment : 3x3 or 6 floats
        Cross-axis terms, zero diagonal ([j, i]: true axis i into measured axis j).
    gyro_bias_rad_s : 3 floats
        Gyro bias added by the scenario (rad/s; the emulator board adds its own on top).
    gyro_scale_factor : 3 floats
        Dimensionless.
    gyro_misalignment : 3x3 or 6 floats
        Cross-axis terms, zero diagonal.
    accel_bias_instability_m_s2, gyro_bias_instability_rad_s : float
        IEEE 952 bias instability B of the flicker-like part (m/s^2, rad/s).
    accel_random_walk_m_s2_sqrt_s, gyro_random_walk_rad_s_sqrt_s : float
        Random-walk coefficient K (m/s^2/sqrt(s), rad/s/sqrt(s)).

    """

    # given as sequences (or None), held as numpy arrays after __post_init__: Any covers both
    accel_bias_m_s2: Any = tuple(b * MG_TO_M_S2 for b in PAPER_BEFORE_BIAS_MG)
    accel_scale_factor: Any = tuple(s / 100.0 for s in PAPER_BEFORE_SCALE_PCT)
    accel_misalignment: Any = None
    gyro_bias_rad_s: Any = (0.0, 0.0, 0.0)
    gyro_scale_factor: Any = (0.0, 0.0, 0.0)
    gyro_misalignment: Any = None
    accel_bias_instability_m_s2: float = 0.0
    gyro_bias_instability_rad_s: float = 0.0
    accel_random_walk_m_s2_sqrt_s: float = 0.0
    gyro_random_walk_rad_s_sqrt_s: float = 0.0

    def __post_init__(self) -> None:
        for name in ('accel_bias_m_s2', 'accel_scale_factor', 'gyro_bias_rad_s',
                     'gyro_scale_factor'):
            object.__setattr__(self, name, _vec(getattr(self, name), name))
        for name in ('accel_misalignment', 'gyro_misalignment'):
            object.__setattr__(self, name, _matrix(getattr(self, name), name))
        for name in ('accel_bias_instability_m_s2', 'gyro_bias_instability_rad_s',
                     'accel_random_walk_m_s2_sqrt_s', 'gyro_random_walk_rad_s_sqrt_s'):
            value = float(getattr(self, name))
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f'{name} must be finite and >= 0, got {value!r}')
            object.__setattr__(self, name, value)

    @property
    def accel_matrix(self) -> NDArray[np.float64]:
        """numpy.ndarray: ``I + diag(accel_scale_factor) + accel_misalignment``."""
        return np.eye(3) + np.diag(self.accel_scale_factor) + self.accel_misalignment

    @property
    def gyro_matrix(self) -> NDArray[np.float64]:
        """numpy.ndarray: ``I + diag(gyro_scale_factor) + gyro_misalignment``."""
        return np.eye(3) + np.diag(self.gyro_scale_factor) + self.gyro_misalignment

    def stressed(self, *, instability_factor: float = 1.5, misalignment_factor: float = 2.0,
                 accel_bias_m_s2: ArrayLike | None = None,
                 accel_scale_factor: ArrayLike | None = None,
                 gyro_bias_change_rad_s: ArrayLike = 0.0) -> 'SensorErrors':
        """
        Return the errors after a stress (paper 001 Table 6 "after" values by default).

        Parameters
        ----------
        instability_factor : float, keyword-only
            Factor on both bias-instability levels (the emulator's ``--stress`` gives 1.7).
        misalignment_factor : float, keyword-only
            Factor on the cross-axis terms (the paper blames a deformed frame).
        accel_bias_m_s2, accel_scale_factor : 3 floats, optional, keyword-only
            New values; default the paper's "after" column.
        gyro_bias_change_rad_s : float or 3 floats, keyword-only
            Added to the gyro bias (rad/s).

        Returns
        -------
        SensorErrors

        """
        if accel_bias_m_s2 is None:
            accel_bias_m_s2 = tuple(b * MG_TO_M_S2 for b in PAPER_AFTER_BIAS_MG)
        if accel_scale_factor is None:
            accel_scale_factor = tuple(s / 100.0 for s in PAPER_AFTER_SCALE_PCT)
        return replace(
            self, accel_bias_m_s2=accel_bias_m_s2, accel_scale_factor=accel_scale_factor,
            accel_misalignment=self.accel_misalignment * misalignment_factor,
            gyro_misalignment=self.gyro_misalignment * misalignment_factor,
            gyro_bias_rad_s=self.gyro_bias_rad_s + _vec(gyro_bias_change_rad_s, 'gyro bias'),
            accel_bias_instability_m_s2=self.accel_bias_instability_m_s2 * instability_factor,
            gyro_bias_instability_rad_s=self.gyro_bias_instability_rad_s * instability_factor)


def flicker_components(bias_instability: float, rate_hz: float,
                       tau_s: tuple[float, float] = FLICKER_TAU_S,
                       per_decade: int = FLICKER_PER_DECADE) -> _TwoArrays:
    """
    Return the AR(1) coefficients and innovation scales of the flicker-like sum.

    A Gauss-Markov process of variance s^2 and time constant T has the one-sided PSD
    4 s^2 T / (1 + (2 pi f T)^2); summed over T spaced by d = ln(10) / per_decade in ln T it
    approaches s^2 / (d f). IEEE 952's flicker PSD B^2 / (2 pi f) is two-sided (its Allan
    relation, paper 001 eq. 8, carries the factor 4), i.e. B^2 / (pi f) one-sided, so
    s = B sqrt(d / pi); the Allan plateau is then sqrt(2 ln 2 / pi) B = 0.664 B.

    Parameters
    ----------
    bias_instability : float
        B (unit of the rate).
    rate_hz : float
        Sample rate (Hz).
    tau_s : (float, float)
        Shortest and longest time constant (s); the shortest is raised to 2 samples.
    per_decade : int
        Components per decade.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        phi (AR coefficient per sample) and the innovation standard deviation of each component.

    """
    lo = max(tau_s[0], 2.0 / rate_hz)
    n = max(1, int(np.ceil(np.log10(tau_s[1] / lo) * per_decade)) + 1)
    taus = lo * 10.0 ** (np.arange(n) / per_decade)
    d = np.log(10.0) / per_decade
    s = bias_instability * np.sqrt(d / np.pi)
    phi = np.exp(-1.0 / (taus * rate_hz))
    return phi, s * np.sqrt(1.0 - phi ** 2)


class BiasVariation:
    """
    Stateful generator of the slow bias variation u(t) of 3 axes (flicker-like + random walk).

    Parameters
    ----------
    bias_instability : float
        B (unit of the rate).
    random_walk : float
        K (unit of the rate per sqrt(s)).
    rate_hz : float
        Sample rate (Hz).
    rng : numpy.random.Generator
        Random stream (one draw per sample, component and axis).

    """

    def __init__(self, bias_instability: float, random_walk: float, rate_hz: float,
                 rng: np.random.Generator) -> None:
        self.rate_hz = float(rate_hz)
        self._rng = rng
        self._k = float(random_walk) / np.sqrt(self.rate_hz)
        self._on_flicker = bias_instability > 0
        self._phi, self._q = flicker_components(bias_instability, rate_hz)
        # start the Gauss-Markov states in their stationary distribution (no warm-up transient)
        sd = self._q / np.sqrt(1.0 - self._phi ** 2)
        self._state = rng.standard_normal((self._phi.size, 3)) * sd[:, None]
        self._walk = np.zeros(3)

    def generate(self, n: int) -> NDArray[np.float64]:
        """
        Return the next ``n`` samples.

        Parameters
        ----------
        n : int
            Samples.

        Returns
        -------
        numpy.ndarray
            (n, 3).

        """
        out = np.zeros((n, 3))
        if n == 0:
            return out
        if self._on_flicker:
            w = self._rng.standard_normal((self._phi.size, n, 3))
            for i, (phi, q) in enumerate(zip(self._phi, self._q)):
                y, _ = lfilter([q], [1.0, -phi], w[i], axis=0, zi=(phi * self._state[i])[None])
                out += y
                self._state[i] = y[-1]
        if self._k > 0:
            steps = np.cumsum(self._rng.standard_normal((n, 3)) * self._k, axis=0) + self._walk
            self._walk = steps[-1].copy()
            out += steps
        return out


@dataclass(frozen=True)
class Static:
    """
    The sensor at rest in one orientation.

    Attributes
    ----------
    orientation : str
        Axis pointing up (``+z`` lying flat).
    gravity_m_s2 : float
        Local gravity (m/s^2).
    latitude_deg : float
        Latitude for the Earth rate (deg).
    heading_deg : float
        Rotation about the vertical (deg).

    """

    orientation: str = '+z'
    gravity_m_s2: float = STANDARD_GRAVITY_M_S2
    latitude_deg: float = 45.0
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        attitude(self.orientation)      # a bad orientation fails here, before any output

    def true(self, t_s: ArrayLike) -> _TwoArrays:
        """
        Return the true angular rate (rad/s) and specific force (m/s^2) in the sensor frame.

        Parameters
        ----------
        t_s : array_like
            Times (s).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (n, 3) each.

        """
        n = np.asarray(t_s).shape[0]
        r = Rotation.from_euler('z', self.heading_deg, degrees=True) * attitude(self.orientation)
        return _earth_and_gravity(r, np.zeros((n, 3)), self.gravity_m_s2, self.latitude_deg)


def _earth_and_gravity(rot: Rotation, rate_body: NDArray[np.float64], g: float,
                       lat: float) -> _TwoArrays:
    lat = np.radians(lat)
    earth = EARTH_RATE_RAD_S * np.array([0.0, np.cos(lat), np.sin(lat)])
    inv = rot.inv()
    shape = np.shape(rate_body)
    return (rate_body + inv.apply(earth),
            np.broadcast_to(inv.apply(np.array([0.0, 0.0, g])), shape).copy())


def _sequence_true(atts: Sequence[Rotation], t_s: ArrayLike, dwell_s: float, move_s: float,
                   lead_s: float, g: float, lat: float) -> _TwoArrays:
    """Dwell in each attitude, turn to the next about a fixed body axis, (1 - cos) profile."""
    t = np.asarray(t_s, dtype=np.float64)
    period = dwell_s + move_s
    u = t - lead_s
    k = np.clip(np.floor(u / period).astype(np.int64), 0, len(atts) - 1)
    phase = u - k * period
    moving = (u > 0) & (phase > dwell_s) & (k < len(atts) - 1)
    rate = np.zeros((t.size, 3))
    quats = np.empty((t.size, 4))
    for j in range(len(atts)):
        sel = k == j
        if not np.any(sel):
            continue
        r0 = atts[j]
        quats[sel] = r0.as_quat()
        mv = sel & moving
        if np.any(mv):
            rel = (r0.inv() * atts[j + 1]).as_rotvec()
            x = (phase[mv] - dwell_s) / move_s
            s = (1.0 - np.cos(np.pi * x)) / 2.0
            quats[mv] = (r0 * Rotation.from_rotvec(np.outer(s, rel))).as_quat()
            rate[mv] = np.outer(np.pi / (2.0 * move_s) * np.sin(np.pi * x), rel)
    return _earth_and_gravity(Rotation.from_quat(quats), rate, g, lat)


def _schedule(labels: Sequence[str], dwell_s: float, move_s: float,
              lead_s: float) -> list[tuple[str, float, float]]:
    out = []
    t = lead_s
    for o in labels:
        out.append((o, t, t + dwell_s))
        t += dwell_s + move_s
    return out


class _PoseSequence:
    """Dwells in a list of attitudes joined by turns (``labels()`` and ``attitudes()``)."""

    # fields of the dataclasses built on it
    dwell_s: float
    move_s: float
    lead_s: float
    gravity_m_s2: float
    latitude_deg: float
    heading_deg: float

    def labels(self) -> list[str]:
        """Return the dwells' labels in the order visited (each subclass says)."""
        raise NotImplementedError

    def attitudes(self) -> list[Rotation]:
        """Return the sensor-to-world rotation of each dwell (each subclass says)."""
        raise NotImplementedError

    @property
    def duration_s(self) -> float:
        """float: time until the end of the last dwell (s)."""
        k = len(self.labels())
        return self.lead_s + k * self.dwell_s + (k - 1) * self.move_s

    def schedule(self) -> list[tuple[str, float, float]]:
        """
        Return the dwells as (label, start, end) in scenario time (s).

        Returns
        -------
        list of (str, float, float)

        """
        return _schedule(self.labels(), self.dwell_s, self.move_s, self.lead_s)

    def true(self, t_s: ArrayLike) -> _TwoArrays:
        """
        Return the true angular rate (rad/s) and specific force (m/s^2) in the sensor frame.

        (n, 3) each at the times ``t_s`` (s); before the start and after the end the sensor rests
        in the first and last attitude.

        """
        yaw = Rotation.from_euler('z', self.heading_deg, degrees=True)
        return _sequence_true([yaw * a for a in self.attitudes()], t_s, self.dwell_s,
                              self.move_s, self.lead_s, self.gravity_m_s2, self.latitude_deg)


@dataclass(frozen=True)
class SixPosition(_PoseSequence):
    """
    A six-position sequence: dwells joined by rotations.

    Attributes
    ----------
    order : tuple of str
        Orientations in the order visited (each of the six once, or any list).
    dwell_s : float
        Length of each dwell (s).
    move_s : float
        Length of each rotation (s).
    lead_s : float
        Dwell before the first one counts (s): time spent in the first orientation before.
    gravity_m_s2, latitude_deg : float
        Local gravity (m/s^2), latitude (deg).
    tilts : tuple of (str, float)
        ``(orientation, degrees)``: that dwell's fixture is tilted by so many degrees about the
        horizontal world x axis (a badly seated fixture; the turns into and out of it follow).
    heading_deg : float
        The whole sequence turned about the vertical (deg; where the Earth rate's horizontal
        part points in the sensor frame).

    """

    order: tuple[str, ...] = ('+z', '-z', '+x', '-x', '+y', '-y')
    dwell_s: float = 60.0
    move_s: float = 5.0
    lead_s: float = 0.0
    gravity_m_s2: float = STANDARD_GRAVITY_M_S2
    latitude_deg: float = 45.0
    tilts: tuple[tuple[str, float], ...] = ()
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        for o in self.order:
            attitude(o)
        for o, deg in self.tilts:
            if o not in self.order or not np.isfinite(deg):
                raise ParameterError(f'a tilt names an orientation of the order and a finite '
                                     f'angle, got {o!r}: {deg!r}')
        if not (self.dwell_s > 0 and self.move_s > 0 and self.lead_s >= 0):
            raise ParameterError(f'dwell_s and move_s must be > 0, lead_s >= 0, got {self}')

    def attitudes(self) -> list[Rotation]:
        """
        Return the sensor-to-world rotation of each dwell, tilts included.

        Returns
        -------
        list of scipy.spatial.transform.Rotation

        """
        tilt = dict(self.tilts)
        return [Rotation.from_euler('x', tilt.get(o, 0.0), degrees=True) * attitude(o)
                for o in self.order]

    def labels(self) -> list[str]:
        """Return the orientations in the order visited (the schedule's labels)."""
        return list(self.order)


def pose_attitudes(n: int) -> list[Rotation]:
    """
    Return ``n`` static attitudes whose "up" directions cover the sensor's sphere evenly.

    The body-frame up directions are a Fibonacci lattice (equal-area spiral), headings advance by
    the golden angle, and the spiral is visited from both ends alternately (first, last,
    second, ...): deterministic, every axis seen with both signs, opposite directions close in
    time (a slow bias drift then cannot pose as a scale factor), each turn tilting gravity by
    well over 90 degrees (a turn about the vertical tells the gyro calibration nothing).

    Parameters
    ----------
    n : int
        Number of poses (>= 9 for the multi-pose calibration).

    Returns
    -------
    list of scipy.spatial.transform.Rotation
        Sensor-to-world rotations.

    """
    n = int(n)
    if n < 1:
        raise ParameterError(f'the number of poses must be >= 1, got {n}')
    golden = np.pi * (3.0 - np.sqrt(5.0))
    out = []
    order = [k // 2 if k % 2 == 0 else n - 1 - k // 2 for k in range(n)]
    for k in order:
        z = 1.0 - 2.0 * (k + 0.5) / n
        r = np.sqrt(max(0.0, 1.0 - z * z))
        up = np.array([r * np.cos(golden * k), r * np.sin(golden * k), z])
        align, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [up])
        out.append(Rotation.from_euler('z', np.degrees(golden) * k, degrees=True) * align)
    return out


@dataclass(frozen=True)
class MultiPose(_PoseSequence):
    """
    The multi-pose sequence of the |a| = g calibration: static poses in arbitrary attitudes.

    Attributes
    ----------
    poses : int
        Number of poses (:func:`pose_attitudes`).
    dwell_s : float
        Length of each dwell (s).
    move_s : float
        Length of each turn (s).
    lead_s : float
        Rest in the first pose before its dwell counts (s).
    gravity_m_s2, latitude_deg : float
        Local gravity (m/s^2), latitude (deg).
    heading_deg : float
        The whole sequence turned about the vertical (deg).

    """

    poses: int = 18
    dwell_s: float = 30.0
    move_s: float = 5.0
    lead_s: float = 0.0
    gravity_m_s2: float = STANDARD_GRAVITY_M_S2
    latitude_deg: float = 45.0
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        if int(self.poses) != self.poses or self.poses < 2:
            raise ParameterError(f'poses must be an integer >= 2, got {self.poses!r}')
        if not (self.dwell_s > 0 and self.move_s > 0 and self.lead_s >= 0):
            raise ParameterError(f'dwell_s and move_s must be > 0, lead_s >= 0, got {self}')

    def attitudes(self) -> list[Rotation]:
        """
        Return the sensor-to-world rotation of each pose.

        Returns
        -------
        list of scipy.spatial.transform.Rotation

        """
        return pose_attitudes(self.poses)

    def labels(self) -> list[str]:
        """Return the pose names in the order visited (the schedule's labels)."""
        return [f'pose {k + 1}' for k in range(int(self.poses))]


@dataclass(frozen=True)
class Excitation:
    """
    Sine dwell or linear up-and-down sine sweep on one axis, the sensor otherwise at rest.

    Attributes
    ----------
    sensor : {'accel', 'gyro'}
        Which sensor the shaker drives.
    axis : {'x', 'y', 'z'}
        Driven axis.
    amplitude : float
        Amplitude (m/s^2 for accel, rad/s for gyro).
    frequency_hz : float
        Sine dwell frequency (Hz); the start frequency of a sweep.
    sweep_to_hz : float, optional
        End frequency of the sweep (Hz); None for a sine dwell.
    sweep_rate_hz_s : float
        Sweep rate (Hz/s); the sweep goes up then back down, and repeats.
    start_s : float
        Start of the excitation (s); at rest before.
    base : Static
        Resting orientation.

    """

    sensor: str = 'accel'
    axis: str = 'x'
    amplitude: float = 0.3 * STANDARD_GRAVITY_M_S2
    frequency_hz: float = 8.0
    sweep_to_hz: float | None = None
    sweep_rate_hz_s: float = 0.5
    start_s: float = 0.0
    base: Static = field(default_factory=Static)

    def __post_init__(self) -> None:
        if self.sensor not in ('accel', 'gyro') or self.axis not in ('x', 'y', 'z'):
            raise ParameterError(f'sensor must be accel|gyro and axis x|y|z, got {self.sensor!r}, '
                                 f'{self.axis!r}')
        if not (self.frequency_hz > 0 and self.amplitude >= 0):
            raise ParameterError('frequency_hz must be > 0 and amplitude >= 0')
        if self.sweep_to_hz is not None and not (self.sweep_to_hz > 0 and self.sweep_rate_hz_s > 0
                                                 and self.sweep_to_hz != self.frequency_hz):
            raise ParameterError('a sweep needs sweep_to_hz > 0, != frequency_hz, and a rate > 0')

    def phase_and_frequency(self, t_s: ArrayLike) -> _TwoArrays:
        """
        Return the phase (rad) and the instantaneous frequency (Hz) of the drive.

        Parameters
        ----------
        t_s : array_like
            Times (s).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)

        """
        tau = np.maximum(np.asarray(t_s, dtype=np.float64) - self.start_s, 0.0)
        f0 = self.frequency_hz
        if self.sweep_to_hz is None:
            return 2.0 * np.pi * f0 * tau, np.full(tau.shape, f0)
        f1 = self.sweep_to_hz
        r = np.sign(f1 - f0) * self.sweep_rate_hz_s
        half = (f1 - f0) / r
        cyc = np.floor(tau / (2 * half))
        x = tau - cyc * 2 * half
        up = x < half
        y = x - half
        cycles = np.where(up, f0 * x + r * x * x / 2.0,
                          (f0 + f1) / 2.0 * half + f1 * y - r * y * y / 2.0)
        freq = np.where(up, f0 + r * x, f1 - r * y)
        return 2.0 * np.pi * (cycles + cyc * (f0 + f1) * half), freq

    def drive(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """
        Return the excitation on the driven axis (m/s^2 or rad/s), 0 before ``start_s``.

        Parameters
        ----------
        t_s : array_like
            Times (s).

        Returns
        -------
        numpy.ndarray

        """
        t = np.asarray(t_s, dtype=np.float64)
        phase, _ = self.phase_and_frequency(t)
        return np.where(t >= self.start_s, self.amplitude * np.sin(phase), 0.0)

    def true(self, t_s: ArrayLike) -> _TwoArrays:
        """
        Return the true angular rate (rad/s) and specific force (m/s^2) in the sensor frame.

        Parameters
        ----------
        t_s : array_like
            Times (s).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)

        """
        rate, force = self.base.true(t_s)
        i = 'xyz'.index(self.axis)
        (force if self.sensor == 'accel' else rate)[:, i] += self.drive(t_s)
        return rate, force

    def reference(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """
        Return what an ideal reference sensor on the shaker reads (the drive alone, 3 axes).

        Parameters
        ----------
        t_s : array_like
            Times (s).

        Returns
        -------
        numpy.ndarray
            (n, 3) in the unit of ``amplitude``.

        """
        out = np.zeros((np.asarray(t_s).shape[0], 3))
        out[:, 'xyz'.index(self.axis)] = self.drive(t_s)
        return out


class Scenario:
    """
    A motion seen through sensor errors: what the emulator adds to its noise, sample by sample.

    Parameters
    ----------
    motion : Static, SixPosition or Excitation
        What the sensor goes through.
    errors : SensorErrors
        Its systematic errors and bias variation.
    rate_hz : float
        Sample rate (Hz) of the bias-variation generators.
    rng : numpy.random.Generator
        Random stream of the bias variation (independent of the emulator's noise streams).

    """

    def __init__(self, motion: Static | SixPosition | MultiPose | Excitation,
                 errors: SensorErrors, rate_hz: float, rng: np.random.Generator) -> None:
        self.motion = motion
        self.errors = errors
        acc_rng, gyr_rng = rng.spawn(2)
        self._accel_u = BiasVariation(errors.accel_bias_instability_m_s2,
                                      errors.accel_random_walk_m_s2_sqrt_s, rate_hz, acc_rng)
        self._gyro_u = BiasVariation(errors.gyro_bias_instability_rad_s,
                                     errors.gyro_random_walk_rad_s_sqrt_s, rate_hz, gyr_rng)

    def measured(self, t_s: ArrayLike) -> _TwoArrays:
        """
        Return the noise-free measurement plus the bias variation for the next samples.

        Consumes ``len(t_s)`` samples of the bias-variation streams: call with consecutive times.

        Parameters
        ----------
        t_s : array_like
            (n,) times (s).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (n, 3) angular rate (rad/s) and (n, 3) specific force (m/s^2).

        """
        t = np.asarray(t_s, dtype=np.float64)
        rate, force = self.motion.true(t)
        e = self.errors
        gyro = rate @ e.gyro_matrix.T + e.gyro_bias_rad_s + self._gyro_u.generate(t.size)
        accel = force @ e.accel_matrix.T + e.accel_bias_m_s2 + self._accel_u.generate(t.size)
        return gyro, accel

    def skip(self, n: int) -> None:
        """
        Advance the bias-variation streams by ``n`` samples (samples lost inside the sensor).

        Parameters
        ----------
        n : int
            Samples.

        """
        self._accel_u.generate(int(n))
        self._gyro_u.generate(int(n))

    def apply(self, t_s: ArrayLike, gyro_rad_s: NDArray[np.float64],
              accel_m_s2: NDArray[np.float64]) -> _TwoArrays:
        """
        Add the scenario to samples that hold only noise (the emulator hook).

        Parameters
        ----------
        t_s : array_like
            (n,) times (s).
        gyro_rad_s, accel_m_s2 : numpy.ndarray
            (n, 3) noise (and the board's own gyro bias).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)

        """
        gyro, accel = self.measured(t_s)
        return gyro_rad_s + gyro, accel_m_s2 + accel


def simulate(scenario: Scenario, n: int, rate_hz: float, *, rng: np.random.Generator,
             accel_noise_m_s2: float = 0.0, gyro_noise_rad_s: float = 0.0,
             t0_s: float = 0.0
             ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """
    Run a scenario with white noise: stamps, specific force and angular rate.

    Parameters
    ----------
    scenario : Scenario
        The scenario (its bias-variation streams advance).
    n : int
        Samples.
    rate_hz : float
        Sample rate (Hz).
    rng : numpy.random.Generator, keyword-only
        Stream of the white noise.
    accel_noise_m_s2, gyro_noise_rad_s : float, keyword-only
        White-noise standard deviations per sample (m/s^2, rad/s).
    t0_s : float, keyword-only
        Time of the first sample (s).

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        t (s), (n, 3) specific force (m/s^2), (n, 3) angular rate (rad/s).

    """
    t = t0_s + np.arange(int(n)) / float(rate_hz)
    gyro, accel = scenario.measured(t)
    accel = accel + rng.standard_normal((t.size, 3)) * accel_noise_m_s2
    gyro = gyro + rng.standard_normal((t.size, 3)) * gyro_noise_rad_s
    return t, accel, gyro
