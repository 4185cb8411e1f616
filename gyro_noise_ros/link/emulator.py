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
Pure model of the Portenta H7 + LSM6DSO32 board: samples with ground truth, commands, faults.

No I/O and no threads: :mod:`gyro_noise_ros.link.serve` serves this model on a pseudo-terminal or
TCP and writes SD logs. One gyro axis at sample k (time ``t_k``, s since power-on)::

    rate_k = bias + v_k + helium(t_k) + temp_sens * (T(t_k) - T(0))
             + vib_amp * sin(2 pi vib_hz t_k + phase)
    raw_k  = clip(round(rate_k / LSB(gyro_fs)), -32768, 32767)

``v_k`` is the fractional-order noise of paper 000 eq. (2), ``Delta^alpha v[k+1] = f v[k] + w[k]``
(:class:`gyro_noise_ros.core.simulate.FractionalNoise`, truncated GL difference, L = 1000), one
generator per axis, ``sigma_w`` set so the stationary output has the configured standard
deviation (:func:`stationary_gain`); the defaults (the paper's order, variance and initial bias)
are in docs/portenta_link.md. The helium effect (:class:`HeliumTransient`) is a delayed
first-order bias rise ``A (1 - exp(-(t - delay) / tau))`` for ``t > delay`` (paper 000 Fig. 3);
the temperature moves linearly and leaks into the bias, or with ``thermal`` comes from
:mod:`gyro_noise_ros.thermal.simulate` (docs/thermal_data.md).

Determinism: every random stream (per gyro axis, accelerometer, temperature) is a child of the
``rng`` given, one draw per sample, so sample k does not depend on batch sizes, pacing, the
connection or the faults (:class:`FaultInjector` has its own generator). Sensor FIFO overruns
(:meth:`BoardModel.sensor_overrun`) consume sample slots without a ``seq``: the truth
(:class:`Truth`, :func:`truth_records`) is then matched by ``seq``, not by position.
"""

from collections.abc import Sequence
from dataclasses import dataclass
import os
from typing import Any, Protocol, TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from . import lsm6dso32 as lsm
from .protocol import (
    Ack,
    ACK_OK,
    Decoder,
    encode_ack,
    FLAG_FIFO_OVERRUN,
    FLAG_SAMPLE_LOST,
    LinkStats,
    NAK_BAD_ACCEL_FS,
    NAK_BAD_GYRO_FS,
    NAK_BAD_ODR,
    SAMPLE_DTYPE,
)
from ..core.fractional import DEFAULT_MEMORY, gl_coefficients
from ..core.simulate import FractionalNoise, require_stable
from ..errors import ParameterError
from ..units import DEG_TO_RAD, STANDARD_GRAVITY_M_S2

if TYPE_CHECKING:  # for annotations only: the link does not import these at run time
    from ..calibration.emulate import Scenario
    from ..thermal.simulate import ThermalStream


class _NoiseSource(Protocol):
    """A streaming noise generator, e.g. :class:`.core.simulate.FractionalNoise` (rad/s)."""

    def generate(self, n: int) -> np.ndarray:
        """Return the next ``n`` samples."""
        ...


#: Paper 000 Table 4, reference sequence: mean noise variance 0.003414 (deg/s)^2.
PAPER_NOISE_STD_DPS = float(np.sqrt(0.003414))
DEFAULT_ALPHA = 1.4
DEFAULT_F = -1.2
DEFAULT_BIAS_DPS = (0.775, -0.35, 0.25)
#: Accelerometer noise density (ug/sqrt(Hz)), LSM6DSO family typical in high-performance mode.
ACCEL_NOISE_DENSITY_UG_RTHZ = 70.0


def stationary_gain(alpha: float, f: float, memory: int = DEFAULT_MEMORY) -> float:
    """
    Return the output standard deviation of eq. (2) per unit source-noise standard deviation.

    Parameters
    ----------
    alpha, f : float
        Order and noise parameter of paper 000 eq. (2).
    memory : int
        L of eq. (5).

    Returns
    -------
    float
        sqrt(sum_k h_k^2) with h the impulse response of w -> v, by Parseval:
        sum h^2 = mean over a dense unit-circle grid of 1 / |A(e^{i w})|^2,
        A(z) = 1 + (c_1 - f) z^-1 + sum_{j>=2} c_j z^-j (exact up to aliasing of h beyond the grid
        size).

    """
    require_stable(alpha, f, memory)
    a = gl_coefficients(alpha, memory).copy()
    a[1] -= f
    spectrum = np.fft.rfft(a, 1 << 17)
    inv = 1.0 / (spectrum.real ** 2 + spectrum.imag ** 2)
    # rfft holds bins 0..M/2: interior bins count twice in the full-circle mean
    total = inv[0] + inv[-1] + 2.0 * inv[1:-1].sum()
    return float(np.sqrt(total / (1 << 17)))


@dataclass(frozen=True)
class HeliumTransient:
    """
    Delayed first-order rise of the gyro bias (helium-like).

    Attributes
    ----------
    amplitude_dps : float or tuple of 3 floats
        Final bias change (deg/s), per axis or common.
    delay_s : float
        Time before the rise starts (s).
    tau_s : float
        Time constant of the rise (s).

    """

    amplitude_dps: float | tuple[float, float, float] = 3.5
    delay_s: float = 5400.0
    tau_s: float = 7200.0


@dataclass(frozen=True)
class Vibration:
    """
    Sinusoidal vibration seen by the gyro (and optionally the accelerometer).

    Attributes
    ----------
    frequency_hz : float
        Vibration frequency (Hz).
    amplitude_dps : float or tuple of 3 floats
        Rate amplitude (deg/s).
    accel_amplitude_g : float or tuple of 3 floats
        Specific-force amplitude (g).
    phase_rad : float
        Phase at t = 0 (rad).

    """

    frequency_hz: float = 50.0
    amplitude_dps: float | tuple[float, float, float] = 1.0
    accel_amplitude_g: float | tuple[float, float, float] = 0.0
    phase_rad: float = 0.0


@dataclass(frozen=True)
class Truth:
    """
    What the emulated sensor saw, before quantisation, for a batch of samples.

    Attributes
    ----------
    seq : numpy.ndarray
        uint32 sequence numbers (as sent).
    time_s : numpy.ndarray
        True time since power-on (s).
    gyro_rad_s : numpy.ndarray
        (n, 3) true angular rate (rad/s).
    accel_m_s2 : numpy.ndarray
        (n, 3) true specific force (m/s^2).
    temperature_c : numpy.ndarray
        (n,) true die temperature (degC).
    gyro_fs_dps, accel_fs_g : int
        Full scales the batch was quantised with.

    """

    seq: np.ndarray
    time_s: np.ndarray
    gyro_rad_s: np.ndarray
    accel_m_s2: np.ndarray
    temperature_c: np.ndarray
    gyro_fs_dps: int
    accel_fs_g: int


def _vec3(name: str, value: npt.ArrayLike) -> NDArray[np.float64]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f'{name} must be finite, got {value!r}')
    return arr


class BoardModel:
    """
    The emulated board: sample generation at the configured ODR and full scales, command handling.

    Parameters
    ----------
    rng : numpy.random.Generator, keyword-only
        Parent of all random streams of the model.
    odr_hz : float, keyword-only
        Power-on output data rate (Hz), one of ``lsm6dso32.ODRS_HZ``.
    gyro_fs_dps, accel_fs_g : int, keyword-only
        Power-on full scales (deg/s, g).
    alpha, f : float, keyword-only
        Fractional noise model of paper 000 eq. (2).
    noise_std_dps : float, keyword-only
        Stationary standard deviation of the gyro noise (deg/s); ignored when ``sigma_w_dps`` is
        given.
    sigma_w_dps : float, optional, keyword-only
        Source-noise standard deviation of eq. (2) (deg/s).
    memory : int, keyword-only
        L of eq. (5).
    bias_dps : float or 3 floats, keyword-only
        Constant gyro bias (deg/s).
    accel_g : 3 floats, keyword-only
        Static specific force (g); (0, 0, 1) is the board lying flat (REP-103: +1 g up).
    accel_noise_ug_rthz : float, keyword-only
        Accelerometer white-noise density (ug/sqrt(Hz)) over ODR/2.
    temperature_c : float, keyword-only
        Die temperature at power-on (degC).
    temp_drift_c_per_h : float, keyword-only
        Linear temperature change (degC/h).
    temp_sensitivity_dps_per_c : float or 3 floats, keyword-only
        Gyro bias change per degC away from the power-on temperature (deg/s/degC).
    helium : HeliumTransient, optional, keyword-only
    vibration : Vibration, optional, keyword-only
    clock_ppm : float, keyword-only
        Board clock error (ppm): device microseconds run fast by this much against true time.
    seq0 : int, keyword-only
        Sequence number of the first sample (uint32; wrap tests start near 2**32).
    t0_us : int, keyword-only
        Device time of power-on (us, uint32).
    noise : sequence of 3 objects with ``generate(n)``, optional, keyword-only
        Replaces the fractional generators (output in rad/s).
    thermal : gyro_noise_ros.thermal.simulate.ThermalStream, optional, keyword-only
        Thermal model (oven, die lag, bias law, temperature sensor noise and LSB); replaces the
        linear temperature ramp and ``temp_sensitivity_dps_per_c``; its bias adds to ``bias_dps``.
    scenario : object with ``apply(t_s, gyro, accel)`` and ``skip(n)``, optional, keyword-only
        Reliability-procedure scenario (:class:`gyro_noise_ros.calibration.emulate.Scenario`):
        adds motion seen through sensor errors to the samples before quantisation.

    """

    def __init__(self, *, rng: np.random.Generator, odr_hz: float = 6667.0,
                 gyro_fs_dps: int = 2000, accel_fs_g: int = 4, alpha: float = DEFAULT_ALPHA,
                 f: float = DEFAULT_F, noise_std_dps: float = PAPER_NOISE_STD_DPS,
                 sigma_w_dps: float | None = None, memory: int = DEFAULT_MEMORY,
                 bias_dps: npt.ArrayLike = DEFAULT_BIAS_DPS,
                 accel_g: npt.ArrayLike = (0.0, 0.0, 1.0),
                 accel_noise_ug_rthz: float = ACCEL_NOISE_DENSITY_UG_RTHZ,
                 temperature_c: float = 25.0, temp_drift_c_per_h: float = 0.0,
                 temp_sensitivity_dps_per_c: npt.ArrayLike = 0.0,
                 helium: HeliumTransient | None = None, vibration: Vibration | None = None,
                 clock_ppm: float = 0.0, seq0: int = 0, t0_us: int = 0,
                 noise: Sequence[_NoiseSource] | None = None, scenario: 'Scenario | None' = None,
                 thermal: 'ThermalStream | None' = None) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ParameterError(f'rng must be a numpy.random.Generator, got {type(rng).__name__}')
        self.odr_hz = lsm.check_odr(odr_hz)
        self.gyro_fs_dps = lsm.check_gyro_fs(gyro_fs_dps)
        self.accel_fs_g = lsm.check_accel_fs(accel_fs_g)
        streams = rng.spawn(5)
        self._accel_rng, self._temp_rng = streams[3], streams[4]
        if noise is None:
            if sigma_w_dps is None:
                if not (np.isfinite(noise_std_dps) and noise_std_dps >= 0):
                    raise ParameterError(
                        f'noise_std_dps must be finite and >= 0, got {noise_std_dps}')
                sigma_w_dps = noise_std_dps / stationary_gain(alpha, f, memory)
            self.sigma_w_rad_s = float(sigma_w_dps) * DEG_TO_RAD
            noise = [FractionalNoise(alpha, f, self.sigma_w_rad_s, rng=streams[i], memory=memory)
                     for i in range(3)]
        elif len(noise) != 3:
            raise ParameterError(f'noise must hold 3 generators, got {len(noise)}')
        self._noise = list(noise)
        self.bias_rad_s = _vec3('bias_dps', bias_dps) * DEG_TO_RAD
        self.accel_m_s2 = _vec3('accel_g', accel_g) * STANDARD_GRAVITY_M_S2
        if not (np.isfinite(accel_noise_ug_rthz) and accel_noise_ug_rthz >= 0):
            raise ParameterError(
                f'accel_noise_ug_rthz must be finite and >= 0, got {accel_noise_ug_rthz}')
        self.accel_noise_ug_rthz = float(accel_noise_ug_rthz)
        self.temperature0_c = float(temperature_c)
        self.temp_drift_c_per_s = float(temp_drift_c_per_h) / 3600.0
        self.temp_sens_rad_s_per_c = _vec3('temp_sensitivity_dps_per_c',
                                           temp_sensitivity_dps_per_c) * DEG_TO_RAD
        self.helium = helium
        self.vibration = vibration
        self.thermal = thermal
        if helium is not None and not (helium.tau_s > 0 and helium.delay_s >= 0):
            raise ParameterError(f'helium needs tau_s > 0 and delay_s >= 0, got {helium}')
        if vibration is not None and not vibration.frequency_hz >= 0:
            raise ParameterError(
                f'vibration frequency_hz must be >= 0, got {vibration.frequency_hz}')
        if not (np.isfinite(clock_ppm) and abs(clock_ppm) < 1e5):
            raise ParameterError(
                f'clock_ppm must be finite and |clock_ppm| < 1e5, got {clock_ppm}')
        self.clock_ppm = float(clock_ppm)
        self.seq = int(seq0) % (1 << 32)
        self.t0_us = int(t0_us) % (1 << 32)
        self.samples_generated = 0
        self._seg_start_s = 0.0    # true time of the first sample since the last ODR change
        self._seg_index = 0        # samples since the last ODR change
        self._decoder = Decoder()
        self.last_truth: Truth | None = None
        # (samples_generated at the change, Ack)
        self.config_changes: list[tuple[int, Ack]] = []
        self.samples_overrun = 0
        self._fifo_overrun = False
        self.scenario = scenario

    @property
    def time_s(self) -> float:
        """float: true time of the next sample (s since power-on)."""
        return self._seg_start_s + self._seg_index / self.odr_hz

    def configure(self, *, command_id: int, odr_hz: float, gyro_fs_dps: int,
                  accel_fs_g: int) -> Ack:
        """
        Apply a configuration as the firmware would, or refuse it.

        Parameters
        ----------
        command_id : int
            Id of the CONFIGURE command, echoed in the acknowledgement.
        odr_hz : float
            Requested ODR (Hz).
        gyro_fs_dps, accel_fs_g : int
            Requested full scales (deg/s, g).

        Returns
        -------
        Ack
            ok with the new configuration, or a NAK naming the bad value (configuration unchanged).

        """
        checks = ((NAK_BAD_ODR, lsm.check_odr, odr_hz),
                  (NAK_BAD_GYRO_FS, lsm.check_gyro_fs, gyro_fs_dps),
                  (NAK_BAD_ACCEL_FS, lsm.check_accel_fs, accel_fs_g))
        values: list[Any] = []
        for code, check, value in checks:
            try:
                values.append(check(value))
            except ParameterError as err:
                return Ack(command_id=command_id, ok=False, odr_hz=self.odr_hz,
                           gyro_fs_dps=self.gyro_fs_dps, accel_fs_g=self.accel_fs_g,
                           message=str(err)[:64], status=code)
        odr, gyro_fs, accel_fs = values
        if odr != self.odr_hz:
            self._seg_start_s = self.time_s
            self._seg_index = 0
        self.odr_hz, self.gyro_fs_dps, self.accel_fs_g = odr, gyro_fs, accel_fs
        ack = Ack(command_id=command_id, ok=True, odr_hz=odr, gyro_fs_dps=gyro_fs,
                  accel_fs_g=accel_fs, message='', status=ACK_OK)
        self.config_changes.append((self.samples_generated, ack))
        return ack

    def handle_bytes(self, data: bytes) -> bytes:
        """
        Feed bytes received from the host; answer every CONFIGURE command.

        Parameters
        ----------
        data : bytes
            Bytes received from the host.

        Returns
        -------
        bytes
            Encoded ACK/NAK frames (empty when no complete command arrived).

        """
        result = self._decoder.feed(data)
        out = []
        for cmd in result.commands:
            out.append(encode_ack(self.configure(command_id=cmd.command_id, odr_hz=cmd.odr_hz,
                                                 gyro_fs_dps=cmd.gyro_fs_dps,
                                                 accel_fs_g=cmd.accel_fs_g)))
        return b''.join(out)

    @property
    def command_stats(self) -> LinkStats:
        """LinkStats: counters of the board's command decoder."""
        return self._decoder.stats

    def sensor_overrun(self, k: int) -> None:
        """
        Let the sensor FIFO overrun: ``k`` samples are produced but never read by the board.

        Time and the noise processes advance by ``k`` samples, ``seq`` does not (the board never
        saw them), and the next sample read carries FLAG_FIFO_OVERRUN. No truth is recorded for
        them.

        Parameters
        ----------
        k : int
            Samples lost inside the sensor (>= 0).

        """
        k = int(k)
        if k <= 0:
            return
        for gen in self._noise:
            gen.generate(k)
        self._accel_rng.standard_normal((k, 3))
        if self.thermal is not None:
            # the die and the sensor move on through samples nobody read
            self.thermal.step(self._seg_start_s + (self._seg_index + np.arange(k)) / self.odr_hz)
            self._temp_rng.standard_normal(k)
        if self.scenario is not None:
            self.scenario.skip(k)
        self._seg_index += k
        self.samples_overrun += k
        self._fifo_overrun = True

    def next_samples(self, n: int) -> NDArray[np.void]:
        """
        Produce the next ``n`` samples; their ground truth is left in :attr:`last_truth`.

        Parameters
        ----------
        n : int
            Number of samples (>= 0).

        Returns
        -------
        numpy.ndarray
            :data:`~gyro_noise_ros.link.protocol.SAMPLE_DTYPE` records, flags 0.

        """
        n = int(n)
        if n < 0:
            raise ParameterError(f'n must be >= 0, got {n}')
        idx = self._seg_index + np.arange(n, dtype=np.float64)
        t = self._seg_start_s + idx / self.odr_hz
        gyro = np.column_stack([gen.generate(n) for gen in self._noise]) + self.bias_rad_s
        if self.thermal is None:
            temp = temp_read = self.temperature0_c + self.temp_drift_c_per_s * t
            gyro += np.outer(temp - self.temperature0_c, self.temp_sens_rad_s_per_c)
        else:
            th = self.thermal.step(t)
            temp = th.die_c
            gyro += th.bias_rad_s
            temp_read = self.thermal.measure_c(temp, self._temp_rng)
        accel = np.broadcast_to(self.accel_m_s2, (n, 3)).copy()
        accel_std = self.accel_noise_ug_rthz * 1e-6 * STANDARD_GRAVITY_M_S2 * np.sqrt(
            self.odr_hz / 2.0)
        accel += self._accel_rng.standard_normal((n, 3)) * accel_std
        if self.thermal is not None:
            accel += th.accel_bias_m_s2
        if self.helium is not None:
            h = self.helium
            rise = np.where(t > h.delay_s, -np.expm1(-(np.maximum(t - h.delay_s, 0.0)) / h.tau_s),
                            0.0)
            gyro += np.outer(rise, _vec3('helium amplitude_dps', h.amplitude_dps) * DEG_TO_RAD)
        if self.vibration is not None:
            v = self.vibration
            s = np.sin(2.0 * np.pi * v.frequency_hz * t + v.phase_rad)
            gyro += np.outer(s, _vec3('vibration amplitude_dps', v.amplitude_dps) * DEG_TO_RAD)
            accel += np.outer(s, _vec3('vibration accel_amplitude_g', v.accel_amplitude_g)
                              * STANDARD_GRAVITY_M_S2)
        if self.scenario is not None:
            gyro, accel = self.scenario.apply(t, gyro, accel)
        out = np.zeros(n, dtype=SAMPLE_DTYPE)
        out['seq'] = (self.seq + np.arange(n, dtype=np.uint64)) % (1 << 32)
        device_us = np.floor(t * 1e6 * (1.0 + self.clock_ppm * 1e-6)).astype(np.int64)
        out['t_us'] = (self.t0_us + device_us) % (1 << 32)
        out['gyro'] = lsm.quantise(gyro, lsm.gyro_sensitivity_rad_s_per_lsb(self.gyro_fs_dps))
        out['accel'] = lsm.quantise(accel, lsm.accel_sensitivity_m_s2_per_lsb(self.accel_fs_g))
        out['temp'] = lsm.quantise(temp_read - lsm.TEMPERATURE_OFFSET_C,
                                   1.0 / lsm.TEMPERATURE_LSB_PER_C)
        if self._fifo_overrun and n:
            out['flags'][0] |= FLAG_FIFO_OVERRUN
            self._fifo_overrun = False
        self.last_truth = Truth(seq=out['seq'].copy(), time_s=t, gyro_rad_s=gyro, accel_m_s2=accel,
                                temperature_c=temp, gyro_fs_dps=self.gyro_fs_dps,
                                accel_fs_g=self.accel_fs_g)
        self.seq = (self.seq + n) % (1 << 32)
        self._seg_index += n
        self.samples_generated += n
        return out


@dataclass(frozen=True)
class FaultCounts:
    """
    What a :class:`FaultInjector` did (the exact numbers a decoder must report).

    Attributes
    ----------
    dropped_flagged : int
        Samples dropped with the next kept sample flagged FLAG_SAMPLE_LOST.
    dropped_unflagged : int
        Samples dropped silently (only the counter gap shows them).
    bytes_corrupted : int
        Bytes XOR-ed with a random non-zero value.
    visible_lost : int
        Dropped samples followed by a kept sample and preceded by one (what a decoder of the kept
        samples reports as ``samples_lost``).
    visible_flagged_lost : int
        Of those, the ones in runs before a flagged sample (the decoder's
        ``samples_flagged_lost``).
    fifo_overruns : int
        Sensor FIFO overrun events injected (:meth:`FaultInjector.overrun`).
    fifo_overrun_samples : int
        Samples lost inside the sensor by them (invisible to ``seq``).

    """

    dropped_flagged: int = 0
    dropped_unflagged: int = 0
    bytes_corrupted: int = 0
    visible_lost: int = 0
    visible_flagged_lost: int = 0
    fifo_overruns: int = 0
    fifo_overrun_samples: int = 0


class FaultInjector:
    """
    Board-side sample loss and transport corruption, seeded, independent of the sample streams.

    Parameters
    ----------
    rng : numpy.random.Generator
    drop_flagged_rate : float, keyword-only
        Probability that a sample is dropped by the "board" that knows it (flags the next sample).
    drop_unflagged_rate : float, keyword-only
        Probability that a sample vanishes unnoticed by the board.
    corrupt_rate : float, keyword-only
        Probability that a transmitted byte is corrupted.
    fifo_overrun_rate : float, keyword-only
        Probability per sample slot that the sensor FIFO overruns (see :meth:`overrun`).

    Notes
    -----
    A dropped run is flagged when any sample in it was a flagged drop, so the flagged count is the
    sum of the gaps before flagged samples, which is what the decoder reports as
    ``samples_flagged_lost``. Drops at the very end of a stream (no later sample) are counted but
    invisible to a decoder. The flags of dropped samples (FIFO_OVERRUN) are OR-ed into the next
    sample kept, as the firmware must.

    """

    def __init__(self, rng: np.random.Generator, *, drop_flagged_rate: float = 0.0,
                 drop_unflagged_rate: float = 0.0, corrupt_rate: float = 0.0,
                 fifo_overrun_rate: float = 0.0) -> None:
        for name, value in (
            ('drop_flagged_rate', drop_flagged_rate),
            ('drop_unflagged_rate', drop_unflagged_rate),
            ('corrupt_rate', corrupt_rate),
            ('fifo_overrun_rate', fifo_overrun_rate),
        ):
            if not 0.0 <= value < 1.0:
                raise ParameterError(f'{name} must be in [0, 1), got {value}')
        if drop_flagged_rate + drop_unflagged_rate >= 1.0:
            raise ParameterError('drop_flagged_rate + drop_unflagged_rate must be < 1, got '
                                 f'{drop_flagged_rate + drop_unflagged_rate}')
        self.rng = rng
        self.drop_flagged_rate = float(drop_flagged_rate)
        self.drop_unflagged_rate = float(drop_unflagged_rate)
        self.corrupt_rate = float(corrupt_rate)
        self.fifo_overrun_rate = float(fifo_overrun_rate)
        # flags of dropped samples still to be OR-ed into the next kept one
        self._pending_carry = 0
        self._pending_flag = False
        self._pending_run = 0
        self._c = dict.fromkeys(FaultCounts.__dataclass_fields__, 0)
        self._seen_kept = False

    @property
    def counts(self) -> FaultCounts:
        """FaultCounts: what has been injected so far."""
        return FaultCounts(**self._c)

    def overrun(self, n: int) -> int:
        """
        Decide whether the sensor FIFO overruns before the next ``n`` sample slots.

        Parameters
        ----------
        n : int
            Sample slots about to be read.

        Returns
        -------
        int
            Samples (0 .. n-1, at most 32) the sensor loses first; give them to
            :meth:`BoardModel.sensor_overrun` and read only the rest.

        """
        if self.fifo_overrun_rate == 0 or n < 2:
            return 0
        if self.rng.random() >= 1.0 - (1.0 - self.fifo_overrun_rate) ** n:
            return 0
        k = int(min(n - 1, int(self.rng.integers(1, 33))))
        self._c['fifo_overruns'] += 1
        self._c['fifo_overrun_samples'] += k
        return k

    def note_lost(self, n: int, *, flagged: bool = True, carry_flags: int = 0) -> None:
        """
        Record ``n`` samples lost outside the injector (e.g. transmit buffer full).

        Flag the next sample.

        The samples must be consecutive with the ones given to :meth:`drop` (they are counted in
        the ``visible_*`` counts once a later sample is kept).

        Parameters
        ----------
        n : int
            Number of samples lost.
        flagged : bool, keyword-only
            Whether the board flags the loss in the next frame.
        carry_flags : int, keyword-only
            OR of the lost samples' flags, carried into the next sample kept.

        """
        if n > 0:
            self._pending_flag = self._pending_flag or flagged
            self._pending_run += n
            self._pending_carry |= int(carry_flags) & FLAG_FIFO_OVERRUN

    def drop(self, samples: NDArray[np.void]) -> NDArray[np.void]:
        """
        Drop samples at the configured rates and flag the sample after each flagged loss.

        Parameters
        ----------
        samples : numpy.ndarray
            SAMPLE_DTYPE records (not modified).

        Returns
        -------
        numpy.ndarray
            The kept samples (a copy).

        """
        n = samples.size
        if n == 0:
            return samples.copy()
        if (
            self.drop_flagged_rate == 0
            and self.drop_unflagged_rate == 0
            and not self._pending_flag
            and not self._pending_run
            and not self._pending_carry
        ):
            self._seen_kept = True
            return samples.copy()
        u = self.rng.random(n)
        flagged = u < self.drop_flagged_rate
        unflagged = (u >= self.drop_flagged_rate) & (u < self.drop_flagged_rate
                                                     + self.drop_unflagged_rate)
        self._c['dropped_flagged'] += int(flagged.sum())
        self._c['dropped_unflagged'] += int(unflagged.sum())
        kept = samples[~(flagged | unflagged)].copy()
        # for every kept sample: was any sample in the dropped run just before it a flagged drop?
        pending = self._pending_flag
        kept_pos = np.flatnonzero(~(flagged | unflagged))
        if kept_pos.size:
            fl_cum = np.concatenate(([0], np.cumsum(flagged)))
            prev_kept = np.concatenate(([-1], kept_pos[:-1]))
            run_has_flag = (fl_cum[kept_pos] - fl_cum[prev_kept + 1]) > 0
            run_has_flag[0] = run_has_flag[0] or pending
            kept['flags'][run_has_flag] |= FLAG_SAMPLE_LOST
            dropped_overrun = ((samples['flags'] & FLAG_FIFO_OVERRUN) != 0) & (flagged | unflagged)
            ov_cum = np.concatenate(([0], np.cumsum(dropped_overrun)))
            carry = (ov_cum[kept_pos] - ov_cum[prev_kept + 1]) > 0
            carry[0] = carry[0] or bool(self._pending_carry)
            kept['flags'][carry] |= FLAG_FIFO_OVERRUN
            runs = kept_pos - prev_kept - 1
            runs[0] += self._pending_run
            if not self._seen_kept:
                runs[0] = 0
            self._seen_kept = True
            self._c['visible_lost'] += int(runs.sum())
            self._c['visible_flagged_lost'] += int(runs[run_has_flag].sum())
            tail = slice(kept_pos[-1] + 1, n)
            self._pending_flag = bool(flagged[tail].any())
            self._pending_run = int((flagged | unflagged)[tail].sum())
            self._pending_carry = FLAG_FIFO_OVERRUN if dropped_overrun[tail].any() else 0
        else:
            self._pending_flag = pending or bool(flagged.any())
            self._pending_run += n
            if np.any(samples['flags'] & FLAG_FIFO_OVERRUN):
                self._pending_carry = FLAG_FIFO_OVERRUN
        return kept

    def corrupt(self, data: bytes) -> bytes:
        """
        Corrupt bytes at the configured rate.

        Parameters
        ----------
        data : bytes
            Bytes about to be sent on the link.

        Returns
        -------
        bytes

        """
        if self.corrupt_rate == 0 or not data:
            return data
        arr = np.frombuffer(data, dtype=np.uint8).copy()
        hit = np.flatnonzero(self.rng.random(arr.size) < self.corrupt_rate)
        if hit.size:
            arr[hit] ^= self.rng.integers(1, 256, hit.size, dtype=np.uint8)
            self._c['bytes_corrupted'] += int(hit.size)
        return arr.tobytes()


#: Ground-truth record written by ``portenta_emulator --truth-out`` (little-endian, packed, 64
#: bytes).
TRUTH_DTYPE = np.dtype([
    ('seq', '<u4'),
    ('gyro_fs_dps', '<u2'),
    ('accel_fs_g', '<u1'),
    ('reserved', '<u1'),
    ('time_s', '<f8'),
    ('gyro_rad_s', '<f8', (3,)),
    ('accel_m_s2', '<f8', (3,)),
])


def truth_records(truth: Truth) -> NDArray[np.void]:
    """
    Pack a :class:`Truth` into TRUTH_DTYPE records (temperature, exact in the raw word, left out).

    Parameters
    ----------
    truth : Truth
        The emulator's ground truth.

    Returns
    -------
    numpy.ndarray

    """
    rec = np.zeros(truth.seq.size, dtype=TRUTH_DTYPE)
    rec['seq'] = truth.seq
    rec['gyro_fs_dps'] = truth.gyro_fs_dps
    rec['accel_fs_g'] = truth.accel_fs_g
    rec['time_s'] = truth.time_s
    rec['gyro_rad_s'] = truth.gyro_rad_s
    rec['accel_m_s2'] = truth.accel_m_s2
    return rec


def read_truth(path: str | os.PathLike[str]) -> NDArray[np.void]:
    """
    Read a ``--truth-out`` file (complete records only, so it can be read while the emulator runs).

    Parameters
    ----------
    path : str
        Truth file written by the emulator.

    Returns
    -------
    numpy.ndarray
        TRUTH_DTYPE records, one per generated sample (sent or not), in order.

    """
    with open(path, 'rb') as fh:
        data = fh.read()
    usable = len(data) - len(data) % TRUTH_DTYPE.itemsize
    return np.frombuffer(data[:usable], dtype=TRUTH_DTYPE).copy()
