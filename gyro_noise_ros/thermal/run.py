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
The data a thermal method is fitted on and applied to, and the protocol every method follows.

A :class:`ThermalRun` is one static recording: gyro samples with their stamps and the die
temperature interpolated onto the same stamps. Every method (the paper's parallel model and each
baseline) implements :class:`ThermalMethod`: fitted on one run, applied to another (never the same
one when it is scored), serialised to a JSON-able dict for ``model.json``. Causal methods can
also give the gyro offset as a function of temperature and its rate, which is what the live
compensation node evaluates.
"""

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class ThermalRun:
    """
    One recording for thermal fitting or evaluation.

    Attributes
    ----------
    t_s : numpy.ndarray
        Sample times (n,), seconds, strictly increasing.
    gyro_rad_s : numpy.ndarray
        Angular rate (n, 3), rad/s, sensor frame.
    temperature_c : numpy.ndarray
        Die temperature (n,), degC, interpolated onto ``t_s``.
    rate_hz : float
        Sample rate, Hz.
    name : str
        Label for reports (file name or seed).

    """

    t_s: np.ndarray
    gyro_rad_s: np.ndarray
    temperature_c: np.ndarray
    rate_hz: float
    name: str = ''


@runtime_checkable
class ThermalMethod(Protocol):
    """
    What every thermal compensation or denoising method provides.

    ``name`` is the ``--method`` value; ``causal`` says whether ``apply`` uses only past
    samples (only causal methods may run live). ``fit`` learns from one run; ``apply`` returns
    the processed angular rate (n, 3) in rad/s for another. ``to_dict``/``from_dict`` round-trip
    every fitted parameter through JSON. Causal methods also implement
    ``drift_rad_s(temperature_c, dtemp_c_s) -> (n, 3)``: the gyro offset to subtract, used live.
    """

    name: str
    causal: bool

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Learn the method's parameters from one run."""

    def apply(self, run: ThermalRun) -> np.ndarray:
        """Return the processed angular rate (n, 3), rad/s."""

    def to_dict(self) -> dict:
        """Return every fitted parameter as a JSON-serialisable dict."""
