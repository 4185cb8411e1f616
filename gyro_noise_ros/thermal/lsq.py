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
``lsq_cv``: least squares on a drift basis of the measured temperature, terms by blocked CV.

The gyro offset of each axis is a linear combination of a few terms of the measured die
temperature T and its causal 10-s slope dT: a polynomial in ``x = (T - T_c) / T_s`` (degree 1
to ``max_degree``), optionally ``r = dT / RATE_SCALE_C_S`` (a thermal-gradient term) and ``x r``
(only when the training dT took both signs), and optionally a hysteresis term ``(z - T) / w``,
z the play operator of half-width w on T (``thermal.hysteresis``; only when the training run
turned far enough to show both branches of the loop). Which terms (one set for the three axes)
is decided on the training run alone: blocked cross-validation over ``folds`` contiguous blocks
of it, each candidate fitted on the other blocks and scored by the squared error on the block
left out, over the three axes; of the candidates within one standard error of the best
(:func:`select_terms`) the simplest wins. Least squares on every sample (normal equations per
block), so the fit and all candidates cost one pass over the run.

dT is scaled by a fixed rate (not the run's own range), and a training run whose dT cannot
support a dT term (:func:`~gyro_noise_ros.thermal.run.rate_support`) gets no dT candidate, said in
:attr:`notes`. Definitions and measurements: ``docs/thermal.md``, "The default method".
"""

from collections.abc import Mapping, Sequence
import itertools
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .hysteresis import play_operator
from .run import DEFAULT_RATE_WINDOW_S, temperature_rate_c_s, ThermalRun
from ..errors import InputDataError, ParameterError

__all__ = ['LeastSquaresCV', 'candidate_terms', 'select_terms']

#: Fixed scale of dT in the basis (degC/s): a chamber's 1 degC/min is r = 1.67.
RATE_SCALE_C_S = 0.01
#: Hysteresis half-widths tried (degC).
HYSTERESIS_WIDTHS_C = (0.5, 1.0, 2.0)
#: Samples per chunk of the normal equations.
_CHUNK = 262144
# Normal equations of one fold: A'A (k, k), A'y (k, 3), y'y (3,), samples.
_Fold = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], int]


def candidate_terms(max_degree: int, *, rate: bool = True, cross: bool = True,
                    widths_c: Sequence[float] = HYSTERESIS_WIDTHS_C) -> list[tuple[str, ...]]:
    """
    Return the candidate term sets, simplest first.

    Each set is a polynomial ``1, x, ..., x^p`` (p = 1..``max_degree``), then nothing, ``r`` or
    ``r, x r`` (with ``rate``; ``x r`` only with ``cross``), then nothing or one hysteresis term
    ``h<w>``.

    Parameters
    ----------
    max_degree : int
        Highest degree in T (1..5).
    rate : bool, keyword-only
        Offer dT terms.
    cross : bool, keyword-only
        Offer the dT-by-T term too.
    widths_c : sequence of float, keyword-only
        Hysteresis half-widths offered (degC).

    Returns
    -------
    list of tuple of str

    """
    rates: tuple[tuple[str, ...], ...] = ((),)
    if rate:
        rates = ((), ('r',), ('r', 'xr')) if cross else ((), ('r',))
    hyst: tuple[tuple[str, ...], ...] = ((),) + tuple((f'h{float(w):g}',) for w in widths_c)
    out = [tuple(['1'] + [f'x{p}' for p in range(1, degree + 1)]) + r + h
           for degree, r, h in itertools.product(range(1, int(max_degree) + 1), rates, hyst)]
    return sorted(out, key=len)


class LeastSquaresCV:
    """
    Least squares on a drift basis of T, dT and the hysteresis state, terms by blocked CV.

    See the module docstring. Causal: ``drift_rad_s(T, dT, played_c=...)`` is the offset;
    ``apply(run)`` is ``gyro - drift_rad_s`` with dT the causal trailing-window slope and the
    hysteresis state started at the run's first temperature (a fresh history). Beyond the trained
    range the polynomial is extrapolated (:attr:`out_of_range`).

    Parameters
    ----------
    max_degree : int, keyword-only
        Highest degree in T tried (1..5).
    folds : int, keyword-only
        Contiguous blocks of the cross-validation (>= 2).
    widths_c : sequence of float, keyword-only
        Hysteresis half-widths tried (degC; empty: no hysteresis term).
    rate_window_s : float, keyword-only
        Window of the temperature rate (s).

    """

    name = 'lsq_cv'
    causal = True
    uses_rate = True
    out_of_range = ('T and dT beyond the trained range: the fitted polynomial in T and the '
                    'linear dT terms are extrapolated')

    def __init__(self, *, max_degree: int = 3, folds: int = 5,
                 widths_c: Sequence[float] = HYSTERESIS_WIDTHS_C,
                 rate_window_s: float = DEFAULT_RATE_WINDOW_S) -> None:
        if not (isinstance(max_degree, (int, np.integer)) and 1 <= max_degree <= 5):
            raise ParameterError(f'max_degree must be an integer in 1..5, got {max_degree!r}')
        if not (isinstance(folds, (int, np.integer)) and folds >= 2):
            raise ParameterError(f'folds must be an integer >= 2, got {folds!r}')
        widths = tuple(float(w) for w in widths_c)
        if not all(np.isfinite(w) and w > 0 for w in widths):
            raise ParameterError(f'widths_c must be finite and > 0 degC, got {widths_c!r}')
        if not rate_window_s > 0:
            raise ParameterError(f'rate_window_s must be > 0, got {rate_window_s!r}')
        self.max_degree, self.folds, self.widths_c = int(max_degree), int(folds), widths
        self.rate_window_s = float(rate_window_s)
        self.terms: tuple[str, ...] | None = None
        self.coef: NDArray[np.float64] | None = None   # (k, 3) rad/s per unit of each term
        self.t_centre_c = self.t_scale_c = 0.0
        self.lo: NDArray[np.float64] | None = None   # (2,) T, dT trained range
        self.hi: NDArray[np.float64] | None = None
        self.cv: list[dict[str, Any]] = []
        self.notes: tuple[str, ...] = ()

    @property
    def hysteresis_c(self) -> float:
        """float: half-width of the chosen hysteresis term (degC; 0: none)."""
        found = [t for t in (self.terms or ()) if t.startswith('h')]
        return float(found[0][1:]) if found else 0.0

    def play(self, temperature_c: ArrayLike, *, start: float | None = None) -> NDArray[np.float64]:
        """
        Return the hysteresis state z of a temperature history (degC; T itself without the term).

        Parameters
        ----------
        temperature_c : array_like
            Temperatures in time order (n,), degC.
        start : float, optional, keyword-only
            State before the first one (default: the first temperature).

        Returns
        -------
        numpy.ndarray
            (n,).

        """
        temp = np.asarray(temperature_c, dtype=float).reshape(-1)
        width = self.hysteresis_c
        return play_operator(temp, width, start=start) if width else temp.copy()

    def _columns(self, names: Sequence[str], temp: NDArray[np.float64],
                 rate: NDArray[np.float64],
                 played: Mapping[float, NDArray[np.float64]]) -> NDArray[np.float64]:
        x = (temp - self.t_centre_c) / self.t_scale_c
        r = rate / RATE_SCALE_C_S
        cols = []
        for name in names:
            if name == '1':
                cols.append(np.ones_like(x))
            elif name.startswith('x') and name[1:].isdigit():
                cols.append(x ** int(name[1:]))
            elif name == 'r':
                cols.append(r)
            elif name == 'xr':
                cols.append(x * r)
            else:   # 'h<w>': (z - T) / w, in [-1, 1]
                width = float(name[1:])
                cols.append((played[width] - temp) / width)
        return np.column_stack(cols)

    def fit(self, run: ThermalRun, *, rng: np.random.Generator) -> None:
        """Choose the terms by blocked CV, then fit them on the whole run (``rng`` unused)."""
        from .baselines import rate_fit_inputs

        (t, gyro, temp), support, self.notes = rate_fit_inputs(run, self.rate_window_s,
                                                               self.name)
        rate = temperature_rate_c_s(t, temp, window_s=self.rate_window_s)
        self.lo = np.array([temp.min(), rate.min()])
        self.hi = np.array([temp.max(), rate.max()])
        self.t_centre_c = float(0.5 * (self.lo[0] + self.hi[0]))
        self.t_scale_c = float(0.5 * (self.hi[0] - self.lo[0]))
        played = {w: play_operator(temp, w) for w in self.widths_c}
        # A hysteresis term is identified only where the run turned: its state must have reached
        # both branches (z - T = -w and +w), else its coefficient is fitted to a start-up
        # transient and extrapolated to the branch never seen.
        widths = [w for w, z in played.items() if np.ptp(z - temp) >= 1.8 * w]
        # Along a run that only heats (or only cools) dT is nearly a function of T, so a term
        # x r is told from curvature in T by little more than noise: offered only when dT took
        # both signs.
        candidates = candidate_terms(self.max_degree, rate=support.supported,
                                     cross=support.both_signs, widths_c=widths)
        names = sorted({n for c in candidates for n in c}, key=_term_order)
        stats = self._fold_stats(names, temp, rate, played, gyro)
        self.cv = _cross_validate(stats, names, candidates)
        best = select_terms(self.cv)
        self.terms = tuple(best['terms'])
        index = [names.index(n) for n in self.terms]
        ata = np.sum([s[0] for s in stats], axis=0)[np.ix_(index, index)]
        aty = np.sum([s[1] for s in stats], axis=0)[index]
        coef, _, rank, _ = np.linalg.lstsq(ata, aty, rcond=None)
        if rank < len(index):
            raise InputDataError(f'run {run.name!r}: T and dT do not vary enough to fit '
                                 f'{", ".join(self.terms)} (rank {rank})')
        self.coef = coef
        self.uses_rate = 'r' in self.terms

    def _fold_stats(self, names: Sequence[str], temp: NDArray[np.float64],
                    rate: NDArray[np.float64], played: Mapping[float, NDArray[np.float64]],
                    gyro: NDArray[np.float64]) -> list[_Fold]:
        """Return the normal equations (A'A, A'y, y'y, samples) of each contiguous fold."""
        edges = np.linspace(0, temp.size, self.folds + 1).astype(int)
        out = []
        for a, b in zip(edges[:-1], edges[1:]):
            ata = np.zeros((len(names), len(names)))
            aty = np.zeros((len(names), 3))
            for lo in range(a, b, _CHUNK):
                hi = min(lo + _CHUNK, b)
                cols = self._columns(names, temp[lo:hi], rate[lo:hi],
                                     {w: z[lo:hi] for w, z in played.items()})
                ata += cols.T @ cols
                aty += cols.T @ gyro[lo:hi]
            out.append((ata, aty, np.sum(gyro[a:b] ** 2, axis=0), int(b - a)))
        return out

    def drift_rad_s(self, temperature_c: ArrayLike, dtemp_c_s: ArrayLike, *,
                    played_c: ArrayLike | None = None) -> NDArray[np.float64]:
        """
        Return the offset (n, 3), rad/s.

        Parameters
        ----------
        temperature_c : array_like
            T (n,), degC, in time order when the model has a hysteresis term.
        dtemp_c_s : array_like
            dT (n,), degC/s.
        played_c : array_like, optional, keyword-only
            The hysteresis state z at each sample (:meth:`play` with the state carried over);
            None: :meth:`play` of ``temperature_c`` from its first value.

        Returns
        -------
        numpy.ndarray

        """
        if self.coef is None or self.terms is None:
            raise ParameterError("method 'lsq_cv' is not fitted: call fit() or from_dict()")
        temp = np.asarray(temperature_c, dtype=float).reshape(-1)
        rate = np.broadcast_to(np.asarray(dtemp_c_s, dtype=float), temp.shape)
        width = self.hysteresis_c
        played: dict[float, NDArray[np.float64]] = {}
        if width:
            z = self.play(temp) if played_c is None else np.asarray(played_c, float).reshape(-1)
            played[width] = z
        return self._columns(self.terms, temp, rate, played) @ self.coef

    def apply(self, run: ThermalRun) -> NDArray[np.float64]:
        """Return ``gyro - drift_rad_s(T, dT)`` (n, 3), rad/s."""
        from .baselines import _check_run

        t, gyro, temp = _check_run(run, need_temperature=True)
        return gyro - self.drift_rad_s(
            temp, temperature_rate_c_s(t, temp, window_s=self.rate_window_s))

    def as_poly3(self) -> Any:
        """
        Return the model as a ``poly3`` when its terms are a polynomial in T alone (else None).

        ``sum_p c_p x^p`` with ``x = (T - T_c) / T_s`` is ``sum_p (c_p / T_s^p) (T - T_c)^p``:
        the PX4 form with ``T_ref = T_c`` and the trained range as ``T_min``..``T_max`` (inside
        it the two agree exactly; beyond it poly3 holds the ends, as the autopilots do).

        Returns
        -------
        TemperaturePolynomial or None

        """
        from .baselines import TemperaturePolynomial

        if self.coef is None or self.terms is None or self.lo is None or self.hi is None:
            return None
        powers = [int(t[1:]) if t.startswith('x') else 0 for t in self.terms]
        if any(not (t == '1' or (t.startswith('x') and t[1:].isdigit())) for t in self.terms) \
                or max(powers) > 3:
            return None
        poly = TemperaturePolynomial()
        poly.coef = np.zeros((3, 4))
        for row, p in zip(self.coef, powers):
            poly.coef[:, p] += row / self.t_scale_c ** p
        poly.t_ref_c = self.t_centre_c
        poly.t_min_c, poly.t_max_c = float(self.lo[0]), float(self.hi[0])
        return poly

    def to_dict(self) -> dict[str, Any]:
        """Return the chosen terms, scaling, coefficients (rad/s), ranges and the CV table."""
        if self.coef is None or self.terms is None or self.lo is None or self.hi is None:
            raise ParameterError("method 'lsq_cv' is not fitted: call fit() or from_dict()")
        return {'method': self.name, 'terms': list(self.terms),
                'coef_rad_s': self.coef.T.tolist(), 't_centre_c': self.t_centre_c,
                't_scale_c': self.t_scale_c, 'rate_scale_c_s': RATE_SCALE_C_S,
                'hysteresis_c': self.hysteresis_c, 'rate_window_s': self.rate_window_s,
                'max_degree': self.max_degree, 'folds': self.folds,
                'widths_c': list(self.widths_c), 'input_min': self.lo.tolist(),
                'input_max': self.hi.tolist(), 'uses_rate': self.uses_rate,
                'cv': self.cv, 'notes': list(self.notes),
                'temperature_range_c': [float(self.lo[0]), float(self.hi[0])]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> 'LeastSquaresCV':
        """Rebuild a fitted model from :meth:`to_dict`."""
        if not isinstance(d, Mapping) or d.get('method') != cls.name:
            raise ParameterError(f'LeastSquaresCV.from_dict needs method {cls.name!r}')
        if float(d['rate_scale_c_s']) != RATE_SCALE_C_S:
            raise ParameterError(f"rate_scale_c_s {d['rate_scale_c_s']!r} is not this "
                                 f"version's {RATE_SCALE_C_S}")
        m = cls(max_degree=int(d['max_degree']), folds=int(d['folds']),
                widths_c=tuple(d['widths_c']), rate_window_s=float(d['rate_window_s']))
        m.terms = tuple(str(n) for n in d['terms'])
        bad = [n for n in m.terms if _term_order(n) is None]
        if bad:
            raise ParameterError(f'unknown lsq_cv term(s) {bad}')
        m.coef = np.asarray(d['coef_rad_s'], dtype=float).reshape(3, len(m.terms)).T.copy()
        m.t_centre_c, m.t_scale_c = float(d['t_centre_c']), float(d['t_scale_c'])
        m.lo, m.hi = np.asarray(d['input_min'], float), np.asarray(d['input_max'], float)
        m.uses_rate = 'r' in m.terms
        m.cv, m.notes = list(d.get('cv', [])), tuple(d.get('notes', ()))
        return m


def _term_order(name: str) -> Any:
    """Sort key of a term name (None: not a term)."""
    if name == '1':
        return (0, 0.0)
    if name.startswith('x') and name[1:].isdigit():
        return (1, float(name[1:]))
    if name in ('r', 'xr'):
        return (2, float(name == 'xr'))
    try:
        return (3, float(name[1:])) if name.startswith('h') and float(name[1:]) > 0 else None
    except ValueError:
        return None


def _cross_validate(stats: Sequence[_Fold], names: Sequence[str],
                    candidates: Sequence[tuple[str, ...]]) -> list[dict[str, Any]]:
    """Held-out mean squared error of every candidate term set, per fold ((rad/s)^2)."""
    total_ata = np.sum([s[0] for s in stats], axis=0)
    total_aty = np.sum([s[1] for s in stats], axis=0)
    rows = []
    for terms in candidates:
        j = [names.index(n) for n in terms]
        fold_mse = []
        for ata, aty, yty, samples in stats:
            coef, _, rank, _ = np.linalg.lstsq((total_ata - ata)[np.ix_(j, j)],
                                               (total_aty - aty)[j], rcond=None)
            if rank < len(j):
                break
            sse = np.sum(yty - 2.0 * np.sum(coef * aty[j], axis=0)
                         + np.einsum('ia,ij,ja->a', coef, ata[np.ix_(j, j)], coef))
            fold_mse.append(float(max(sse, 0.0) / (3.0 * float(samples))))
        else:
            rows.append({'terms': list(terms), 'fold_mse_rad2_s2': fold_mse,
                         'cv_rms_rad_s': float(np.sqrt(np.mean(fold_mse)))})
    if not rows:
        raise InputDataError('no candidate drift basis can be fitted on every fold of the '
                             'training run (T and dT do not vary enough)')
    return rows


def select_terms(rows: Sequence[Mapping[str, Any]]) -> Mapping[str, Any]:
    """
    Pick a candidate by the one-standard-error rule on paired fold differences.

    The candidate with the least mean held-out error is the reference; every candidate whose
    mean excess over it, fold by fold, is within one standard error of that excess (std over the
    folds / sqrt(folds)) is as good as the data can tell; of those the simplest wins: fewest
    terms, then fewest terms in dT and hysteresis (they are extrapolated when a run's dT has
    another sign than in training), then the lower error (Hastie, Tibshirani, Friedman, *The
    Elements of Statistical Learning*, 2nd ed., section 7.10).

    Parameters
    ----------
    rows : sequence of dict
        ``terms`` and ``fold_mse_rad2_s2`` per candidate (:func:`_cross_validate`).

    Returns
    -------
    dict
        The row chosen.

    """
    mse = [np.asarray(r['fold_mse_rad2_s2'], dtype=float) for r in rows]
    best = int(np.argmin([m.mean() for m in mse]))

    def as_good(m: NDArray[np.float64]) -> bool:
        d = m - mse[best]
        return bool(d.mean() <= d.std(ddof=1) / np.sqrt(d.size))

    eligible = [i for i, m in enumerate(mse) if as_good(m)]
    return rows[min(eligible, key=lambda i: (len(rows[i]['terms']),
                                             sum(not _is_t_term(n) for n in rows[i]['terms']),
                                             mse[i].mean()))]


def _is_t_term(name: str) -> bool:
    return name == '1' or (name.startswith('x') and name[1:].isdigit())
