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

from collections.abc import Mapping
import math
from pathlib import Path
from typing import Any, TYPE_CHECKING

from ..outputs import StrPath

if TYPE_CHECKING:  # annotations only: a renderer needs no readout code at run time
    from ..core.readout import AllanReadout

__all__ = ['DEFAULT_IMU_TOPIC', 'imu_yaml_text', 'kalibr_noise', 'write_imu_yaml']

#: Topic written into imu.yaml for inputs that have none (CSV tables, PX4 ULogs).
DEFAULT_IMU_TOPIC = '/imu/data_raw'


def kalibr_noise(readouts: Mapping[str, 'AllanReadout | None'], *,
                 record_s: float | None = None) -> dict[str, Any]:
    """
    Return one sensor's Kalibr noise parameters from its axes' readouts, with the notes to say.

    Kalibr takes one number per sensor: the largest over the axes (the noisiest axis bounds the
    others). The random walk of each axis is the larger of its fitted K and its bound
    (:meth:`..core.readout.AllanReadout.kalibr`). Each note names the axis the value came from
    and the taus it was read at, and what that axis' record could not resolve.

    Parameters
    ----------
    readouts : dict
        Axis name -> :class:`~gyro_noise_ros.core.readout.AllanReadout` of the analysed axes
        (None entries ignored).
    record_s : float, optional, keyword-only
        Record length (s), named in the notes.

    Returns
    -------
    dict
        ``noise_density`` and ``random_walk`` (SI; None when no axis gives one: a zero or
        missing density is never written as a number), ``noise_density_note`` and
        ``random_walk_note`` (where each value came from, or why there is none).

    """
    rs = {a: r for a, r in readouts.items() if r is not None}
    dens = {a: r for a, r in rs.items()
            if math.isfinite(r.arw_rad_per_sqrt_s) and r.arw_rad_per_sqrt_s > 0}
    walks = {a: (r.kalibr(), r) for a, r in rs.items()}
    walks = {a: kr for a, kr in walks.items()
             if math.isfinite(kr[0]['random_walk']) and kr[0]['random_walk'] > 0}
    out: dict[str, Any] = {'noise_density': None, 'random_walk': None,
                           'noise_density_note': _density_note(dens),
                           'random_walk_note': ''}
    if dens:
        out['noise_density'] = max(r.arw_rad_per_sqrt_s for r in dens.values())
    if walks:
        axis = max(walks, key=lambda a: walks[a][0]['random_walk'])
        k, r = walks[axis]
        out['random_walk'] = k['random_walk']
        out['random_walk_note'] = _walk_note(axis, k, r, record_s)
    return out


def _density_note(dens: Mapping[str, 'AllanReadout']) -> str:
    """Where the noise density came from: its axis and taus (or why there is none)."""
    if not dens:
        return ('not measured: no -1/2 region and no tau = 1 s on the Allan curve (record too '
                'short); give it from the datasheet')
    axis = max(dens, key=lambda a: dens[a].arw_rad_per_sqrt_s)
    r = dens[axis]
    if not r.arw_from_region:
        return (f'axis {axis}: read as ADEV(1 s) x sqrt(1 s): its Allan curve has no -1/2 '
                '(white-noise) region')
    lo, hi = r.arw_tau_range_s
    return f'axis {axis}: the -1/2 line through its Allan curve at tau = {lo:.3g}-{hi:.3g} s'


def _walk_note(axis: str, k: Mapping[str, Any], r: 'AllanReadout',
               record_s: float | None) -> str:
    """Where the random walk came from: its axis and tau, and what that axis resolves."""
    length = f' ({record_s:.4g} s)' if record_s is not None and math.isfinite(record_s) else ''
    tau_b = r.rate_random_walk_bound_tau_s
    bound = f'K <= upper ADEV bound at its longest tau ({tau_b:.3g} s) x sqrt(3 / tau)'
    k_fit = r.rate_random_walk_rad_per_s_sqrt_s
    fitted = (f'the fitted K, {k_fit:.3g}, is smaller' if math.isfinite(k_fit) and k_fit > 0
              else 'the fit finds none')
    if not k['random_walk_is_bound']:
        if r.rate_random_walk_resolved:
            lo, hi = r.rate_random_walk_tau_range_s
            return (f'axis {axis}: the fitted K, shown by its +1/2 region at tau = '
                    f'{lo:.3g}-{hi:.3g} s')
        return (f'axis {axis}: the fitted K, not resolved: its Allan curve has no +1/2 region of '
                f'two octaves that excludes a flat curve (longest tau {tau_b:.3g} s)')
    if k['too_short']:
        return (f'axis {axis}: record too short{length} for a random walk: its Allan curve was '
                f'not seen to turn up (its floor at tau = {r.bias_stability_tau_s:.3g} s is an '
                f'upper bound), so this is only an upper bound, {bound}')
    return (f'axis {axis}: upper bound: the record{length} does not resolve a random walk; '
            f'{bound} ({fitted})')


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
