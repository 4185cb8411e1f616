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

"""The number helpers of every document and report, on values written out by hand."""

import json
import math

from gyro_noise_ros.formatting import finite_list, finite_or_none, fmt_or_na, percent, plus_minus
import numpy as np


def test_finite_or_none_is_what_json_can_hold():
    assert finite_or_none(None) is None
    for bad in (math.nan, math.inf, -math.inf, np.float64('nan')):
        assert finite_or_none(bad) is None
    v = finite_or_none(np.float32(0.5))
    assert v == 0.5 and type(v) is float
    assert finite_or_none(-0.0) == 0.0 and math.copysign(1.0, finite_or_none(-0.0)) < 0
    doc = finite_list(np.array([[1.0, np.nan], [np.inf, 2]]))
    assert doc == [1.0, None, None, 2.0]
    assert finite_list([1, None]) == [1.0, None]
    json.dumps(doc, allow_nan=False)  # a document of these never holds NaN


def test_text_forms():
    assert fmt_or_na(None, '.3f') == 'n/a'
    assert fmt_or_na(1.23456, '.3f') == '1.235'
    assert plus_minus(None, 1.0, '.2f') == 'n/a'
    assert plus_minus(0.5, None, '.2f', 100) == '50.00'
    # a signed change keeps its sign; its uncertainty is unsigned
    assert plus_minus(-0.0123, 0.004, '+.1f', 100) == '-1.2 +/- 0.4'
    assert percent(0.1234, '.1f') == '12.3 %'
    assert percent(-0.5, '+.0f') == '-50 %'
    for bad in (None, math.nan, math.inf):
        assert percent(bad, '.1f') == 'n/a'
