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
One self-contained HTML report per analysis (``report.html``), ROS-free.

:mod:`.page` holds the page skeleton (:class:`~.page.Page`, :func:`~.page.write_report_html`),
:mod:`.figures` the interactive Bokeh figures, and one module per tool turns that tool's JSON
document and in-memory arrays into a page (:mod:`.analyze`, ...). Bokeh is imported only when a
page is written. What the page holds and why Bokeh: ``docs/report_html.md``.
"""

from .page import Key, Num, Page, render_html, Table, write_report_html

__all__ = ['Key', 'Num', 'Page', 'Table', 'render_html', 'write_report_html']
