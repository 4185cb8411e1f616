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
Classification of VMD modes into noise, mixed and drift by sample entropy (paper 002, Fig. 13).

The paper classifies its eight IMFs by their sample entropy without giving a rule. Ours:

1. Each mode's sample entropy (m = 2, r = 0.2 std) is computed on its coarse-grained series
   (non-overlapping block means; Costa et al.'s multiscale entropy). By default the scale is
   ``q = ceil(n / max_samples)``, so the whole record counts and the O(n^2) cost stays bounded
   (a record of at most ``max_samples`` samples is used as it is, q = 1). With ``scale`` given,
   q is that many samples whatever the record's length, and a coarse series longer than
   ``max_samples`` is cut into windows of ``max_samples`` whose template counts are pooled
   (one tolerance, ``r`` times the std of the whole coarse series): the classes then mean the
   same on a short and a long record. What coarse-graining by q keeps is content slower than
   about q samples; white noise stays white (entropy ``-ln erf(0.1) = 2.20``) at any q.
2. Modes are taken by ascending centre frequency. The lowest is drift; each next one is drift
   too while its entropy stays below ``drift_max`` (drift is the slow, regular end).
3. Every other mode is noise when its entropy exceeds ``noise_min`` (white noise has
   ``-ln erf(0.1) = 2.20`` at m = 2, r = 0.2), else mixed.

Defaults ``drift_max = 0.5`` and ``noise_min = 1.5``.
"""

from dataclasses import dataclass

from gyro_noise_ros.errors import ParameterError
from gyro_noise_ros.thermal.entropy import sample_entropy, sample_entropy_counts
import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Class names, slow to fast.
CLASSES = ('drift', 'mixed', 'noise')


@dataclass(frozen=True)
class ModeClasses:
    """
    Per-mode classification (the paper's Figure 13 a/b).

    Attributes
    ----------
    classes : tuple of str
        'drift', 'mixed' or 'noise' per mode (input order).
    sample_entropy : numpy.ndarray
        Sample entropy of each mode's coarse-grained series (k,).
    scale : int
        Coarse-graining scale q used.
    drift_max, noise_min : float
        Thresholds applied.

    """

    classes: tuple
    sample_entropy: np.ndarray
    scale: int
    drift_max: float
    noise_min: float

    def mask(self, name: str) -> NDArray[np.bool_]:
        """Select the modes of one class: a boolean array (k,)."""
        return np.array([c == name for c in self.classes], dtype=bool)


def coarse_grain(x: ArrayLike, scale: int) -> NDArray[np.float64]:
    """Return the means of consecutive non-overlapping blocks of ``scale`` samples."""
    x = np.asarray(x, dtype=float)
    n = (x.size // scale) * scale
    return x[:n].reshape(-1, scale).mean(axis=1)


def pooled_sample_entropy(x: ArrayLike, *, m: int = 2, r: float = 0.2,
                          window: int = 2000) -> float:
    """
    Sample entropy with the template counts of consecutive windows pooled (bounded cost).

    Parameters
    ----------
    x : array_like
        Series (n,).
    m, r : keyword-only
        Template length and tolerance (fraction of ``std(x)`` over the whole series).
    window : int, keyword-only
        Longest window the O(n^2) count runs on; a shorter series is one window.

    Returns
    -------
    float
        ``-ln(sum A / sum B)``; inf when no pair matches at m + 1, nan when none at m, 0 for a
        constant series.

    """
    a = np.asarray(x, dtype=float)
    sd = a.std()
    if sd == 0:
        return 0.0
    window = max(int(window), m + 2)
    n_win = max(1, a.size // window)
    a_sum = b_sum = 0
    for w in range(n_win):
        stop = a.size if w == n_win - 1 else (w + 1) * window
        a_w, b_w = sample_entropy_counts(a[w * window:stop], m=m, tolerance=r * sd)
        a_sum += a_w
        b_sum += b_w
    if b_sum == 0:
        return float('nan')
    if a_sum == 0:
        return float('inf')
    return float(-np.log(a_sum / b_sum))


def classify_modes(modes: ArrayLike, center_freqs: ArrayLike, *, m: int = 2, r: float = 0.2,
                   drift_max: float = 0.5, noise_min: float = 1.5, max_samples: int = 2000,
                   scale: int | None = None) -> ModeClasses:
    """
    Classify modes into drift, mixed and noise by sample entropy (rule in the module docstring).

    Parameters
    ----------
    modes : array_like
        Modes (k, n).
    center_freqs : array_like
        Their centre frequencies (k,), used only to order them.
    m, r : keyword-only
        Sample entropy template length and tolerance (fraction of std).
    drift_max, noise_min : float, keyword-only
        Thresholds (drift_max <= noise_min).
    max_samples : int, keyword-only
        Longest series the entropy is computed on (sets the coarse-graining scale when
        ``scale`` is None; the window of the pooled counts otherwise).
    scale : int or None, keyword-only
        Fixed coarse-graining scale (samples, >= 1); None: ``ceil(n / max_samples)``.

    Returns
    -------
    ModeClasses
        Classes and entropies per mode.

    """
    u = np.atleast_2d(np.asarray(modes, dtype=float))
    freqs = np.asarray(center_freqs, dtype=float).reshape(-1)
    if freqs.size != u.shape[0]:
        raise ParameterError(f'{u.shape[0]} modes but {freqs.size} centre frequencies')
    if not drift_max <= noise_min:
        raise ParameterError(f'drift_max ({drift_max}) must be <= noise_min ({noise_min})')
    if int(max_samples) < m + 10:
        raise ParameterError(f'max_samples must be >= {m + 10}, got {max_samples}')
    if scale is None:
        scale = max(1, -(-u.shape[1] // int(max_samples)))
        se = np.array([sample_entropy(coarse_grain(mode, scale), m=m, r=r) for mode in u])
    else:
        scale = int(scale)
        if scale < 1 or u.shape[1] // scale < m + 2:
            raise ParameterError(f'scale must be >= 1 and leave at least {m + 2} coarse '
                                 f'samples of the {u.shape[1]}, got {scale}')
        se = np.array([pooled_sample_entropy(coarse_grain(mode, scale), m=m, r=r,
                                             window=int(max_samples)) for mode in u])
    # nan (no template pair matched) counts as irregular; inf is irregular already.
    se_rank = np.where(np.isnan(se), np.inf, se)
    classes = [''] * len(u)
    in_drift = True
    for rank, i in enumerate(np.argsort(freqs, kind='stable')):
        if in_drift and (rank == 0 or se_rank[i] < drift_max):
            classes[i] = 'drift'
            continue
        in_drift = False
        classes[i] = 'noise' if se_rank[i] > noise_min else 'mixed'
    return ModeClasses(classes=tuple(classes), sample_entropy=se, scale=scale,
                       drift_max=float(drift_max), noise_min=float(noise_min))
