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

``model.json`` (format version 1) holds the method name, every fitted parameter (the method's
``to_dict()`` under ``parameters``) and what the model was trained on (temperature and
temperature-rate range, sample rate, source names): :func:`save_model` / :func:`load_model`.
:func:`check_temperature_range` refuses to apply a model more than ``margin_c`` (default
:data:`DEFAULT_RANGE_MARGIN_C`) outside the temperatures it was trained on: every data-driven
drift model extrapolates badly, a third-order polynomial worst of all.
"""

from dataclasses import dataclass
import datetime
import importlib
import json
import math
from pathlib import Path

import numpy as np

from .run import temperature_rate_c_s, ThermalMethod, ThermalRun
from .. import __version__
from ..errors import GyroNoiseError, InputDataError, ParameterError

__all__ = ['BUILTIN_METHODS', 'DEFAULT_METHOD', 'DEFAULT_MIN_RANGE_C', 'DEFAULT_RANGE_MARGIN_C',
           'MODEL_FORMAT', 'MODEL_FORMAT_VERSION', 'MethodUnavailableError', 'ModelFileError',
           'TemperatureRangeError', 'ThermalModel', 'TrainingInfo', 'check_temperature_range',
           'check_trainable', 'fit_method', 'get_method', 'load_model', 'method_class',
           'method_names', 'register_method', 'save_model', 'to_jsonable', 'training_info']

#: The built-in methods: ``--method`` name -> (module, class name). Imported on first use.
BUILTIN_METHODS = {
    'raw': ('gyro_noise_ros.thermal.baselines', 'RawMethod'),
    'poly3': ('gyro_noise_ros.thermal.baselines', 'TemperaturePolynomial'),
    'linear_tdt': ('gyro_noise_ros.thermal.baselines', 'LinearTdT'),
    'wtd': ('gyro_noise_ros.thermal.baselines', 'WaveletThreshold'),
    'bp': ('gyro_noise_ros.thermal.baselines', 'BPNetwork'),
    'emd_wtd_sabp': ('gyro_noise_ros.thermal.baselines', 'EmdWtdSaBp'),
    'parallel': ('gyro_noise_ros.thermal.parallel', 'ParallelModel'),
}

#: Default ``--method`` of ``gyro_noise_thermal fit``: the held-out winner of
#: ``gyro_noise_thermal compare`` (lowest mean residual drift on the test run among the methods
#: that keep the full bandwidth and run causally) on three simulated train/test pairs; the
#: measurement and its limits are in docs/thermal.md, "The default method".
DEFAULT_METHOD = 'bp'

#: How far (degC) outside the trained temperature range a model may still be applied.
DEFAULT_RANGE_MARGIN_C = 5.0

#: Smallest temperature span (degC) a drift model is fitted on (``fit`` refuses less).
DEFAULT_MIN_RANGE_C = 2.0

#: ``format`` and ``format_version`` of model.json.
MODEL_FORMAT = 'gyro_noise_ros.thermal.model'
MODEL_FORMAT_VERSION = 1

_registered = {}


class MethodUnavailableError(GyroNoiseError):
    """A ``--method`` name is unknown, or its module cannot be imported (exit code 2)."""

    exit_code = 2


class ModelFileError(GyroNoiseError):
    """A model.json is missing, unreadable or not a model of a known method (exit code 3)."""

    exit_code = 3


class TemperatureRangeError(InputDataError):
    """The data's temperature lies outside the model's trained range plus margin (exit code 4)."""


def register_method(name, cls):
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


def method_names():
    """
    List every known method name: the built-ins, then those registered.

    Returns
    -------
    list of str

    """
    return list(BUILTIN_METHODS) + [n for n in _registered if n not in BUILTIN_METHODS]


def method_class(name):
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


def get_method(name, **options):
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
    temperature_rate_min_c_s, temperature_rate_max_c_s : float
        Range of the causal temperature rate (degC/s, :func:`temperature_rate_c_s`).
    rate_hz : float
        Sample rate of the training data (Hz).
    samples : int
        Training samples.
    duration_s : float
        Training duration (s), summed over sources.
    sources : tuple of str
        Names of the recordings trained on.

    """

    temperature_min_c: float
    temperature_max_c: float
    temperature_rate_min_c_s: float
    temperature_rate_max_c_s: float
    rate_hz: float
    samples: int
    duration_s: float
    sources: tuple

    def as_dict(self):
        """
        Return the JSON form.

        Returns
        -------
        dict

        """
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out['sources'] = list(self.sources)
        return out


def training_info(run, *, sources=None):
    """
    Summarise a training run.

    Parameters
    ----------
    run : ThermalRun
        The (possibly joined) training data.
    sources : sequence of str, optional
        Recording names (default: ``[run.name]``).

    Returns
    -------
    TrainingInfo

    """
    temp = np.asarray(run.temperature_c, dtype=float)
    rate = temperature_rate_c_s(run.t_s, temp)
    t = np.asarray(run.t_s, dtype=float)
    return TrainingInfo(
        temperature_min_c=float(np.min(temp)), temperature_max_c=float(np.max(temp)),
        temperature_rate_min_c_s=float(np.min(rate)), temperature_rate_max_c_s=float(np.max(rate)),
        rate_hz=float(run.rate_hz), samples=int(t.size),
        duration_s=float(t.size / run.rate_hz),
        sources=tuple(sources) if sources is not None else (run.name,))


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

    """

    method: object
    training: TrainingInfo
    package_version: str = __version__


def to_jsonable(value):
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


def save_model(method, path, *, training):
    """
    Write a fitted method to model.json.

    Parameters
    ----------
    method : ThermalMethod
        A fitted method (``to_dict()`` must give every fitted parameter).
    path : str or os.PathLike
        File to write (its directory must exist).
    training : TrainingInfo
        What it was trained on (:func:`training_info`).

    Returns
    -------
    dict
        The document written.

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
    }
    doc = to_jsonable(doc)
    Path(path).write_text(json.dumps(doc, indent=1, allow_nan=False) + '\n')
    return doc


def load_model(path):
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
    if doc.get('format_version') != MODEL_FORMAT_VERSION:
        raise ModelFileError(f'model file {str(path)!r} has format_version '
                             f'{doc.get("format_version")!r}; this version reads '
                             f'{MODEL_FORMAT_VERSION}')
    try:
        name = doc['method']
        tr = doc['training']
        training = TrainingInfo(
            temperature_min_c=float(tr['temperature_min_c']),
            temperature_max_c=float(tr['temperature_max_c']),
            temperature_rate_min_c_s=float(tr['temperature_rate_min_c_s']),
            temperature_rate_max_c_s=float(tr['temperature_rate_max_c_s']),
            rate_hz=float(tr['rate_hz']), samples=int(tr['samples']),
            duration_s=float(tr['duration_s']), sources=tuple(tr['sources']))
        params = doc['parameters']
    except (KeyError, TypeError, ValueError) as err:
        raise ModelFileError(f'model file {str(path)!r} lacks or garbles {err}') from err
    cls = method_class(name)
    try:
        method = cls.from_dict(params)
    except GyroNoiseError:
        raise
    except (KeyError, TypeError, ValueError) as err:
        raise ModelFileError(f'model file {str(path)!r}: parameters of method {name!r} are '
                             f'invalid ({type(err).__name__}: {err})') from err
    return ThermalModel(method=method, training=training,
                        package_version=str(doc.get('package_version', '')))


def check_temperature_range(model, temperature_c, *, margin_c=DEFAULT_RANGE_MARGIN_C):
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
            f'data covering it or widen --range-margin-c')
    return lo, hi


def fit_method(name, run, *, rng, sources=None, executor=None, **options):
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
    return ThermalModel(method=method, training=training_info(run, sources=sources))


def check_trainable(run, *, min_range_c=DEFAULT_MIN_RANGE_C):
    """
    Refuse training data a temperature model cannot be fitted on.

    Parameters
    ----------
    run : ThermalRun
        Training data.
    min_range_c : float, keyword-only
        Smallest accepted temperature span, max - min (degC).

    Raises
    ------
    InputDataError
        Constant temperature, a span below ``min_range_c``, or non-finite samples.

    """
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
                             '(--min-range-c)')
