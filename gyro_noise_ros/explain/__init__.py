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
Discrepancy workflow (issue 5).

Where do simulation and measurement disagree, which effect is missing.

Modules: :mod:`.inputs` (bag / CSV to one axis), :mod:`.baseline` (paper model fit),
:mod:`.signatures` (signatures, band, gap), :mod:`.effects` (catalogue), :mod:`.workflow` (the
loop), :mod:`.report` (explain.json, report.md, figures), :mod:`.synthetic` (records with hidden
effects, for the proof). See docs/discrepancy.md.
"""

from .effects import CATALOGUE, NAMES
from .inputs import load_input, make_measurement, Measurement
from .workflow import explain, ExplainResult

__all__ = ['CATALOGUE', 'NAMES', 'Measurement', 'load_input', 'make_measurement', 'ExplainResult',
           'explain']
