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
report.html in a real browser: headless Chromium loads each tool's page.

Each test asserts no console error, no request leaving the file, every figure drawn (its first
curve's colour on screen) and keeps a full-page screenshot under its tmp_path. Without Chromium
or playwright the tests skip with one line (fail under ``CI=true``): see test/_html_report.py.
"""

from _html_report import check_in_browser
from gyro_noise_ros.cli.analyze import main as analyze_main
import pytest
from test_report_html import (FAST, make_calibration, make_excitation, make_explain,
                              make_reliability, make_thermal_outputs, write_bag)

# slow: a headless Chromium per page (3-8 s each) on top of the tool run that writes it
# (the thermal pair 15-30 s); the same pages' numbers are checked without a browser in
# test_report_html.py, which make test runs.
pytestmark = pytest.mark.slow


@pytest.mark.timeout(300)
def test_analyze_report_renders(tmp_path):
    bags = [write_bag(tmp_path / 'bag_a', 4 * 600 + 50, 200.0, seed=1, drift_rad_s2=1e-6),
            write_bag(tmp_path / 'bag_b', 3 * 600, 200.0, seed=2)]
    out = tmp_path / 'out'
    assert analyze_main([*map(str, bags), '--out', str(out), *FAST]) == 0
    shot = check_in_browser(out / 'report.html', tmp_path, figures=5)
    assert shot.stat().st_size > 10_000


@pytest.mark.timeout(300)
def test_thermal_compare_and_apply_reports_render(tmp_path):
    tmp, _ = make_thermal_outputs(tmp_path)
    check_in_browser(tmp / 'c' / 'report.html', tmp_path / 'compare', figures=3)
    check_in_browser(tmp / 'a' / 'report.html', tmp_path / 'apply', figures=4)


@pytest.mark.timeout(300)
def test_calibrate_report_renders(tmp_path):
    out, _ = make_calibration(tmp_path)
    check_in_browser(out / 'report.html', tmp_path / 'shot', figures=1)


@pytest.mark.timeout(300)
def test_reliability_report_renders(tmp_path):
    out, _ = make_reliability(tmp_path)
    check_in_browser(out / 'report.html', tmp_path / 'shot', figures=2)


@pytest.mark.timeout(300)
def test_excitation_report_renders(tmp_path):
    out, _ = make_excitation(tmp_path)
    check_in_browser(out / 'report.html', tmp_path / 'shot', figures=1)


@pytest.mark.timeout(300)
def test_a_figure_with_nothing_drawn_is_caught(tmp_path):
    """The rendering check can fail: a figure whose curves are all NaN shows only its legend."""
    import numpy as np
    from gyro_noise_ros.htmlreport.figures import series_figure
    from gyro_noise_ros.htmlreport.page import Page, write_report_html

    t = np.arange(10.0)
    empty = series_figure([(name, t, np.full(10, np.nan)) for name in 'abc'], title='empty',
                          x_label='time (s)', y_label='value (1)')
    page = write_report_html(Page(title='blank', data={}, in_short_markdown='## In short',
                                  figures=(('nothing drawn', empty),)), tmp_path / 'blank.html')
    with pytest.raises(AssertionError, match='looks blank'):
        check_in_browser(page, tmp_path, figures=1)


@pytest.mark.timeout(300)
def test_explain_report_renders(tmp_path):
    out, _ = make_explain(tmp_path)
    check_in_browser(out / 'report.html', tmp_path / 'shot', figures=1)
