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
The paper's model on the docs' example: its numbers beside the paper's, and what they cost.

Usage::

    python docs/scripts/thermal_parallel_example.py [--seed 1] [--budget small|paper]
        [--figures docs/figures/thermal]

Three parts, printed as Markdown (docs/thermal_model.md holds the output):

1. **Paper 002's Figure 19 numbers beside the tool's.** The docs' example (trained on
   ``heating``, scored on ``cooling``, 1 h at 20 Hz, seed 1, as
   ``thermal_parallel_held_out.py``) is scored by
   :func:`gyro_noise_ros.thermal.metrics.evaluate_method`. ARW in the paper's unit
   (deg/h/sqrt(Hz) = 60 deg/sqrt(h)) and bias stability (deg/h) before and after, with the
   ratios, beside the paper's 0.531076 -> 5.22502e-3 and 32.7364 -> 0.140403; the ARW gain on
   the noise path, the -3 dB corners and the look-ahead say where the tool's gain comes from.
   Figure ``paper_vs_tool.png``.
2. **The causal story.** The same scoring of three plain filters with the TFPF window's support
   (31 samples): TFPF alone (centred), a centred moving average, and a trailing (causal) moving
   average: the ARW gain of a centred filter, its -3 dB corner and its look-ahead, against the
   delay the causal one pays for the same gain. Figures ``causal_steps.png``,
   ``causal_bandwidth.png``.
3. **A run with a mixed band** (paper Figure 14). A static run has no band where drift and
   noise share a mode (every mode above the lowest holds none of the simulated drift), so the
   classifier correctly finds no mixed mode there. This part builds the signal the paper's
   three classes are for: a 1-Hz run (one cycle/sample = 1 Hz), drift from a temperature ramp,
   a rate-table oscillation at 0.01 Hz with 0.6 of the white noise's std, white noise; the
   model has the options of part 1, a three-mode VMD around drift, oscillation and noise (K,
   alpha and the centre frequencies set here, as MOPSO would need them), a drift model fitted
   on this run's lowest mode, classes at a coarse-graining scale of 16 samples. The model's own
   report figures (Figures 12-17 analogues) go to ``mixed_band/``; the printed numbers are the
   classes, the entropies and the effect of TFPF on the mixed part (error to the clean
   oscillation before and after).
"""

import argparse
import dataclasses
import math
from pathlib import Path

from gyro_noise_ros.plotting import pyplot, save_figure
from gyro_noise_ros.thermal import figures as thermal_figures, report
from gyro_noise_ros.thermal.elman import fit_drift
from gyro_noise_ros.thermal.metrics import evaluate_method
from gyro_noise_ros.thermal.parallel import block_means, ParallelModel
from gyro_noise_ros.thermal.run import temperature_rate_c_s, ThermalRun
from gyro_noise_ros.thermal.simulate import make_profile, simulate_pair
from gyro_noise_ros.thermal.tfpf import tfpf
from gyro_noise_ros.thermal.vmd import vmd
from gyro_noise_ros.units import RAD_TO_DEG
import numpy as np
import scipy.signal

#: Paper 002, abstract and section 4.2 (Figure 19): ARW (deg/h/sqrt(Hz)) and bias stability
#: (deg/h) of the raw and the processed output.
PAPER = {'arw_raw': 0.531076, 'arw_processed': 5.22502e-3,
         'bias_raw': 32.7364, 'bias_processed': 0.140403}
#: MOPSO budget of ``--budget small`` (as thermal_parallel_held_out.py).
SMALL_BUDGET = {'n_particles': 10, 'iterations': 4, 'refine_points': 4, 'refine_polish': 4}
#: The TFPF window of the parallel model (its default), the support of the plain filters.
WINDOW = 31


class _Filter:
    """A fixed filter applied per axis, as a ThermalMethod (nothing to fit)."""

    def __init__(self, name, causal, fn):
        self.name, self.causal, self._fn = name, causal, fn

    def fit(self, run, *, rng):
        pass

    def apply(self, run):
        g = np.asarray(run.gyro_rad_s, dtype=float)
        return np.column_stack([self._fn(g[:, a]) for a in range(3)])

    def to_dict(self):
        return {}


def _filters():
    box = np.ones(WINDOW) / WINDOW
    return [_Filter('TFPF alone (centred)', False, lambda x: tfpf(x, window=WINDOW)),
            _Filter('moving average, centred', False,
                    lambda x: np.convolve(np.pad(x, WINDOW // 2, mode='reflect'), box,
                                          mode='valid')),
            _Filter('moving average, trailing', True,
                    lambda x: scipy.signal.lfilter(box, [1.0], x - x[0]) + x[0])]


def _bs(m):
    return report.bias_stability_cell(m, '.3g')


def part1(model, test, figures):
    """Score the fitted model on the test run; print the paper's numbers beside the tool's."""
    doc, _, _ = evaluate_method(model, test)
    print('### Paper 002 Figure 19 beside the tool (docs example: heating -> cooling, seed '
          f'{test.name})\n')
    print('| | ARW raw (deg/h/sqrt(Hz)) | ARW processed | ARW ratio | ARW gain, noise path | '
          'bias stability raw (deg/h) | processed | ratio | -3 dB 1 deg/s / noise-sized (Hz) '
          '| look-ahead (s) |')
    print('|---|---|---|---|---|---|---|---|---|---|')
    p = PAPER
    print(f'| paper 002 | {p["arw_raw"]:.4g} | {p["arw_processed"]:.3g} | '
          f'{p["arw_processed"] / p["arw_raw"]:.3g} | not given | {p["bias_raw"]:.4g} | '
          f'{p["bias_processed"]:.3g} | {p["bias_processed"] / p["bias_raw"]:.3g} | not given '
          '| not given (offline) |')
    ratios = []
    for axis, v in doc['axes'].items():
        raw, proc, bw = v['raw'], v['processed'], v['bandwidth']
        small = v.get('bandwidth_small_signal')
        arw_r, arw_p = raw['arw_deg_sqrt_h'] * 60.0, proc['arw_deg_sqrt_h'] * 60.0
        bs_ratio = proc['bias_stability_deg_h'] / raw['bias_stability_deg_h']
        ratios.append((arw_p / arw_r, bs_ratio, v['noise_path']['arw_gain']))
        print(f'| tool, axis {axis} | {arw_r:.4g} | {arw_p:.3g} | {arw_p / arw_r:.3g} | '
              f'{v["noise_path"]["arw_gain"]:.3g} | {_bs(raw)} | {_bs(proc)} | '
              f'{bs_ratio:.3g} | {report.bandwidth_cell(bw)} / '
              f'{report.bandwidth_cell(small)} | {bw["step_lead_s"]:.3g} |')
    print('\n(`<=`: the readout saw no minimum, an upper bound.)\n')
    if figures:
        plt = pyplot()
        fig, panel = plt.subplots(figsize=(8, 4.5))
        labels = ['ARW', 'bias stability']
        paper = [p['arw_processed'] / p['arw_raw'], p['bias_processed'] / p['bias_raw']]
        x = np.arange(2)
        panel.bar(x - 0.3, paper, 0.15, label='paper 002 (its test run)', color='k')
        for i, (axis, r) in enumerate(zip('xyz', ratios)):
            panel.bar(x - 0.1 + 0.15 * i, [r[0], r[1]], 0.15, label=f'tool, axis {axis}')
        panel.bar(x[:1] + 0.4, [np.mean([r[2] for r in ratios])], 0.15, color='tab:gray',
                  label='tool, ARW gain on the noise path (mean of axes)')
        panel.set_yscale('log')
        panel.set_xticks(x, labels)
        panel.set_ylabel('processed / raw (ratio, log)')
        panel.grid(True, which='both', axis='y', alpha=0.3)
        panel.legend(fontsize=7)
        fig.suptitle('Paper 002 Fig. 19 ratios beside the tool on the docs example '
                     '(heating -> cooling, 20 Hz)', fontsize=10)
        save_figure(fig, Path(figures) / 'paper_vs_tool.png', dpi=100, tight=True)


def part2(model, test, figures):
    """Score the model and three plain filters of the TFPF window's support."""
    print(f'### The causal story: centred and trailing filters of {WINDOW} samples '
          f'({WINDOW / test.rate_hz:.2f} s at {test.rate_hz:g} Hz)\n')
    print('| method | ARW gain, noise path (x) | -3 dB 1 deg/s / noise-sized (Hz) | '
          'step delay 50 % (s) | look-ahead before the step (s) | live-capable |')
    print('|---|---|---|---|---|---|')
    steps, responses = {}, {}
    for method in [model] + _filters():
        doc, _, curves = evaluate_method(method, test)
        v = doc['axes']['x']
        bw = v['bandwidth']
        print(f'| {method.name} | {v["noise_path"]["arw_gain"]:.3g} | '
              f'{report.bandwidth_cell(bw)} / '
              f'{report.bandwidth_cell(v.get("bandwidth_small_signal"))} | '
              f'{bw["step_delay_50_s"]:.3g} | {bw["step_lead_s"]:.3g} | '
              f'{"yes" if v["verdict"]["live_capable"] else "no"} |')
        steps[method.name] = {'x': curves['x']['step']}
        responses[method.name] = {'x': curves['x']['frequency']}
    print()
    if figures:
        thermal_figures.plot_steps(Path(figures) / 'causal_steps.png', steps,
                                   title='step response, axis x: centred filters answer before '
                                         'the step, the trailing one after it')
        thermal_figures.plot_bandwidth(Path(figures) / 'causal_bandwidth.png', responses,
                                       title='response to injected motion, axis x')


def part3(model, figures):
    """Put a run with a known mixed band through the apply of the model and its figures."""
    rate, n = 1.0, 24000
    rng = np.random.default_rng(3)
    t = np.arange(n) / rate
    temp = 20.0 + 20.0 * np.clip(t / t[-1] * 1.5 - 0.25, 0.0, 1.0)
    noise_std = 1e-3
    tone = 0.6 * noise_std * np.sin(2 * np.pi * 0.01 * t + 0.3)
    drift = np.radians(0.01) * (temp - 30.0)
    gyro = (drift + tone)[:, None] + noise_std * rng.standard_normal((n, 3))
    run = ThermalRun(t_s=t, gyro_rad_s=gyro, temperature_c=temp, rate_hz=rate,
                     name='mixed-band example')
    d = model.to_dict()
    opts = dict(d['options'], entropy_scale=16)
    mixed = ParallelModel.from_dict(dict(d, options=opts, rate_hz=rate))
    axes = []
    rate_c_s = temperature_rate_c_s(t, temp)
    q = 12
    for a, ax in enumerate(d['axes']):
        # K and alpha around drift, oscillation and noise; the drift model fitted on this
        # run's lowest mode (in-sample: this part is about the classes and TFPF)
        low = vmd(gyro[:, a], k=3, alpha=10000.0, solver='exact', max_iter=30,
                  center_freqs=[0.0, 0.01, 0.25]).modes[0]
        drift_model = fit_drift(block_means(np.c_[temp, rate_c_s], q), block_means(low, q),
                                dt_s=q / rate, rng=np.random.default_rng(a), epochs=2,
                                weight_decay=1e-3)
        axes.append(dict(ax, k=3, alpha=10000.0, center_freqs_hz=[0.0, 0.01, 0.25],
                         elman=drift_model.to_dict()))
    mixed.axes = axes
    mixed.apply(run)
    print('### A run with a mixed band (the Figure 14 of the paper)\n')
    print('| axis | classes | sample entropy at scale 16 | TFPF: error to the clean '
          'oscillation before -> after (rad/s) | change |')
    print('|---|---|---|---|---|')
    for a, info in enumerate(mixed.last_info):
        dec = vmd(gyro[:, a], k=3, alpha=10000.0, solver='exact', center_freqs=[0, 0.01, 0.25],
                  max_iter=int(opts['apply_vmd_iter']))
        clean = vmd(tone, k=3, alpha=10000.0, solver='exact', max_iter=1,
                    center_freqs=dec.center_freqs).modes
        sel = np.array([c == 'mixed' for c in info['classes']])
        before = dec.modes[sel].sum(axis=0)
        after = tfpf(before, window=int(opts['tfpf_window'])) if sel.any() else before
        target = clean[sel].sum(axis=0)
        e0 = math.sqrt(np.mean((before - target) ** 2))
        e1 = math.sqrt(np.mean((after - target) ** 2))
        print(f'| {"xyz"[a]} | {", ".join(info["classes"])} | '
              f'{", ".join(f"{e:.2f}" for e in info["sample_entropy"])} | {e0:.3g} -> '
              f'{e1:.3g} ({20 * math.log10(e0 / e1):.2f} dB) | '
              f'{math.sqrt(np.mean((after - before) ** 2)) / np.std(before):.3f} of its rms |')
    print()
    if figures:
        out = Path(figures) / 'mixed_band'
        out.mkdir(parents=True, exist_ok=True)
        for name, caption in mixed.report_figures(run, out):
            if name is not None:
                print(f'- `{out / name}`: {caption}')
        thermal_figures.plot_mode_classes(
            out / 'fig13_classes.png', mixed.last_info,
            title='mixed-band example: sample entropy (scale 16) and class')
        print()


def main():
    """Fit once on the docs' example and run the three parts."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[1])
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--budget', choices=('small', 'paper'), default='small')
    parser.add_argument('--figures', default='docs/figures/thermal')
    parser.add_argument('--parts', default='123')
    args = parser.parse_args()
    if args.figures:
        Path(args.figures).mkdir(parents=True, exist_ok=True)
    (_, train, _), (_, test, _) = simulate_pair(
        seed=args.seed, rate_hz=20.0, hours=1.0, profile=make_profile('heating'),
        test_profile=make_profile('cooling'))
    test = dataclasses.replace(test, name=str(args.seed))
    model = ParallelModel(**(SMALL_BUDGET if args.budget == 'small' else {}))
    model.fit(train, rng=np.random.default_rng(args.seed))
    print(f'Parallel model, MOPSO budget {args.budget}: K = '
          f'{", ".join(str(ax["k"]) for ax in model.axes)}, classes on the training run '
          f'{[ax["classes"] for ax in model.axes]}\n')
    if '1' in args.parts:
        part1(model, test, args.figures)
    if '2' in args.parts:
        part2(model, test, args.figures)
    if '3' in args.parts:
        part3(model, args.figures)
    print(f'(units: ARW from deg/sqrt(h) x 60; the tool in rad/s inside, '
          f'{RAD_TO_DEG:.4f} deg/rad)')


if __name__ == '__main__':
    main()
