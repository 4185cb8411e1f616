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

"""The verdict lines report.md, compare.md and report.html open with (synthetic documents)."""

from gyro_noise_ros.thermal.report import apply_verdict, compare_verdict


def _apply_doc(*, warnings=(), in_sample=False, drift_ratio=0.01):
    axes = {a: {'verdict': {'residual_drift_ratio': drift_ratio}} for a in 'xyz'}
    return {'method': 'lsq_cv', 'axes': axes, 'warnings': list(warnings), 'in_sample': in_sample,
            'rate_mismatch': False,
            'yardstick': {'floor': 'white', 'over_floor': [1.3, 2.0, None],
                          'over_poly3': [0.06, 0.1, 0.2]}}


def test_apply_verdict_states_the_yardstick_and_warns_on_what_weakens_it():
    level, text = apply_verdict(_apply_doc())
    assert level == 'OK'
    assert text == ('`lsq_cv` applied: residual drift **1.3, 2, n/a x the noise floor** (the '
                    "run's white noise) on x, y, z, 0.06, 0.1, 0.2 x poly3.")
    level, text = apply_verdict(_apply_doc(warnings=['69 % of the run lies outside']))
    assert level == 'WARN' and text.endswith('; **69 % of the run lies outside**.')
    level, text = apply_verdict(_apply_doc(in_sample=True))
    assert level == 'WARN' and '**in-sample**' in text
    level, text = apply_verdict(_apply_doc(drift_ratio=1.2))
    assert level == 'WARN' and text.endswith('residual drift above the raw one on x, y, z.')


def _compare_doc(*, outside=0.0, errors=None, best='lsq_cv'):
    warning = f'{100 * outside:.3g} % of the run lies outside' if outside > 0.05 else None
    methods = {n: {'range': {'fraction_outside': outside, 'warning': warning}}
               for n in ('lsq_cv', 'poly3')}
    return {'best_held_out': {'method': best},
            'ranking': [{'method': 'lsq_cv', 'mean_over_floor': 1.52, 'mean_over_poly3': 0.059},
                        {'method': 'poly3', 'mean_over_floor': 25.0, 'mean_over_poly3': 1.0}],
            'methods': methods, 'errors': errors or {},
            'warnings': ['the temperature stream is in kelvin'] + (
                [f'{n}: {warning}' for n in methods] if warning else [])}


def test_compare_verdict_names_the_best_its_ratios_and_the_extrapolation():
    level, text = compare_verdict(_compare_doc())
    assert level == 'WARN'  # the kelvin warning, said once
    assert text.startswith('best on the held-out run: **`lsq_cv`**, 1.5 x the noise floor, '
                           '0.059 x poly3 (mean over the axes); ranked by x noise floor: '
                           '1. lsq_cv, 2. poly3; **the temperature stream is in kelvin**')
    doc = _compare_doc(outside=0.69)
    doc['warnings'] = doc['warnings'][1:]
    level, text = compare_verdict(doc)
    assert level == 'WARN' and text.endswith(
        '**extrapolating** over more than 5 % of the test run (outside the trained range of T '
        'or dT): lsq_cv 69 %, poly3 69 %.')
    doc = _compare_doc()
    doc['warnings'] = []
    assert compare_verdict(doc)[0] == 'INFO'
    doc['errors'] = {'parallel': 'failed'}
    assert compare_verdict(doc) == ('WARN', compare_verdict(_compare_doc())[1].split(
        '; **the')[0] + '; not scored: parallel.')
    assert compare_verdict(_compare_doc(best=None))[1].startswith(
        'no live-capable full-bandwidth method was scored')
