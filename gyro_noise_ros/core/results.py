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
What the streaming engine reports: one chunk of one axis, and one axis of a run.

:class:`ChunkResult` holds the per-chunk numbers of paper 000 sec. 3.3-3.5 (bias, variance, both
fractional orders) and :class:`AxisSummary` the per-axis sequence statistics (Tables 3-6), Allan
deviation and counts. They are produced by :mod:`.engine` and read by the health verdicts
(:mod:`.health`), the diagnostic items (:mod:`.items`) and the reports; SI units inside.
"""

from dataclasses import dataclass, field, fields

import numpy as np

from .allan import AllanResult, NoiseTerms
from .chunks import SequenceSummary
from .readout import AllanReadout
from .stamps import StreamCounts

__all__ = ['AxisSummary', 'ChunkResult', 'rad_s2_to_deg_s_per_h', 'STATUSES']

#: Chunk statuses: analysed, left out because of a gap ('drop'), holding NaN/Inf, skipped by the
#: caller, or failing identification (e.g. a constant chunk).
STATUSES = ('ok', 'dropped', 'nan', 'skipped', 'failed')


def _same(a: object, b: object) -> bool:
    """Equality that treats NaN as equal to NaN (results carry NaN for 'not identified')."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (a != a and b != b)
    return a == b


@dataclass(frozen=True, eq=False)
class ChunkResult:
    """
    Per-chunk results of one axis (identical from the node and the offline tool for the same data).

    Equality compares every field except the curves and treats NaN as equal to NaN, so ``a == b``
    is the "same numbers" test between two runs.

    Attributes
    ----------
    axis, chunk, stamp_start_ns, t_start_s, t_mid_s, samples_lost, gaps, nan_samples, temperature_c
        As in :class:`.engine.ChunkJob`.
    samples : int
        Samples in the chunk.
    bias_rad_s : float
        Chunk mean (rad/s), paper sec. 3.3.
    variance_rad2_s2 : float
        Chunk variance, ddof = 1 ((rad/s)^2), paper sec. 3.4.
    alpha_var, f_var : float
        Order and f of the variance method (paper eqs. 6-9, sec. 3.5).
    var_min : float
        Minimum source-noise variance ((rad/s)^2).
    alpha_corr, f_corr : float
        Order and f of the correlation method (eqs. 13-14).
    j_min : float
        Minimum of J ((rad/s)^2).
    tie_var, tie_corr : bool
        The minimum was an exact tie between grid orders (the largest is reported; see
        fractional.py).
    noise_colour : float
        Log-log slope of the chunk's Allan deviation over m = 2-64 samples (dimensionless,
        :func:`.chunks.noise_colour`); NaN when the chunk is too short or not analysed.
    status : str
        One of :data:`STATUSES`.
    message : str
        Why the status is not 'ok' (empty otherwise).
    var_curve, j_curve : numpy.ndarray or None
        var(w)(alpha) and J(alpha) over the grid when curves were requested (not compared).

    """

    axis: str
    chunk: int
    t_start_s: float
    t_mid_s: float
    stamp_start_ns: int
    samples: int
    samples_lost: int
    gaps: int
    nan_samples: int
    bias_rad_s: float
    variance_rad2_s2: float
    alpha_var: float
    f_var: float
    var_min: float
    alpha_corr: float
    f_corr: float
    j_min: float
    tie_var: bool
    tie_corr: bool
    noise_colour: float
    temperature_c: float
    status: str
    message: str = ''
    var_curve: np.ndarray | None = field(default=None, repr=False, compare=False)
    j_curve: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __eq__(self, other: object) -> bool:
        """Compare field by field, NaN equal to NaN (curves are not compared)."""
        if not isinstance(other, ChunkResult):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self) if f.compare)

    # Defining __eq__ leaves the class unhashable (Python sets __hash__ to None).


@dataclass(frozen=True)
class AxisSummary:
    """
    Everything known about one axis of the run: paper Tables 3-6, Allan deviation, counts.

    Attributes
    ----------
    axis : str
    sequence : SequenceSummary
        Tables 3-6 over the 'ok' chunks (rad/s units inside).
    stream : StreamCounts
    nan_samples : int
        NaN/Inf samples on this axis.
    chunks_ok, chunks_nan, chunks_dropped, chunks_failed, chunks_skipped : int
        Chunks by status.
    temperature_mean_c : float
        Mean of the chunk temperatures (degC), NaN if none.
    allan : allan.AllanResult or None
        The Allan deviation result of :mod:`.allan` (None if unavailable or off).
    noise_terms : allan.NoiseTerms or None
        The fitted Allan noise terms of :mod:`.allan` (None if unavailable, off or not fittable),
        band-limited short taus left out (:mod:`.readout`).
    readout : readout.AllanReadout or None
        The datasheet numbers of the Allan deviation (:func:`.readout.read_allan`: bias
        stability, B, ARW, K and its bound, Q, fit quality).

    """

    axis: str
    sequence: SequenceSummary
    stream: StreamCounts
    nan_samples: int
    chunks_ok: int
    chunks_nan: int
    chunks_dropped: int
    chunks_failed: int
    chunks_skipped: int
    temperature_mean_c: float
    allan: AllanResult | None = None
    noise_terms: NoiseTerms | None = None
    readout: AllanReadout | None = None

    @property
    def offset_drift_deg_s_per_h(self) -> float:
        """Signed offset drift (Table 3) in (deg/s)/h."""
        return rad_s2_to_deg_s_per_h(self.sequence.drift.slope)


def rad_s2_to_deg_s_per_h(value: float) -> float:
    """Convert a rate drift from rad/s per s to (deg/s)/h, the unit of the paper's Table 3."""
    return float(np.degrees(value) * 3600.0)
