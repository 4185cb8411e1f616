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
Checks of a report.html shared by the tools' tests: static (numbers, no network) and in a browser.

The static checks parse the page with the standard library's HTML parser, independently of the
code that wrote it. The browser check drives Debian's Chromium through the playwright Python
package; without either, it skips with one line saying how to install them, and under ``CI=true``
it fails instead (CI must not pass having checked nothing).
"""

from html.parser import HTMLParser
import io
import json
import os
from pathlib import Path
import re
import shutil

import pytest

CHROMIUM = '/usr/bin/chromium'
CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update',
                 '--disable-sync']


class _Parser(HTMLParser):
    """Collect the data block, the number spans, the table cells and every src/href."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.data = None
        self.nums = []        # (pointer, fmt, text, scale)
        self.cells = []       # text of each <td> of section#tables and #card outside number spans
        self.refs = []        # (tag, attribute, value)
        self.sections = {}    # id -> text
        self._stack = []
        self._script_json = False
        self._json = []
        self._num = None
        self._key = False
        self._cell = None
        self._section = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        for name in ('src', 'href'):
            if name in attrs:
                self.refs.append((tag, name, attrs[name]))
        if tag == 'script' and attrs.get('type') == 'application/json':
            self._script_json = attrs.get('id') == 'gyro-noise-data'
        if tag == 'section':
            self._section = attrs.get('id')
            self.sections.setdefault(self._section, '')
        if tag == 'td' and self._section in ('tables', 'card'):
            self._cell = []
        if ((tag == 'code' and attrs.get('class') == 'key')
                or (tag == 'span' and attrs.get('class') == 'unit')) and self._cell is not None:
            self._key = True
        if tag == 'span' and attrs.get('class') == 'num':
            self._num = [attrs['data-json'], attrs['data-fmt'], '',
                         float(attrs.get('data-scale', '1.0'))]

    def handle_endtag(self, tag):
        if tag == 'script' and self._script_json:
            self.data = json.loads(''.join(self._json))
            self._script_json = False
        if tag == 'span' and self._num is not None:
            self.nums.append(tuple(self._num))
            self._num = None
        if tag == 'code' or (tag == 'span' and self._key):
            self._key = False
        if tag == 'td' and self._cell is not None:
            self.cells.append(''.join(self._cell))
            self._cell = None
        if tag == 'section':
            self._section = None

    def handle_data(self, data):
        if self._script_json:
            self._json.append(data)
        elif self._num is not None:
            self._num[2] += data
        elif self._cell is not None and not self._key:
            # a JSON key name (code.key) or a unit (span.unit) may hold a unit's digits (m_s2,
            # m/s^2): not a number
            self._cell.append(data)
        if self._section is not None:
            self.sections[self._section] += data


def parse_report(path):
    """Return the parsed page (a :class:`_Parser` after feeding it)."""
    parser = _Parser()
    parser.feed(Path(path).read_text(encoding='utf-8'))
    parser.close()
    return parser


def resolve(doc, pointer):
    """JSON Pointer (RFC 6901) lookup, written here again so the test does not trust the page."""
    value = doc
    for raw in pointer.split('/')[1:]:
        key = raw.replace('~1', '/').replace('~0', '~')
        value = value[int(key)] if isinstance(value, list) else value[key]
    return value


def shown(value, fmt, scale=1.0):
    """How a value must read on the page (numbers times ``scale``, a unit conversion)."""
    if value is None:
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, str):
        return value
    if isinstance(value, int) and fmt in ('', 'd') and scale == 1.0:
        return str(value)
    return format(value * scale if scale != 1.0 else value, fmt)


def check_static(html_path, json_doc, *, min_numbers=1):
    """
    Assert that a report.html holds ``json_doc`` and shows only its numbers, with no network.

    Returns the parsed page for further checks.
    """
    page = parse_report(html_path)
    # the page carries exactly the JSON document the tool wrote
    assert page.data == json_doc
    assert len(page.nums) >= min_numbers
    for pointer, fmt, text, scale in page.nums:
        assert text == shown(resolve(json_doc, pointer), fmt, scale), (pointer, fmt, text)
    # every digit in a table cell is inside a number span that came from the JSON
    for cell in page.cells:
        assert not re.search(r'\d', cell), cell
    # nothing is loaded from a network: no http(s) (nor protocol-relative) src/href
    for tag, attr, value in page.refs:
        assert not re.match(r'\s*(https?:)?//', value, re.I), (tag, attr, value)
    text = Path(html_path).read_text(encoding='utf-8')
    assert not re.search(r'<(script|link|img|iframe)[^>]+(src|href)\s*=\s*["\']?\s*(https?:)?//',
                         text, re.I)
    return page


def _no_browser(reason):
    message = (f'no headless browser for the report.html tests ({reason}): apt-get install '
               'chromium and pip install playwright')
    if os.environ.get('CI', '').lower() in ('1', 'true', 'yes'):
        pytest.fail(message + '; CI=true requires them')
    pytest.skip(message)


def _pixels(png):
    import matplotlib.image as mpimg
    import numpy as np

    img = mpimg.imread(io.BytesIO(png), format='png')
    return np.round(np.asarray(img)[..., :3] * 255).astype(np.int16)


#: The window a new user opens the page in (a laptop screen).
VIEWPORT = {'width': 1280, 'height': 800}

#: Geometry of the page in the window: its width, and the verdict line and first card table.
_GEOMETRY = """() => {
  const box = sel => { const e = document.querySelector(sel);
                       if (!e) return null;
                       const r = e.getBoundingClientRect();
                       return {top: r.top, bottom: r.bottom, height: r.height}; };
  return {width: document.documentElement.scrollWidth,
          verdict: box('#verdict'), card: box('#card table'),
          images: Array.from(document.querySelectorAll('img.png')).map(i => i.naturalWidth)};
}"""


def check_first_screen(geometry, viewport=VIEWPORT):
    """Assert the answer is on the first screen and nothing is wider than the window."""
    assert geometry['width'] <= viewport['width'], (
        f"page {geometry['width']} px wide in a {viewport['width']} px window")
    verdict, card = geometry['verdict'], geometry['card']
    assert verdict is not None, 'no verdict line'
    assert 0 <= verdict['top'] and verdict['bottom'] <= viewport['height'], verdict
    assert card is not None, 'no card'
    assert card['bottom'] <= viewport['height'], f'card ends at {card["bottom"]} px: {card}'
    assert all(w > 0 for w in geometry['images']), geometry['images']


def check_in_browser(html_path, tmp_path, *, figures, first_screen=True):
    """
    Load a report.html in headless Chromium (a 1280x800 window) and check it.

    Asserts no console error, no request leaving the file, every figure drawn (its curves'
    colours on screen) and every embedded image decoded; with ``first_screen`` the verdict line
    and the first card table inside the first 800 px and the page no wider than the window.
    Keeps the first screen (``first_screen.png``) and a full-page screenshot
    (``report_screenshot.png``) under ``tmp_path``; returns the full page's path.
    """
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _no_browser('the Python package playwright is not installed')
    exe = CHROMIUM if os.path.exists(CHROMIUM) else shutil.which('chromium')
    if not exe:
        _no_browser(f'{CHROMIUM} not found')

    errors, requests = [], []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=exe, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport=VIEWPORT)
            page.on('console', lambda m: errors.append(m.text) if m.type == 'error' else None)
            page.on('pageerror', lambda e: errors.append(str(e)))

            def route(r):
                requests.append(r.request.url)
                if r.request.url.startswith(('file:', 'data:', 'blob:', 'about:')):
                    r.continue_()
                else:
                    r.abort()

            page.route('**/*', route)
            page.goto(Path(html_path).resolve().as_uri())
            divs = page.locator('div.figure')
            assert divs.count() == figures
            if figures:
                page.wait_for_function(
                    'n => window.Bokeh !== undefined && Bokeh.documents.length > 0 && '
                    "document.querySelectorAll('div.figure > div').length === n && "
                    'Bokeh.documents.every(d => d.is_idle)', arg=figures, timeout=60_000)
            tmp_path.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(tmp_path / 'first_screen.png'))
            geometry = page.evaluate(_GEOMETRY)
            shot = tmp_path / 'report_screenshot.png'
            page.screenshot(path=str(shot), full_page=True)
            for k in range(figures):
                div = divs.nth(k)
                div.scroll_into_view_if_needed()
                px = _pixels(div.screenshot())
                # Axes, text and toolbar are grey or black; the curves are the palette's
                # saturated colours. A curve across the plot covers thousands of pixels, the
                # legend swatches about a hundred; a blank or failed figure has none of them.
                coloured = (px.max(axis=-1) - px.min(axis=-1)) > 60
                assert coloured.sum() >= 400, (
                    f'figure {k} looks blank ({coloured.sum()} coloured pixels)')
                assert px.shape[0] > 100 and px.shape[1] > 300, px.shape
        finally:
            browser.close()
    assert not errors, errors
    outside = [u for u in requests if not u.startswith(('file:', 'data:', 'blob:', 'about:'))]
    assert not outside, outside
    if first_screen:
        check_first_screen(geometry)
    return shot
