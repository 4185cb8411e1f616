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
What the data allow: least squares on the simulator's own drift terms (the oracle).

A thermal method is scored on a held-out run by the drift it leaves; that number alone does not
say whether a method is poor or the run hard. The oracle answers "how well could any method do
with these data": the gyro output of the *training* run is regressed (per axis, ordinary least
squares) on the seven terms of the simulator's drift law (:meth:`ThermalModel.bias_terms`:
``1, d, d^2, d^3, knee, dT/dt, z - T``), and the fitted coefficients are applied to the test
run's terms. Two versions:

- **true terms** (:func:`true_terms`): the die's true temperature, rate and hysteresis state
  from the simulation truth. Only the noise and the training run's own limits stand between it
  and the drift; methods are reported as a ratio to it.
- **measured terms** (:func:`measured_terms`): the same basis computed from what a method sees,
  the measured temperature (sensor noise, LSB, 52-Hz readings interpolated) and its causal
  trailing-window slope (:func:`~gyro_noise_ros.thermal.run.temperature_rate_c_s`, the rate
  every method uses), the hysteresis state played on the measured temperature. The gap between
  the two is what measuring T and dT costs.

The oracle knows the form of the law (the knee's centre and width, the play's half-width); only
the seven coefficients per axis are fitted. It is a yardstick for the simulator, not a method:
real data have no truth.
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .hysteresis import play_operator
from .run import DEFAULT_RATE_WINDOW_S, temperature_rate_c_s, ThermalRun
from .simulate import ThermalModel, ThermalTruth
from ..errors import ParameterError

__all__ = ['LeastSquaresOracle', 'fit_oracle', 'measured_terms', 'oracle_residual',
           'true_terms']


def true_terms(truth: ThermalTruth, model: ThermalModel) -> NDArray[np.float64]:
    """
    Return the (n, 7) drift-law terms (:attr:`ThermalModel.TERMS`) of a simulated run's truth.

    :meth:`ThermalModel.bias_terms` of the die temperature, its natural-time rate and the
    hysteresis state of ``truth``, for the device ``model``.

    """
    return model.bias_terms(truth.die_c, np.asarray(truth.die_rate_c_s) / truth.compress,
                            truth.played_c)


def measured_terms(run: ThermalRun, model: ThermalModel, *, compress: float,
                   rate_window_s: float = DEFAULT_RATE_WINDOW_S) -> NDArray[np.float64]:
    """
    Return the drift-law terms computed from the measured temperature only.

    T is ``run.temperature_c``; dT its causal trailing-window slope (start-up backfilled, as
    every method gets it) divided by the compression (the law's rate is in uncompressed time; a
    constant factor, which least squares absorbs anyway); z the play operator of the model's
    half-width on the measured T.

    Parameters
    ----------
    run : ThermalRun
        The run.
    model : ThermalModel
        The device (knee, reference temperature, play half-width).
    compress : float, keyword-only
        The run's time compression.
    rate_window_s : float, keyword-only
        Window of the temperature rate (s).

    Returns
    -------
    numpy.ndarray
        (n, 7).

    """
    temp = np.asarray(run.temperature_c, dtype=float)
    rate = temperature_rate_c_s(run.t_s, temp, window_s=rate_window_s) / float(compress)
    played = play_operator(temp, float(model.hysteresis_half_width_c))
    return model.bias_terms(temp, rate, played)


@dataclass(frozen=True)
class LeastSquaresOracle:
    """
    Per-axis least-squares coefficients on a fixed basis.

    Attributes
    ----------
    coef : numpy.ndarray
        (k, 3) coefficients, output unit per unit of each column.
    scale : numpy.ndarray
        (k,) the column scales used for conditioning (already folded into ``coef``).
    rank : int
        Rank of the (scaled) training design; below k when a term never varied in training
        (e.g. no hysteresis), and then the minimum-norm solution is used.

    """

    coef: np.ndarray
    scale: np.ndarray
    rank: int

    def predict(self, terms: ArrayLike) -> NDArray[np.float64]:
        """Return the fitted drift (n, 3) at the rows of ``terms`` (n, k)."""
        return np.asarray(terms, dtype=float) @ self.coef


def fit_oracle(terms: ArrayLike, output: ArrayLike) -> LeastSquaresOracle:
    """
    Fit :class:`LeastSquaresOracle` (ordinary least squares per axis, columns scaled to rms 1).

    Parameters
    ----------
    terms : array_like
        (n, k) training terms.
    output : array_like
        (n, 3) training output (e.g. gyro, rad/s).

    Returns
    -------
    LeastSquaresOracle

    """
    a = np.asarray(terms, dtype=float)
    y = np.asarray(output, dtype=float)
    if a.ndim != 2 or y.ndim != 2 or a.shape[0] != y.shape[0] or a.shape[0] < a.shape[1]:
        raise ParameterError(f'fit_oracle needs (n, k) terms and (n, m) output with n >= k, got '
                             f'{a.shape} and {y.shape}')
    scale = np.sqrt(np.mean(a * a, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    sol, _, rank, _ = np.linalg.lstsq(a / scale, y, rcond=None)
    return LeastSquaresOracle(coef=sol / scale[:, None], scale=scale, rank=int(rank))


def oracle_residual(train_run: ThermalRun, train_truth: ThermalTruth, test_run: ThermalRun,
                    test_truth: ThermalTruth, model: ThermalModel, *, measured: bool = False,
                    rate_window_s: float = DEFAULT_RATE_WINDOW_S) -> NDArray[np.float64]:
    """
    Fit the oracle on the training run and return the test run's gyro minus its prediction.

    Parameters
    ----------
    train_run, test_run : ThermalRun
        The two simulated runs.
    train_truth, test_truth : ThermalTruth
        Their truths (for the true terms and the compression).
    model : ThermalModel
        The simulated device.
    measured : bool, keyword-only
        Use :func:`measured_terms` instead of :func:`true_terms`.
    rate_window_s : float, keyword-only
        Window of the measured rate (s).

    Returns
    -------
    numpy.ndarray
        (n_test, 3) compensated test gyro, rad/s (the same quantity a causal method's
        ``apply`` returns).

    """
    if measured:
        a_train = measured_terms(train_run, model, compress=train_truth.compress,
                                 rate_window_s=rate_window_s)
        a_test = measured_terms(test_run, model, compress=test_truth.compress,
                                rate_window_s=rate_window_s)
    else:
        a_train = true_terms(train_truth, model)
        a_test = true_terms(test_truth, model)
    oracle = fit_oracle(a_train, train_run.gyro_rad_s)
    return np.asarray(test_run.gyro_rad_s, dtype=float) - oracle.predict(a_test)
