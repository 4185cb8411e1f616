"""
Discrepancy workflow (issue 5): where do simulation and measurement disagree, which effect is missing.

Modules: :mod:`.inputs` (bag / CSV to one axis), :mod:`.baseline` (paper model fit), :mod:`.signatures`
(signatures, band, gap), :mod:`.effects` (catalogue), :mod:`.workflow` (the loop), :mod:`.report`
(explain.json, report.md, figures), :mod:`.synthetic` (records with hidden effects, for the proof).
See docs/discrepancy.md.
"""

from .effects import CATALOGUE, NAMES
from .inputs import Measurement, load_input, make_measurement
from .workflow import ExplainResult, explain

__all__ = ['CATALOGUE', 'NAMES', 'Measurement', 'load_input', 'make_measurement', 'ExplainResult', 'explain']
