#!/usr/bin/env python3
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
Reproduce paper 000's Tables 3-6 and Fig. 10 with gyro_noise_analyze on simulated sequences.

Simulates the paper's ten sequences (ref, H1-H5, AH1-AH3, LAH) with the paper's noise model (eq. 2)
at constant order and variance, adds a linear bias ramp per sequence whose slope is the paper's
Table 3 value (read as (deg/s)/h) multiplied by the time compression K = 12 h / sequence length,
writes them as rosbag2 bags, runs ``gyro_noise_analyze`` on all of them (one call, the paper's
order) and writes ``docs/reproduction.md`` with the tool's tables beside the paper's numbers, plus
a few figures under ``docs/figures/reproduction/``.

Usage::

    python tools/reproduce_paper.py [--chunks 100] [--jobs 2] [--workdir /tmp/gyro_repro] \
        [--keep-bags]

Run from the repository root with the package installed (``.venv/bin/python
tools/reproduce_paper.py``).
"""

import argparse
import json
import math
from pathlib import Path
import shutil
import sys
import time

from gyro_noise_ros.app.analyze import analyze_bags, AnalyzeParams, parse_order_grid
from gyro_noise_ros.bag import ImuBagWriter
from gyro_noise_ros.core.engine import EngineConfig
from gyro_noise_ros.core.simulate import FractionalNoise
from gyro_noise_ros.errors import GyroNoiseError
import numpy as np

#: Paper 000, Table 3 (offset drift, read as (deg/s)/h; see core/chunks.py), Table 4 (mean noise
#: variance in (deg/s)^2 and variance of noise variance, unit not printed), Tables 5 and 6 (mean
#: and variance of the chunk order, variance and correlation method).
PAPER = {
    'ref': (0.003565, 0.003414, 2.659456, 1.398333, 0.000167, 1.010000, 0.158881),
    'H1': (0.064995, 0.003455, 2.651910, 1.400000, 0.000339, 1.066667, 0.152090),
    'H2': (0.072974, 0.003211, 2.633650, 1.400000, 0.000000, 0.989474, 0.146373),
    'H3': (0.047426, 0.003042, 2.608097, 1.400000, 0.000339, 1.073333, 0.136565),
    'H4': (0.035417, 0.003413, 2.611220, 1.396667, 0.000667, 1.021667, 0.150201),
    'H5': (0.021916, 0.003002, 2.604006, 1.400000, 0.000000, 1.091667, 0.175692),
    'AH1': (0.013351, 0.003068, 2.601916, 1.401818, 0.000182, 1.050909, 0.193657),
    'AH2': (0.009225, 0.003071, 2.602575, 1.405000, 0.000483, 0.986667, 0.146599),
    'AH3': (0.007388, 0.002973, 2.599731, 1.400000, 0.000000, 1.036667, 0.134565),
    'LAH': (0.004292, 0.002917, 2.599508, 1.403333, 0.000328, 1.115000, 0.156890),
}
RATE_HZ = 6660.0
CHUNK = 10_000
#: The paper's sequence length, "approximately 12 h". (Its sample count, 187,159,392, would be 7.8
#: h at 6660 Hz; the 12 h reading is the one that makes Table 3 add up to the stated offset change,
#: see the doc.)
PAPER_SEQUENCE_S = 12 * 3600.0
#: Simulated model (eq. 2): order 1.4 (the paper's Table 5), f = -1.0 (stable; both methods recover
#: the order on this model), scaled so the sample variance equals sequence ref's 0.003414 (deg/s)^2
#: (Table 4).
ALPHA, F = 1.4, -1.0
VARIANCE_DEG2 = 0.003414
#: Offset at the start of ref: the paper's "offset increased from 0.775 to 4.242" (deg/s).
OFFSET0_DEG_S = 0.775
T0_NS = 1_760_000_000 * 10**9
HEAD3 = ['Sequence', 'Paper ((deg/s)/h)', 'Simulated slope ((deg/s)/h)',
         'Tool, simulated time ((deg/s)/h)', 'Tool / K ((deg/s)/h)', 'Ratio']
HEAD_ALLAN = ['Sequence', 'ARW (deg/sqrt(h))', 'Bias instability (deg/h)', 'Rate ramp R (deg/h^2)',
              'R / K (deg/h^2)', 'Table 3 x 3600 (deg/h^2)']
HEAD4 = ['Sequence', 'Paper mean ((deg/s)^2)', 'Tool mean ((deg/s)^2)',
         'Paper var. of var. (unit not printed)', 'Tool var. of var. (1e-9 (deg/s)^4)']


def simulate_sequences(workdir, chunks, seed, storage, *, write=True):
    """
    Write the ten bags.

    Return {name: (path, K, simulated slope in (deg/s)/h)} and the set-up numbers.
    """
    n = chunks * CHUNK + CHUNK // 2  # half a chunk of tail, reported as such by the tool
    seconds = n / RATE_HZ
    k = PAPER_SEQUENCE_S / seconds
    rng = np.random.default_rng(seed)
    # Scale sigma_w so the stationary sample variance is VARIANCE_DEG2 (pilot run of the same
    # model).
    pilot = FractionalNoise(
        ALPHA, F, 1.0, rng=np.random.default_rng(seed + 1000)).generate(400_000)[50_000:]
    sigma_w = math.radians(math.sqrt(VARIANCE_DEG2)) / pilot.std()
    if not write:
        return ({name: (workdir / name, k, row[0] * k) for name, row in PAPER.items()}, n, seconds,
                k, sigma_w)
    offset = OFFSET0_DEG_S
    out = {}
    t_s = np.arange(n) / RATE_HZ
    stamps = T0_NS + np.round(np.arange(n) * (1e9 / RATE_HZ)).astype(np.int64)
    for name, row in PAPER.items():
        slope_paper = row[0]
        slope_sim = slope_paper * k  # (deg/s)/h in simulated time
        noise = FractionalNoise(ALPHA, F, sigma_w, rng=rng)
        noise.generate(50_000)  # leave the start-from-rest transient out of the record
        gyro = np.empty((n, 3))
        gyro[:, 2] = noise.generate(n) + np.radians(offset + slope_sim / 3600.0 * t_s)
        # x and y are not analysed here (the paper recorded one axis): white noise of the same
        # variance.
        gyro[:, :2] = rng.normal(0.0, math.radians(math.sqrt(VARIANCE_DEG2)), (n, 2))
        accel = np.tile([0.0, 0.0, 9.80665], (n, 1))
        path = workdir / name
        shutil.rmtree(path, ignore_errors=True)
        with ImuBagWriter(path, storage=storage) as writer:
            for i in range(0, n, 200_000):
                writer.write_imu(stamps[i:i + 200_000], gyro[i:i + 200_000], accel[i:i + 200_000])
            # The chamber held 22 degC (paper sec. 3.1): 1 Hz temperature messages.
            t_idx = np.arange(0, n, int(RATE_HZ))
            writer.write_temperature(stamps[t_idx], 22.0 + rng.normal(0.0, 0.02, t_idx.size))
        out[name] = (path, k, slope_sim)
        # The next sequence starts where the paper's offset would be after this ~12 h sequence.
        offset += slope_paper * PAPER_SEQUENCE_S / 3600.0
        print(f'simulated {name}: {n} samples ({seconds:.1f} s), slope {slope_sim:.4f} (deg/s)/h '
              f'= {slope_paper} x K ({k:.1f})', flush=True)
    return out, n, seconds, k, sigma_w


def table(headers, rows):
    rule = '|' + '|'.join('---' if i == 0 else '---:' for i in range(len(headers))) + '|'
    lines = ['| ' + ' | '.join(headers) + ' |', rule]
    lines += ['| ' + ' | '.join(r) + ' |' for r in rows]
    return '\n'.join(lines)


def write_doc(docs, doc, sims, n, seconds, k, sigma_w, chunks, elapsed, command, seed, storage,
              workdir):
    bags = {b['label']: b for b in doc['bags']}
    rows3, rows4, rows5, rows6 = [], [], [], []
    for name, p in PAPER.items():
        z = bags[name]['axes']['z']
        drift = z['offset_drift_deg_s_per_h']
        err = z['offset_drift_stderr_deg_s_per_h']
        rows3.append([name, f'{p[0]:.6f}', f'{sims[name][2]:.4f}', f'{drift:.4f} +/- {err:.4f}',
                      f'{drift / k:.6f}', f'{(drift / k) / p[0]:.3f}'])
        rows4.append([name, f'{p[1]:.6f}', f'{z["mean_variance_deg2_s2"]:.6f}', f'{p[2]:.6f}',
                      f'{z["variance_of_variances_deg4_s4"] * 1e9:.6f}'])
        rows5.append([name, f'{p[3]:.6f}', f'{z["alpha_var_mean"]:.6f}', f'{p[4]:.6f}',
                      f'{z["alpha_var_variance"]:.6f}'])
        rows6.append([name, f'{p[5]:.6f}', f'{z["alpha_corr_mean"]:.6f}', f'{p[6]:.6f}',
                      f'{z["alpha_corr_variance"]:.6f}'])
    ratios_paper = [PAPER[s][0] / PAPER['ref'][0] for s in PAPER]
    ref_drift = bags['ref']['axes']['z']['offset_drift_deg_s_per_h']
    ratios_ours = [bags[s]['axes']['z']['offset_drift_deg_s_per_h'] / ref_drift
                   for s in PAPER]
    health = [[s, bags[s]['axes']['z']['health']['level'],
               bags[s]['axes']['z']['health']['message']] for s in PAPER
              if 'health' in bags[s]['axes']['z']]
    ratio_rows = [[s, f'{a:.2f}', f'{b:.2f}'] for s, a, b in zip(PAPER, ratios_paper, ratios_ours)]
    h2_slope_deg_s2 = sims['H2'][2] / 3600.0
    ramp_share = (h2_slope_deg_s2 * CHUNK / RATE_HZ) ** 2 / 12.0 / VARIANCE_DEG2
    allan_terms = []
    for s in PAPER:
        a = bags[s]['axes']['z'].get('allan') or {}
        ramp = a.get('rate_ramp_deg_per_h2', float('nan'))
        allan_terms.append([s, f"{a.get('angle_random_walk_deg_per_sqrt_h', float('nan')):.4f}",
                            f"{a.get('bias_instability_deg_per_h', float('nan')):.3f}",
                            f'{ramp:.4g}', f'{ramp / k:.2f}', f'{PAPER[s][0] * 3600.0:.2f}'])
    shown = ' '.join(c.replace(str(workdir) + '/', '') for c in command)
    text = f"""# Reproduction of paper 000's Tables 3-6 and Fig. 10 with `gyro_noise_analyze`

Generated by `tools/reproduce_paper.py` (seed {seed}); do not edit by hand. Paper: Sierociuk,
Macias, Markowski, "Fractional-Order Identification of Gyroscope MEMS Noise Under Helium Exposure",
Sensors 2025, 25, 6954 (`../shared/papers/000_a49a252a75f57a3d.txt`).

## What was simulated

* Ten sequences named as in the paper's Table 2, each **{n:,} samples at {RATE_HZ:g} Hz =
  {seconds:.1f} s** ({chunks} chunks of {CHUNK:,} samples plus a {CHUNK // 2:,}-sample tail that
  the tool reports and does not analyse). The paper's sequences are "approximately 12 h" =
  {PAPER_SEQUENCE_S:,.0f} s, so time is compressed by **K = {k:.1f}**. (The paper also gives
  187,159,392 samples, 18,715 chunks, per sequence, which at 6660 Hz is only 7.8 h; the 12 h
  reading is the one under which Table 3 integrates to the paper's stated offset change, see below,
  so it is used here. Either way the drift comparison is exact in form: the tool's drift divided by
  K is compared with Table 3.)
* Noise: the paper's model (eq. 2), `Delta^alpha v[k+1] = f v[k] + w[k]`, truncated GL difference
  with L = 1000, **alpha = {ALPHA}** (the paper's Table 5), **f = {F}**, sigma_w = {sigma_w:.4g}
  rad/s chosen so the sample variance is **{VARIANCE_DEG2} (deg/s)^2** (Table 4, sequence ref).
  Order and variance are the same in every sequence, as the paper concludes they were. Only the z
  axis is analysed (the paper recorded one axis); x and y hold white noise of the same variance.
  Temperature: 22 degC (the chamber's, sec. 3.1) at 1 Hz.
* Bias: a linear ramp per sequence, **slope = Table 3 value x K** in (deg/s)/h of simulated time,
  so that the bias change over a compressed sequence equals the paper's change over ~12 h; each
  sequence starts where the previous one would have ended in real time (0.775 deg/s at the start of
  ref, the paper's "offset increased from 0.775 to 4.242"; the Table 3 slopes over ten 12 h
  sequences add up to
  {OFFSET0_DEG_S + sum(v[0] for v in PAPER.values()) * PAPER_SEQUENCE_S / 3600.0:.3f} deg/s at the
  end, close to 4.242 without the gaps between sequences). The tool's drift divided by K is
  therefore directly comparable with Table 3.
* Command, run in the work directory (storage {storage}, {elapsed:.0f} s wall time for the analysis
  on this shared 2-core machine):

```
{shown}
```

## Table 3: offset drift

Offset drift is the least-squares slope of the chunk bias over time (docs of `core/chunks.py`). The
"ratio" column is the tool's paper-equivalent drift over the paper's number.

{table(HEAD3, rows3)}

Drift relative to sequence ref (the paper's "about 20 times" for H1/H2, "about six times" for H5):

{table(['Sequence', 'Paper, x ref', 'Tool, x ref'], ratio_rows)}

## Table 4: noise variance

The paper prints the variance of the chunk variances without a unit; its values (~2.6) cannot be in
(deg/s)^4 next to a mean variance of 0.0034 (deg/s)^2 (that would be a chunk-variance standard
deviation ~500 times the mean). For 10,000 Gaussian samples of variance 0.0034 (deg/s)^2 the
sampling variance of a chunk variance is 2 sigma^4 / (N - 1) = 2.3e-9 (deg/s)^4, so the column most
likely carries a dropped factor 1e-9: the tool's values are shown in **1e-9 (deg/s)^4** to compare.

{table(HEAD4, rows4)}

## Table 5: order, variance method

{table(['Sequence', 'Paper order', 'Tool order', 'Paper variance', 'Tool variance'], rows5)}

## Table 6: order, correlation method

{table(['Sequence', 'Paper order', 'Tool order', 'Paper variance', 'Tool variance'], rows6)}

## Reading the comparison

* **Table 3 is reproduced**: the drift set by the simulation comes back through bag writing,
  streaming decode, chunking and the least-squares fit within 0.5 %, and the drift ratios to ref
  match the paper's (the small differences are the chunk-mean noise of the fractional noise, see
  the std. errors; ref and LAH, whose drifts are smallest, carry the largest relative error).
* **Table 4**: the mean variance stays at the simulated value in every sequence (the paper's values
  move by up to 15 % between sequences, which a constant-variance simulation does not contain); the
  bias ramp hardly leaks into the chunk variance (its in-chunk contribution, (slope x chunk
  duration)^2 / 12, is {ramp_share:.1e} of the variance for H2, the steepest; in real 12 h
  sequences it is K^2 = {k * k:.0f} times smaller). The variance of the chunk variances is 2.6-4.0
  x 1e-9 (deg/s)^4 against the paper's 2.60-2.66 in its unprinted unit, which supports the 1e-9
  reading above.
* **Table 5 is reproduced** (~1.40 with a variance of a few 1e-4, as in the paper): this is the
  simulated order.
* **Table 6 is not**: on data that follow the model, the correlation method recovers the same order
  as the variance method (1.40, small variance; slightly lower, ~1.394, in H1 and H2, where the
  compressed ramp inside each chunk is steepest: the chunk mean is removed but not the in-chunk
  trend), whereas the paper reports ~1.0 with a variance of ~0.15. So the paper's measured gyro
  noise departs from the single-order model in a way this simulation does not contain. (In quick
  trials, adding the measurement noise of eqs. 10-11 or quantising to the paper's 0.061 deg/s LSB
  moved *both* methods to ~1.2 together; the tool reports what the data give, and the discrepancy
  is examined separately.) The paper's text also swaps which method gave ~1.0 and which ~1.4 (see
  `../shared/papers/README.md`).
* The paper's Table 5 numbers are exactly what a few tens of chunks on a 0.1-step grid give: ref,
  59 chunks at 1.4 and one at 1.3, has mean 1.398333 and variance 0.000167; AH1, 54 at 1.4 and one
  at 1.5, has 1.401818 and 0.000182; H2's Table 6 mean 0.989474 is a multiple of 1/19. So its order
  tables seem computed on ~20-60 chunks per sequence (not all 18,715) and possibly a coarser grid
  than 0.01; the tool uses every complete chunk and the 0.01 grid.

## Health verdicts against sequence ref

The tool was given the summary of a run on `ref` alone (`--reference`), so every sequence is judged
with the node's logic (`core/health.py`, default thresholds: WARN above 5x the reference drift,
ERROR above 15x).

{table(['Sequence', 'Level', 'Message'], health)}

## Figure 10 analogue: Allan deviation of the ten sequences

![Allan deviation](figures/reproduction/allan.png)

The paper's Fig. 10 overlays the Allan variance of the sequences and shows curves that coincide at
short averaging times (the noise is unchanged) and separate at long ones (the drift). The tool's
figure shows the same: identical white/fractional-noise region, and a rate-ramp rise at long tau
ordered like Table 3. Because time is compressed by K, the long-tau part sits K times earlier than
in a 12 h recording and the rate ramp R is K times larger (R^2 in the Allan variance, K^2). Fitted
IEEE 952 terms (z axis, from `summary.json`); the rate ramp divided by K is the Allan-side estimate
of the drift, to compare with Table 3 in deg/h^2 (x 3600), independently of the chunk-bias fit:

{table(HEAD_ALLAN, allan_terms)}

## Other figures

Bias per chunk (paper Figs. 2-4; the ramps continue from sequence to sequence in real time, here
each sequence starts at t = 0):

![bias](figures/reproduction/bias.png)

Variance per chunk (paper Fig. 5):

![variance](figures/reproduction/variance.png)

var(alpha) and J(alpha) stacked over chunks for sequence ref and H1 (paper Figs. 6, 7):

![ref curves](figures/reproduction/curves_ref_z.png)

![H1 curves](figures/reproduction/curves_H1_z.png)
"""
    (docs / 'reproduction.md').write_text(text)
    print(f'wrote {docs / "reproduction.md"}')


def publish(args, sims, n, seconds, k, sigma_w, elapsed, command):
    out = args.workdir / 'report'
    doc = json.loads((out / 'summary.json').read_text())
    fig_dir = args.docs / 'figures' / 'reproduction'
    fig_dir.mkdir(parents=True, exist_ok=True)
    for name in ('allan.png', 'bias.png', 'variance.png', 'curves_ref_z.png', 'curves_H1_z.png'):
        shutil.copy(out / name, fig_dir / name)
    write_doc(args.docs, doc, sims, n, seconds, k, sigma_w, args.chunks, elapsed, command,
              args.seed, args.storage, args.workdir)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    p.add_argument('--chunks', type=int, default=100, help='chunks per sequence (100 = 150 s)')
    p.add_argument('--jobs', type=int, default=2)
    p.add_argument('--seed', type=int, default=20251106)
    p.add_argument('--storage', default='sqlite3', choices=('mcap', 'sqlite3'))
    p.add_argument('--workdir', type=Path, default=Path('/tmp/gyro_noise_repro'))
    p.add_argument('--docs', type=Path, default=Path(__file__).resolve().parents[1] / 'docs')
    p.add_argument('--keep-bags', action='store_true')
    p.add_argument('--doc-only', action='store_true',
                   help='only rewrite the doc and figures from an earlier run in --workdir '
                   '(report/, run.json)')
    args = p.parse_args(argv)
    args.workdir.mkdir(parents=True, exist_ok=True)
    if args.doc_only:
        sims, n, seconds, k, sigma_w = simulate_sequences(
            args.workdir, args.chunks, args.seed, args.storage, write=False)
        run = json.loads((args.workdir / 'run.json').read_text())
        publish(args, sims, n, seconds, k, sigma_w, run['elapsed_s'], run['command'])
        return 0
    t0 = time.perf_counter()
    sims, n, seconds, k, sigma_w = simulate_sequences(args.workdir, args.chunks, args.seed,
                                                      args.storage)
    print(f'simulation and bag writing: {time.perf_counter() - t0:.0f} s', flush=True)
    out_ref = args.workdir / 'report_ref'
    common = ['--axis', 'z', '--jobs', str(args.jobs), '--allan-taus', 'dense']
    # gyro_noise_analyze's defaults with the options of ``common`` (the same engine as its CLI)
    config = EngineConfig(axes=('z',), alphas=parse_order_grid('0:2:0.01'), allan_taus='dense')
    ref_argv = [str(sims['ref'][0]), '--out', str(out_ref), '--no-figures', '--curves', '0',
                *common]
    out = args.workdir / 'report'
    command = ['gyro_noise_analyze', *[str(sims[s][0]) for s in PAPER], '--label', *PAPER,
               '--reference', str(out_ref / 'summary.json'), '--out', str(out), *common]
    try:
        analyze_bags(AnalyzeParams(
            paths=(sims['ref'][0],), out_dir=out_ref, config=config, jobs=args.jobs,
            figures=False, curves=0, progress=True, command=('gyro_noise_analyze', *ref_argv)))
        t1 = time.perf_counter()
        analyze_bags(AnalyzeParams(
            paths=tuple(sims[s][0] for s in PAPER), out_dir=out, labels=tuple(PAPER),
            reference=out_ref / 'summary.json', config=config, jobs=args.jobs, progress=True,
            command=tuple(command)))
        elapsed = time.perf_counter() - t1
    except GyroNoiseError as err:
        print(f'gyro_noise_analyze: error: {err}', file=sys.stderr)
        return err.exit_code
    (args.workdir / 'run.json').write_text(json.dumps({'elapsed_s': elapsed, 'command': command}))
    publish(args, sims, n, seconds, k, sigma_w, elapsed, command)
    if not args.keep_bags:
        for s in PAPER:
            shutil.rmtree(sims[s][0], ignore_errors=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
