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
The registry of thermal methods, the ``model.json`` file and the trained-range check.

Every ``--method`` name maps to a class implementing
:class:`~gyro_noise_ros.thermal.run.ThermalMethod` plus a ``from_dict(d)`` classmethod (the
inverse of ``to_dict``). The built-in classes are imported lazily by module and class name, so a
method whose module is missing or broken fails with one clear :class:`MethodUnavailableError`
naming it, while the others still work. :func:`register_method` adds a class at run time (tests,
user plug-ins).

``model.json`` (format version 2; version 1 is still read) holds the method name, every fitted
parameter (the method's ``to_dict()`` under ``parameters``), the accelerometer's polynomial
(``accel``, when the training bags had accelerometer data) and what the model was trained on
(temperature and temperature-rate range, sample rate, source names): :func:`save_model` /
:func:`load_model`. :func:`check_temperature_range` refuses to apply a model more than
``margin_c`` (default :data:`DEFAULT_RANGE_MARGIN_C`) outside the temperatures it was trained on:
every data-driven drift model extrapolates badly, a third-order polynomial worst of all.
:func:`range_report` counts the samples outside the trained range of T and of dT, which each
method treats as its ``out_of_range`` attribute says.
"""

from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
import datetime
import importlib
import json
import math
from pathlib import Path
from typing import Any, TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .run import (check_temperature_readings, DEFAULT_RATE_WINDOW_S, temperature_rate_c_s,
                  ThermalMethod, ThermalRun)
from .. import __version__
from ..errors import GyroNoiseError, InputDataError, ParameterError
from ..outputs import atomic_write_text, StrPath

if TYPE_CHECKING:
    from .baselines import TemperaturePolynomial

__all__ = ['BUILTIN_METHODS', 'DEFAULT_METHOD', 'DEFAULT_MIN_RANGE_C', 'DEFAULT_RANGE_MARGIN_C',
           'MAX_OUTSIDE_SHARE', 'MAX_SENSOR_OFFSET_DEG_S', 'MODEL_FORMAT', 'MODEL_FORMAT_VERSION',
           'MethodUnavailableError', 'ModelFileError', 'RangeReport', 'SensorMismatchError',
           'TemperatureRangeError', 'ThermalModel', 'TrainingInfo', 'accel_view',
           'check_same_sensor', 'check_temperature_range', 'check_trainable', 'fit_accel',
           'fit_method', 'get_method', 'load_model', 'method_class', 'method_names',
           'range_report', 'register_method', 'save_model', 'to_jsonable', 'training_info']

#: The built-in methods: ``--method`` name -> (module, class name). Imported on first use.
BUILTIN_METHODS = {
    'raw': ('gyro_noise_ros.thermal.baselines', 'RawMethod'),
    'poly3': ('gyro_noise_ros.thermal.baselines', 'TemperaturePolynomial'),
    'linear_tdt': ('gyro_noise_ros.thermal.baselines', 'LinearTdT'),
    'lsq_cv': ('gyro_noise_ros.thermal.lsq', 'LeastSquaresCV'),
    'wtd': ('gyro_noise_ros.thermal.baselines', 'WaveletThreshold'),
    'bp': ('gyro_noise_ros.thermal.baselines', 'BPNetwork'),
    'emd_wtd_sabp': ('gyro_noise_ros.thermal.baselines', 'EmdWtdSaBp'),
    'parallel': ('gyro_noise_ros.thermal.parallel', 'ParallelModel'),
}

#: Default ``--method`` of ``gyro_noise_thermal fit``: least squares on a drift basis of the
#: measured T and its 10-s slope, terms by blocked cross-validation on the training run
#: (thermal/lsq.py); the best of the causal, full-bandwidth methods on runs shaped unlike their
#: training run (docs/scripts/thermal_heldout.py; docs/thermal.md, "The default method").
DEFAULT_METHOD = 'lsq_cv'

#: How far (degC) outside the trained temperature range a model may still be applied.
DEFAULT_RANGE_MARGIN_C = 5.0

#: Smallest temperature span (degC) a drift model is fitted on (``fit`` refuses less).
DEFAULT_MIN_RANGE_C = 2.0

#: Largest offset (deg/s, any axis) between a run's gyro and the model's drift at its temperatures
#: before the model is taken for another sensor's: a quarter of the LSM6DSO32's typical zero-rate
#: level (+-1 deg/s), far above a part's turn-on repeatability, so two parts of that type agree
#: within it on all three axes about once in a hundred (uniform levels).
MAX_SENSOR_OFFSET_DEG_S = 0.25

#: Largest share of a run outside the trained range of T or dT applied without a warning
#: (``apply``, ``compare``; above it ``--strict`` makes ``apply`` refuse, exit code 4).
MAX_OUTSIDE_SHARE = 0.05

#: ``format`` and ``format_version`` of model.json.
MODEL_FORMAT = 'gyro_noise_ros.thermal.model'
MODEL_FORMAT_VERSION = 3
#: The format versions :func:`load_model` reads (1: no ``accel``, no ``rate_window_s``; 2: no
#: ``autopilot``).
READABLE_FORMAT_VERSIONS = (1, 2, 3)

_registered: dict[str, type] = {}


class MethodUnavailableError(GyroNoiseError):
    """A ``--method`` name is unknown, or its module cannot be imported (exit code 2)."""

    exit_code = 2


class ModelFileError(GyroNoiseError):
    """A model.json is missing, unreadable or not a model of a known method (exit code 3)."""

    exit_code = 3


class TemperatureRangeError(InputDataError):
    """The data's temperature lies outside the model's trained range plus margin (exit code 4)."""


class SensorMismatchError(InputDataError):
    """The run's gyro sits far from the model's drift: a model of another sensor (exit code 4)."""


def register_method(name: str, cls: type[Any]) -> None:
    """
    Register (or replace) a method class under a ``--method`` name.

    Parameters
    ----------
    name : str
        The name (letters, digits, underscores).
    cls : type
        Class with a no-argument constructor, the :class:`ThermalMethod` attributes and methods,
        and a ``from_dict(d)`` classmethod.

    Raises
    ------
    ParameterError
        Bad name or a class lacking part of the protocol.

    """
    if not isinstance(name, str) or not name or not name.replace('_', '').isalnum():
        raise ParameterError(f'method name must be letters, digits and underscores, got {name!r}')
    missing = [a for a in ('fit', 'apply', 'to_dict', 'from_dict')
               if not callable(getattr(cls, a, None))]
    if missing:
        raise ParameterError(f'method class {cls!r} lacks {", ".join(missing)}')
    _registered[name] = cls


def method_names() -> list[str]:
    """
    List every known method name: the built-ins, then those registered.

    Returns
    -------
    list of str

    """
    return list(BUILTIN_METHODS) + [n for n in _registered if n not in BUILTIN_METHODS]


def method_class(name: str) -> type[Any]:
    """
    Return the class of a method, importing its module on first use.

    Parameters
    ----------
    name : str
        ``--method`` value.

    Returns
    -------
    type

    Raises
    ------
    MethodUnavailableError
        Unknown name, or the module or class cannot be imported (the message says why).

    """
    if name in _registered:
        return _registered[name]
    if name not in BUILTIN_METHODS:
        known = ', '.join(method_names())
        raise MethodUnavailableError(f'unknown method {name!r} (known: {known})')
    module_name, class_name = BUILTIN_METHODS[name]
    try:
        module = importlib.import_module(module_name)
    except ImportError as err:
        raise MethodUnavailableError(f'method {name!r} is not available: module {module_name} '
                                     f'cannot be imported ({err})') from err
    cls = getattr(module, class_name, None)
    if cls is None:
        raise MethodUnavailableError(f'method {name!r} is not available: {module_name} has no '
                                     f'{class_name}')
    return cls


def get_method(name: str, **options: Any) -> ThermalMethod:
    """
    Build an unfitted method.

    Parameters
    ----------
    name : str
        ``--method`` value.
    **options
        Passed to the class's constructor.

    Returns
    -------
    ThermalMethod

    Raises
    ------
    MethodUnavailableError
        See :func:`method_class`.
    ParameterError
        The constructor rejects the options.

    """
    cls = method_class(name)
    try:
        method = cls(**options)
    except TypeError as err:
        raise ParameterError(f'method {name!r} does not take options {sorted(options)}: '
                             f'{err}') from err
    if not isinstance(method, ThermalMethod):
        raise MethodUnavailableError(f'method {name!r}: {cls.__name__} does not implement '
                                     'ThermalMethod')
    return method


@dataclass(frozen=True)
class TrainingInfo:
    """
    What a model was trained on (stored in model.json under ``training``).

    Attributes
    ----------
    temperature_min_c, temperature_max_c : float
        Range of the training temperature (degC).
    temperature_rate_min_c_s, temperature_rate_max_c_s : float or None
        Range of the causal temperature rate (degC/s, :func:`temperature_rate_c_s` over
        filled windows only: no start-up outliers); None when the run is shorter than the
        window.
    rate_hz : float
        Sample rate of the training data (Hz).
    samples : int
        Training samples.
    duration_s : float
        Training duration (s), summed over sources.
    sources : tuple of str
        Names of the recordings trained on.
    rate_window_s : float
        Window of the temperature rate (s).

    """

    temperature_min_c: float
    temperature_max_c: float
    temperature_rate_min_c_s: float | None
    temperature_rate_max_c_s: float | None
    rate_hz: float
    samples: int
    duration_s: float
    sources: tuple
    rate_window_s: float = DEFAULT_RATE_WINDOW_S

    def as_dict(self) -> dict[str, Any]:
        """
        Return the JSON form.

        Returns
        -------
        dict

        """
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out['sources'] = list(self.sources)
        return out


def training_info(run: ThermalRun, *, sources: Sequence[str] | None = None,
                  rate_window_s: float = DEFAULT_RATE_WINDOW_S) -> TrainingInfo:
    """
    Summarise a training run.

    Parameters
    ----------
    run : ThermalRun
        The (possibly joined) training data.
    sources : sequence of str, optional
        Recording names (default: ``[run.name]``).
    rate_window_s : float, keyword-only
        Window of the temperature rate (s): the fitted method's.

    Returns
    -------
    TrainingInfo

    """
    temp = np.asarray(run.temperature_c, dtype=float)
    t = np.asarray(run.t_s, dtype=float)
    rate = temperature_rate_c_s(t, temp, window_s=rate_window_s, start='nan')
    filled = rate[np.isfinite(rate)]
    return TrainingInfo(
        temperature_min_c=float(np.min(temp)), temperature_max_c=float(np.max(temp)),
        temperature_rate_min_c_s=float(np.min(filled)) if filled.size else None,
        temperature_rate_max_c_s=float(np.max(filled)) if filled.size else None,
        rate_hz=float(run.rate_hz), samples=int(t.size),
        duration_s=float(t.size / run.rate_hz),
        sources=tuple(sources) if sources is not None else (run.name,),
        rate_window_s=float(rate_window_s))


@dataclass(frozen=True)
class RangeReport:
    """
    How much of a run lies outside a model's trained range of T and of dT.

    Attributes
    ----------
    samples : int
        Samples checked.
    temperature_below, temperature_above : int
        Samples below ``temperature_min_c`` / above ``temperature_max_c``.
    rate_below, rate_above : int
        Samples whose temperature rate is below / above the trained rate range (0 when the
        training has no rate range).
    outside : int
        Samples outside in T or dT (each counted once).
    temperature_range_c, rate_range_c_s : list of float or None
        The trained ranges.
    run_temperature_c, run_rate_c_s : list of float
        The run's own [min, max].
    treatment : str
        What the method does there (its ``out_of_range`` attribute).

    """

    samples: int
    temperature_below: int
    temperature_above: int
    rate_below: int
    rate_above: int
    outside: int
    temperature_range_c: list
    rate_range_c_s: list | None
    run_temperature_c: list
    run_rate_c_s: list
    treatment: str

    @property
    def fraction_outside(self) -> float:
        """float: ``outside / samples``."""
        return self.outside / self.samples if self.samples else 0.0

    def as_dict(self) -> dict[str, Any]:
        """
        Return the JSON form (the attributes and ``fraction_outside``).

        Returns
        -------
        dict

        """
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out['fraction_outside'] = self.fraction_outside
        return out

    def text(self) -> str:
        """
        Return one sentence for reports and logs.

        Returns
        -------
        str

        """
        if not self.outside:
            return 'the whole run is inside the trained range of T and dT'
        pct = 100.0 * self.fraction_outside
        lo, hi = self.temperature_range_c
        trained = f'T {lo:.2f}..{hi:.2f} degC'
        here = f'T {_span(self.run_temperature_c, ".2f")} degC'
        if self.rate_range_c_s is not None:
            trained += f', dT {self.rate_range_c_s[0]:.3g}..{self.rate_range_c_s[1]:.3g} degC/s'
            here += f', dT {_span(self.run_rate_c_s, ".3g")} degC/s'
        return (f'{self.outside} of {self.samples} samples ({pct:.3g} %) lie outside the trained '
                f'range ({trained}; this run {here}): {self.temperature_below} with T below it, '
                f'{self.temperature_above} above, {self.rate_below} with dT below it, '
                f'{self.rate_above} above. There the method: {self.treatment}')

    def warning(self) -> str | None:
        """
        Return a warning when more than :data:`MAX_OUTSIDE_SHARE` of the run lies outside.

        Returns
        -------
        str or None

        """
        if self.fraction_outside <= MAX_OUTSIDE_SHARE:
            return None
        return (f'{100.0 * self.fraction_outside:.3g} % of the run lies outside the trained '
                f'range of T or dT, more than {100.0 * MAX_OUTSIDE_SHARE:g} %: the model '
                'extrapolates there; retrain on a run covering it (a strict apply refuses it)')


def _span(values: Sequence[float], spec: str) -> str:
    return f'{values[0]:{spec}}..{values[1]:{spec}}' if len(values) == 2 else 'n/a'


def range_report(training: TrainingInfo, temperature_c: ArrayLike, rate_c_s: ArrayLike, *,
                 treatment: str = '', uses_temperature: bool = True,
                 uses_rate: bool = True) -> RangeReport:
    """
    Count the samples outside the trained range of the method's inputs, T and dT.

    Only the inputs a method evaluates count: a T-only method (``poly3``) is not extrapolating
    where only dT leaves the trained range, a method without temperature input (``raw``,
    ``wtd``) nowhere (as the live node, :mod:`.live`, checks them).

    Parameters
    ----------
    training : TrainingInfo
        The model's training summary.
    temperature_c : array_like
        Temperature of the run (n,), degC.
    rate_c_s : array_like
        Its temperature rate (n,), degC/s (the same estimator and window as in training).
    treatment : str, keyword-only
        What the method does outside (its ``out_of_range``).
    uses_temperature, uses_rate : bool, keyword-only
        Whether the method evaluates T, dT (its ``uses_temperature``, ``uses_rate``).

    Returns
    -------
    RangeReport

    """
    temp = np.asarray(temperature_c, dtype=float).reshape(-1)
    rate = np.asarray(rate_c_s, dtype=float).reshape(-1)
    t_lo, t_hi = training.temperature_min_c, training.temperature_max_c
    below_t, above_t = temp < t_lo, temp > t_hi
    if not uses_temperature:
        below_t = above_t = np.zeros(temp.size, dtype=bool)
    r_lo, r_hi = training.temperature_rate_min_c_s, training.temperature_rate_max_c_s
    if r_lo is None or r_hi is None or not (uses_rate and uses_temperature):
        below_r = above_r = np.zeros(temp.size, dtype=bool)
        rate_range = None
    else:
        below_r, above_r = rate < r_lo, rate > r_hi
        rate_range = [r_lo, r_hi]
    outside = below_t | above_t | below_r | above_r
    finite = rate[np.isfinite(rate)]
    return RangeReport(
        samples=int(temp.size), temperature_below=int(below_t.sum()),
        temperature_above=int(above_t.sum()), rate_below=int(below_r.sum()),
        rate_above=int(above_r.sum()), outside=int(outside.sum()),
        temperature_range_c=[t_lo, t_hi], rate_range_c_s=rate_range,
        run_temperature_c=[float(temp.min()), float(temp.max())] if temp.size else [],
        run_rate_c_s=[float(finite.min()), float(finite.max())] if finite.size else [],
        treatment=str(treatment))


@dataclass(frozen=True)
class ThermalModel:
    """
    A fitted method and what it was trained on, as read from (or written to) model.json.

    Attributes
    ----------
    method : ThermalMethod
        The fitted method.
    training : TrainingInfo
    package_version : str
        gyro_noise_ros version that wrote the file.
    accel : TemperaturePolynomial or None
        The accelerometer's polynomial (offset change relative to its ``t_ref_c``, m/s^2), when
        the training data had accelerometer samples.
    notes : tuple of str
        What the fit or :func:`load_model` noticed and let pass (a method fitted without its dT
        term, a file written by another package version).
    autopilot : TemperaturePolynomial or None
        For a method other than ``poly3``: the ``poly3`` fitted on the same training run, the
        form PX4 and ArduPilot evaluate (what ``export`` writes, and the yardstick "x poly3").

    """

    # Any, not ThermalMethod: callers also use members outside the protocol (drift_rad_s,
    # out_of_range) that only some methods have.
    method: Any
    training: TrainingInfo
    package_version: str = __version__
    accel: 'TemperaturePolynomial | None' = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    autopilot: 'TemperaturePolynomial | None' = None

    def poly3(self) -> 'TemperaturePolynomial | None':
        """Return the model's poly3: the method itself when it is one, else :attr:`autopilot`."""
        from .baselines import TemperaturePolynomial

        method = self.method
        if isinstance(method, TemperaturePolynomial) and not method.relative:
            return method
        return self.autopilot


def to_jsonable(value: Any) -> Any:
    """
    Turn numpy scalars and arrays into JSON types, non-finite floats into None (recursively).

    Parameters
    ----------
    value : object
        Dicts, lists, tuples, numpy arrays and scalars, str, None.

    Returns
    -------
    object

    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def model_document(method: ThermalMethod, *, training: TrainingInfo,
                   accel: 'TemperaturePolynomial | None' = None,
                   autopilot: 'TemperaturePolynomial | None' = None) -> dict[str, Any]:
    """
    Return the model.json document of a fitted method (what :func:`save_model` writes).

    Parameters
    ----------
    method : ThermalMethod
        A fitted method (``to_dict()`` must give every fitted parameter).
    training : TrainingInfo
        What it was trained on (:func:`training_info`).
    accel : TemperaturePolynomial, optional, keyword-only
        The accelerometer's fitted polynomial.
    autopilot : TemperaturePolynomial, optional, keyword-only
        The poly3 fitted beside a method of another form (:attr:`ThermalModel.autopilot`).

    Returns
    -------
    dict
        JSON-able.

    """
    doc = {
        'format': MODEL_FORMAT,
        'format_version': MODEL_FORMAT_VERSION,
        'method': method.name,
        'causal': bool(method.causal),
        'package_version': __version__,
        'created_utc': datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds'),
        'training': training.as_dict(),
        'parameters': method.to_dict(),
        'accel': None if accel is None else {
            'unit': 'm/s^2', 'relative_to_t_ref': True, 'parameters': accel.to_dict()},
        'autopilot': None if autopilot is None else {
            'note': 'poly3 fitted on the same training run: the form PX4 and ArduPilot '
                    'evaluate (gyro_noise_thermal export writes it)',
            'parameters': autopilot.to_dict()},
    }
    return to_jsonable(doc)


def save_model(method: ThermalMethod, path: StrPath, *, training: TrainingInfo,
               accel: 'TemperaturePolynomial | None' = None,
               autopilot: 'TemperaturePolynomial | None' = None) -> dict[str, Any]:
    """
    Write a fitted method to model.json (atomically: a half-written file is never left).

    Parameters
    ----------
    method : ThermalMethod
        A fitted method (``to_dict()`` must give every fitted parameter).
    path : str or os.PathLike
        File to write (its directory must exist).
    training : TrainingInfo
        What it was trained on (:func:`training_info`).
    accel : TemperaturePolynomial, optional, keyword-only
        The accelerometer's fitted polynomial.
    autopilot : TemperaturePolynomial, optional, keyword-only
        The poly3 fitted beside a method of another form.

    Returns
    -------
    dict
        The document written.

    """
    doc = model_document(method, training=training, accel=accel, autopilot=autopilot)
    atomic_write_text(path, json.dumps(doc, indent=1, allow_nan=False) + '\n')
    return doc


def load_model(path: StrPath) -> ThermalModel:
    """
    Read model.json and rebuild the fitted method through its class's ``from_dict``.

    Parameters
    ----------
    path : str or os.PathLike
        model.json written by :func:`save_model`.

    Returns
    -------
    ThermalModel

    Raises
    ------
    ModelFileError
        Missing, not JSON, another format or version, or parameters the class rejects.
    MethodUnavailableError
        The method's class cannot be imported.

    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except OSError as err:
        raise ModelFileError(f'model file {str(path)!r} cannot be read: '
                             f'{err.strerror or err}') from err
    except ValueError as err:
        raise ModelFileError(f'model file {str(path)!r} is not JSON: {err}') from err
    if not isinstance(doc, dict) or doc.get('format') != MODEL_FORMAT:
        raise ModelFileError(f'{str(path)!r} is not a gyro_noise_ros thermal model '
                             f'(format {doc.get("format") if isinstance(doc, dict) else None!r})')
    if doc.get('format_version') not in READABLE_FORMAT_VERSIONS:
        raise ModelFileError(f'model file {str(path)!r} has format_version '
                             f'{doc.get("format_version")!r}; this version reads '
                             f'{", ".join(str(v) for v in READABLE_FORMAT_VERSIONS)}')

    def rate(value: Any) -> float | None:
        return None if value is None else float(value)

    try:
        name = doc['method']
        tr = doc['training']
        training = TrainingInfo(
            temperature_min_c=float(tr['temperature_min_c']),
            temperature_max_c=float(tr['temperature_max_c']),
            temperature_rate_min_c_s=rate(tr['temperature_rate_min_c_s']),
            temperature_rate_max_c_s=rate(tr['temperature_rate_max_c_s']),
            rate_hz=float(tr['rate_hz']), samples=int(tr['samples']),
            duration_s=float(tr['duration_s']), sources=tuple(tr['sources']),
            rate_window_s=float(tr.get('rate_window_s', DEFAULT_RATE_WINDOW_S)))
        params = doc['parameters']
    except (KeyError, TypeError, ValueError) as err:
        raise ModelFileError(f'model file {str(path)!r} lacks or garbles {err}') from err
    if not isinstance(params, dict) or not params:
        raise ModelFileError(f'model file {str(path)!r} has no fitted parameters '
                             f'("parameters": {json.dumps(params)}); fit the model again')
    cls = method_class(name)
    method = _from_dict(cls, params, f'model file {str(path)!r}: parameters of method {name!r}')
    from .baselines import TemperaturePolynomial

    polys = {}
    for key, label in (('accel', 'accelerometer'), ('autopilot', 'autopilot poly3')):
        part = doc.get(key)
        polys[key] = None if not part else _from_dict(
            TemperaturePolynomial, part.get('parameters') if isinstance(part, dict) else None,
            f'model file {str(path)!r}: {label} parameters')
    version = str(doc.get('package_version', ''))
    notes: tuple[str, ...] = ()
    if version != __version__:
        notes = (f'model file {str(path)!r} was written by gyro_noise_ros {version or "?"}, '
                 f'this is {__version__}; it loads, but refit if the methods changed since',)
    return ThermalModel(method=method, training=training, package_version=version,
                        accel=polys['accel'], notes=notes, autopilot=polys['autopilot'])


def _from_dict(cls: type[Any], params: Any, where: str) -> Any:
    if not isinstance(params, dict) or not params:
        raise ModelFileError(f'{where} are empty')
    try:
        return cls.from_dict(params)
    except GyroNoiseError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as err:
        raise ModelFileError(f'{where} are invalid ({type(err).__name__}: {err})') from err


def check_same_sensor(model: ThermalModel, run: ThermalRun, *,
                      max_offset_deg_s: float = MAX_SENSOR_OFFSET_DEG_S) -> list[float]:
    """
    Refuse a run whose gyro sits far from what the model predicts at its temperatures.

    The offset per axis is the median over the (static) run of the gyro minus the model's drift
    at the run's temperatures (its poly3, :meth:`ThermalModel.poly3`, else the method's own
    ``drift_rad_s``): a turn-on difference for the sensor the model was fitted on, the
    difference of two parts' zero-rate levels for a model of another sensor.

    Parameters
    ----------
    model : ThermalModel
        The model.
    run : ThermalRun
        The run it is about to be applied to.
    max_offset_deg_s : float, keyword-only
        Largest accepted offset on any axis (deg/s, >= 0; ``inf`` disables the check).

    Returns
    -------
    list of float
        The offsets per axis (deg/s); empty when the model gives no drift function.

    Raises
    ------
    SensorMismatchError
        An axis beyond ``max_offset_deg_s``.
    ParameterError
        A NaN or negative limit.

    """
    limit = float(max_offset_deg_s)
    if not limit >= 0.0:
        raise ParameterError(f'{{max_offset_deg_s}} must be >= 0 deg/s (inf: off), got '
                             f'{max_offset_deg_s!r}', parameters=('max_offset_deg_s',))
    poly = model.poly3()
    drift = getattr(poly if poly is not None else model.method, 'drift_rad_s', None)
    if drift is None:
        return []
    temp = np.asarray(run.temperature_c, dtype=float)
    rate = temperature_rate_c_s(run.t_s, temp, window_s=model.training.rate_window_s)
    offsets = np.degrees(np.median(np.asarray(run.gyro_rad_s, dtype=float)
                                   - np.asarray(drift(temp, rate), dtype=float), axis=0))
    far = [f'{axis} {v:+.3g}' for axis, v in zip('xyz', offsets) if abs(v) > limit]
    if far:
        raise SensorMismatchError(
            f'run {run.name!r}: its gyro sits {", ".join(far)} deg/s from the model drift at '
            f'its temperatures (more than {limit:g} deg/s): is the model of another sensor? '
            '({max_offset_deg_s} inf applies it anyway)', parameters=('max_offset_deg_s',))
    return [float(v) for v in offsets]


def check_temperature_range(model: ThermalModel, temperature_c: ArrayLike, *,
                            margin_c: float = DEFAULT_RANGE_MARGIN_C) -> tuple[float, float]:
    """
    Refuse data whose temperature leaves the trained range by more than ``margin_c``.

    Parameters
    ----------
    model : ThermalModel
        The model (its ``training`` range is used).
    temperature_c : array_like
        Temperature of the data the model is about to be applied to (degC).
    margin_c : float, keyword-only
        Allowed excursion beyond each end of the trained range (degC, >= 0; ``inf`` disables
        the check).

    Returns
    -------
    tuple of float
        (min, max) of ``temperature_c`` (degC).

    Raises
    ------
    TemperatureRangeError
        Below ``temperature_min_c - margin_c`` or above ``temperature_max_c + margin_c``.
    ParameterError
        Negative or NaN margin.

    """
    margin = float(margin_c)
    if not margin >= 0.0:
        raise ParameterError(f'temperature range margin must be >= 0 degC, got {margin_c!r}')
    temp = np.asarray(temperature_c, dtype=float)
    lo, hi = float(np.min(temp)), float(np.max(temp))
    t_lo, t_hi = model.training.temperature_min_c, model.training.temperature_max_c
    if lo < t_lo - margin or hi > t_hi + margin:
        raise TemperatureRangeError(
            f"data temperature {lo:.2f}..{hi:.2f} degC leaves the model's trained range "
            f'{t_lo:.2f}..{t_hi:.2f} degC by more than the {margin:g} degC margin; retrain on '
            'data covering it or widen {range_margin_c}', parameters=('range_margin_c',))
    return lo, hi


def fit_method(name: str, run: ThermalRun, *, rng: np.random.Generator,
               sources: Sequence[str] | None = None, executor: Executor | None = None,
               accel: bool = True, **options: Any) -> ThermalModel:
    """
    Build, fit and wrap a method with its training summary.

    Parameters
    ----------
    name : str
        ``--method`` value.
    run : ThermalRun
        Training data.
    rng : numpy.random.Generator
        Passed to ``fit``.
    sources : sequence of str, optional
        Recording names for :class:`TrainingInfo`.
    executor : concurrent.futures.Executor, optional
        Where a method with an ``executor`` attribute (the parallel model: its MOPSO particles)
        runs its pure work units, e.g. a Dask cluster (:mod:`gyro_noise_ros.cluster`); the
        caller shuts it down. Not part of the model: the fit is the same without it.
    accel : bool, keyword-only
        Also fit the accelerometer's polynomial (:func:`fit_accel`) when the run has
        accelerometer samples.
    **options
        Constructor options.

    Returns
    -------
    ThermalModel

    """
    if not isinstance(run, ThermalRun):
        raise ParameterError(f'run must be a ThermalRun, got {type(run).__name__}')
    method = get_method(name, **options)
    if executor is not None and hasattr(method, 'executor'):
        method.executor = executor
        try:
            method.fit(run, rng=rng)
        finally:
            method.executor = None
    else:
        method.fit(run, rng=rng)
    notes: tuple[str, ...] = tuple(getattr(method, 'notes', ()))
    accel_poly = None
    if accel and run.accel_m_s2 is not None:
        try:
            accel_poly = fit_accel(run)
        except InputDataError as err:
            # the gyro model stands on its own; say why the accelerometer has none
            notes += (f'accelerometer not compensated: {err}',)
    window = float(getattr(method, 'rate_window_s', DEFAULT_RATE_WINDOW_S))
    return ThermalModel(method=method, accel=accel_poly, notes=notes,
                        training=training_info(run, sources=sources, rate_window_s=window),
                        autopilot=_autopilot_poly3(method, run))


def _autopilot_poly3(method: Any, run: ThermalRun) -> 'TemperaturePolynomial | None':
    """Fit the poly3 a method of another form is exported as (None when it cannot be)."""
    from .baselines import TemperaturePolynomial

    if isinstance(method, TemperaturePolynomial):
        return None
    poly = TemperaturePolynomial()
    try:
        poly.fit(run, rng=np.random.default_rng(0))
    except InputDataError:
        return None   # a span too narrow for any temperature model: the method says so itself
    return poly


def accel_view(run: ThermalRun) -> ThermalRun:
    """
    Return the run with its accelerometer samples in place of the gyro's.

    The drift methods are unit-agnostic (an offset per axis as a function of T and dT); the
    accelerometer's polynomial is fitted and applied on this view (``gyro_rad_s`` then holds
    m/s^2).

    Parameters
    ----------
    run : ThermalRun
        A run with ``accel_m_s2``.

    Returns
    -------
    ThermalRun

    """
    if run.accel_m_s2 is None:
        raise InputDataError(f'run {run.name!r} has no accelerometer samples')
    return ThermalRun(t_s=run.t_s, gyro_rad_s=np.asarray(run.accel_m_s2, dtype=float),
                      temperature_c=run.temperature_c, rate_hz=run.rate_hz,
                      name=f'{run.name} (accelerometer)')


def fit_accel(run: ThermalRun) -> 'TemperaturePolynomial':
    """
    Fit the accelerometer's temperature polynomial (PX4 ``TC_A0_*`` form).

    Per axis a cubic in ``T - T_ref`` (``T_ref`` the middle of the training range) of the
    specific force, with its constant term removed: what is compensated is the *change* of
    the accelerometer offset from ``T_ref`` (gravity and the offset at ``T_ref`` belong to the
    six-position calibration). Beyond the trained range the change is held at the range's
    ends, as PX4 and ArduPilot do.

    Parameters
    ----------
    run : ThermalRun
        Training data with ``accel_m_s2`` (static: the specific force constant but for the
        temperature effect).

    Returns
    -------
    TemperaturePolynomial
        Fitted, ``relative=True``.

    """
    from .baselines import TemperaturePolynomial

    poly = TemperaturePolynomial(relative=True)
    poly.fit(accel_view(run), rng=np.random.default_rng(0))
    return poly


def check_min_range(min_range_c: float) -> float:
    """
    Validate ``--min-range-c``: a finite number of degC, >= 0.

    Parameters
    ----------
    min_range_c : float
        The value.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        NaN, infinite or negative.

    """
    try:
        value = float(min_range_c)
    except (TypeError, ValueError):
        raise ParameterError(f'{{min_range_c}} must be a number of degC, got {min_range_c!r}',
                             parameters=('min_range_c',)) from None
    if not (math.isfinite(value) and value >= 0.0):
        raise ParameterError(f'{{min_range_c}} must be a finite temperature span >= 0 degC, got '
                             f'{min_range_c!r}', parameters=('min_range_c',))
    return value


def check_trainable(run: ThermalRun, *, min_range_c: float = DEFAULT_MIN_RANGE_C,
                    method: str | None = None) -> None:
    """
    Refuse training data a temperature model cannot be fitted on.

    Parameters
    ----------
    run : ThermalRun
        Training data.
    min_range_c : float, keyword-only
        Smallest accepted temperature span, max - min (degC, finite, >= 0).
    method : str, optional, keyword-only
        ``--method`` about to be fitted: a method that uses dT also needs a run at least
        ``baselines.MIN_TRAINING_WINDOWS`` rate windows long, with temperature readings at
        least every ``run.MIN_READINGS_PER_WINDOW``-th of a window.

    Raises
    ------
    ParameterError
        ``min_range_c`` NaN, infinite or negative.
    InputDataError
        Constant temperature, a span below ``min_range_c``, non-finite samples, a run too short
        for the method's rate window or its temperature read too sparsely for it.

    """
    min_range_c = check_min_range(min_range_c)
    temp = np.asarray(run.temperature_c, dtype=float)
    gyro = np.asarray(run.gyro_rad_s, dtype=float)
    if not (np.isfinite(temp).all() and np.isfinite(gyro).all()):
        raise InputDataError(f'training run {run.name!r} has NaN/Inf samples')
    lo, hi = float(temp.min()), float(temp.max())
    if hi == lo:
        raise InputDataError(f'training run {run.name!r}: the temperature is constant at '
                             f'{lo:.3f} degC, so there is no temperature dependence to fit')
    if hi - lo < min_range_c:
        raise InputDataError(f'training run {run.name!r}: the temperature spans only '
                             f'{hi - lo:.3g} degC ({lo:.2f}..{hi:.2f}), less than the '
                             f'{min_range_c:g} degC needed to fit a drift model '
                             '({min_range_c})', parameters=('min_range_c',))
    if method is not None:
        cls = method_class(method)
        if getattr(cls, 'uses_rate', False):
            from .baselines import check_rate_training

            check_rate_training(np.asarray(run.t_s, dtype=float), DEFAULT_RATE_WINDOW_S,
                                run.name)
            check_temperature_readings(run, DEFAULT_RATE_WINDOW_S)
