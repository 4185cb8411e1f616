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
imu.yaml of an analysis: one sensor's noise parameters as Kalibr takes them (SI).

:func:`kalibr_noise` picks one number per sensor from its axes' readouts and says in notes what
the record could not resolve; :func:`write_imu_yaml` writes them with the notes as YAML comments.
"""

from collections.abc import Iterable, Mapping
import math
from pathlib import Path
from typing import Any, TYPE_CHECKING

from ..outputs import StrPath

if TYPE_CHECKING:  # annotations only: a renderer needs no readout code at run time
    from ..core.readout import AllanReadout

__all__ = ['DEFAULT_IMU_TOPIC', 'imu_yaml_text', 'kalibr_noise', 'write_imu_yaml']

#: Topic written into imu.yaml for inputs that have none (CSV tables, PX4 ULogs).
DEFAULT_IMU_TOPIC = '/imu/data_raw'


def kalibr_noise(readouts: Iterable['AllanReadout | None'], *,
                 record_s: float | None = None) -> dict[str, Any]:
    """
    Return one sensor's Kalibr noise parameters from its axes' readouts, with the notes to say.

    Kalibr takes one number per sensor: the largest over the axes (the noisiest axis bounds the
    others). The random walk of each axis is the larger of its fitted K and its bound
    (:meth:`..core.readout.AllanReadout.kalibr`).

    Parameters
    ----------
    readouts : list of core.readout.AllanReadout or None
        The analysed axes (None entries ignored).
    record_s : float, optional, keyword-only
        Record length (s), named in the notes.

    Returns
    -------
    dict
        ``noise_density`` and ``random_walk`` (SI; None when no axis gives one: a zero or
        missing density is never written as a number), ``noise_density_note`` and
        ``random_walk_note`` (empty when there is nothing to say).

    """
    rs = [r for r in readouts if r is not None]
    dens = [r for r in rs if math.isfinite(r.arw_rad_per_sqrt_s) and r.arw_rad_per_sqrt_s > 0]
    walks = [(r.kalibr(), r) for r in rs]
    walks = [(k, r) for k, r in walks if math.isfinite(k['random_walk']) and k['random_walk'] > 0]
    out: dict[str, Any] = {'noise_density': None, 'random_walk': None, 'noise_density_note': '',
                           'random_walk_note': ''}
    if dens:
        best = max(dens, key=lambda r: r.arw_rad_per_sqrt_s)
        out['noise_density'] = best.arw_rad_per_sqrt_s
        if not best.arw_from_region:
            out['noise_density_note'] = ('read as ADEV(1 s) x sqrt(1 s): the Allan curve has no '
                                         '-1/2 (white-noise) region')
    else:
        out['noise_density_note'] = ('not measured: no -1/2 region and no tau = 1 s on the Allan '
                                     'curve (record too short); give it from the datasheet')
    if walks:
        k, r = max(walks, key=lambda kr: kr[0]['random_walk'])
        out['random_walk'] = k['random_walk']
        length = f' ({record_s:.4g} s)' if record_s is not None and math.isfinite(record_s) else ''
        bound = 'K <= upper ADEV bound at the longest tau x sqrt(3 / tau)'
        k_fit = r.rate_random_walk_rad_per_s_sqrt_s
        fitted = (f'the fitted K, {k_fit:.3g}, is smaller' if math.isfinite(k_fit) and k_fit > 0
                  else 'the fit finds none')
        short = [rr for kk, rr in walks if kk['too_short']]
        if short:
            out['random_walk_note'] = (
                f'record too short{length} for a random walk: the Allan curve is still falling '
                f'at its longest tau ({short[0].bias_stability_tau_s:.3g} s), so this is only an '
                f'upper bound, {bound}')
        elif k['random_walk_is_bound']:
            out['random_walk_note'] = (f'upper bound: the record{length} does not resolve a '
                                       f'random walk; {bound} ({fitted})')
    return out


def imu_yaml_text(*, rostopic: str, update_rate_hz: float, gyroscope: Mapping[str, Any],
                  accelerometer: Mapping[str, Any] | None = None, rostopic_note: str = '',
                  source: str = '') -> str:
    """
    Return a Kalibr-style imu.yaml (kalibr ``imu.yaml`` keys, SI units), notes as YAML comments.

    The text of the file :func:`write_imu_yaml` writes (report.html shows it, ready to copy).

    Parameters
    ----------
    rostopic : str
        IMU topic.
    update_rate_hz : float
        Sample rate (Hz).
    gyroscope : dict
        :func:`kalibr_noise` of the gyroscope axes (rad/s/sqrt(Hz), rad/s^2/sqrt(Hz)).
    accelerometer : dict, optional
        The same for the accelerometer (m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)); omitted when None.
    rostopic_note : str
        Comment above ``rostopic`` (e.g. that the input had no topic).
    source : str
        Comment line saying which bag and axes the numbers come from.

    Returns
    -------
    str

    """
    def val(v: float | None) -> str:
        return 'null' if v is None or not math.isfinite(float(v)) else repr(float(v))

    def entry(key: str, value: float | None, unit: str, note: str) -> list[str]:
        return ([f'# {key}: {note}'] if note else []) + [f'{key}: {val(value)}  # {unit}']

    lines = [
        '# Kalibr-style IMU noise parameters written by gyro_noise_analyze (continuous-time, SI).']
    if source:
        lines.append(f'# {source}')
    if rostopic_note:
        lines.append(f'# rostopic: {rostopic_note}')
    lines += [f'rostopic: {rostopic}', f'update_rate: {val(update_rate_hz)}  # Hz']
    sensors = [('gyroscope', gyroscope, 'rad/s/sqrt(Hz)', 'rad/s^2/sqrt(Hz)')]
    if accelerometer is not None:
        sensors.append(('accelerometer', accelerometer, 'm/s^2/sqrt(Hz)', 'm/s^3/sqrt(Hz)'))
    for name, noise, u_density, u_walk in sensors:
        lines += entry(f'{name}_noise_density', noise['noise_density'], u_density,
                       noise['noise_density_note'])
        lines += entry(f'{name}_random_walk', noise['random_walk'], u_walk,
                       noise['random_walk_note'])
    return '\n'.join(lines) + '\n'


def write_imu_yaml(path: StrPath, **kwargs: Any) -> str:
    """
    Write :func:`imu_yaml_text` to ``path``; return the text.

    Parameters
    ----------
    path : str or os.PathLike
        YAML file to write.
    **kwargs
        The keyword arguments of :func:`imu_yaml_text`.

    Returns
    -------
    str
        What was written.

    """
    text = imu_yaml_text(**kwargs)
    Path(path).write_text(text)
    return text
