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
The page skeleton of every ``report.html``: one file, no network, nothing beside it needed.

Order of the page, the answer first: title; the verdict line (:class:`Verdict`, coloured by
level); the unit policy (:data:`..units.UNIT_POLICY`); the card (the tool's key numbers, and
blocks to copy such as imu.yaml); "In short" (the same text as the tool's Markdown, converted)
with its glossary folded; the figures (Bokeh, its script embedded once, then PNG images embedded
as data); the tables; the method, the exact command, the versions and the input files with their
size and SHA-256. The tool's JSON document is embedded verbatim in
``<script type="application/json" id="gyro-noise-data">``. Nothing is wider than the window:
tables scroll inside the page.

Every number in a table is a :class:`..formatting.Num`: a JSON Pointer (RFC 6901) into that
document and a format. The page looks the value up itself, so a table cannot show a number the
JSON does not hold; the cell carries the pointer and the format (``data-json``, ``data-fmt``) so
a test checks every visible cell against the document.
"""

import base64
from collections.abc import Iterable
from dataclasses import dataclass, field
import hashlib
import html
import json
import os
from pathlib import Path
import platform
import re
import shlex
from typing import Any

from ..formatting import Aside, format_value, Key, Num, pointer, resolve_pointer, Unit
from ..outputs import atomic_write_text, StrPath
from ..units import UNIT_POLICY

__all__ = ['Aside', 'Cell', 'CellPart', 'DATA_ID', 'Key', 'Num', 'Page', 'Table', 'Unit',
           'Verdict', 'format_value', 'input_files', 'markdown_to_html', 'plus_minus_cell',
           'pointer', 'pretty_unit', 'render_html', 'resolve_pointer', 'write_report_html']

#: id of the embedded JSON document.
DATA_ID = 'gyro-noise-data'
#: Bytes read at a time when hashing input files.
_HASH_BLOCK = 1 << 20


#: One part of a table cell: plain text, a value of the JSON document, a key name, a unit, or
#: the same quantity in another unit beside it (:class:`..formatting.Aside`).
CellPart = str | Num | Key | Unit | Aside
#: A table cell: one part, or a tuple of them (e.g. a value and its interval).
Cell = CellPart | tuple[CellPart, ...]


@dataclass(frozen=True)
class Table:
    """
    One table of the page.

    Attributes
    ----------
    title : str
        Heading above the table.
    columns : tuple of str
        Column headers, units in parentheses.
    rows : tuple of tuple
        Cells: a ``str`` (plain text), a :class:`Num`, a :class:`Key`, or a tuple of them (one
        cell of several parts, e.g. a value and its interval).
    note : str
        A sentence under the heading (plain text).

    """

    title: str
    columns: tuple
    rows: tuple
    note: str = ''


#: Verdict levels and their colours (text, background): green, amber, red, grey.
LEVELS = {'OK': ('#1b5e20', '#e8f5e9'), 'WARN': ('#8a4b00', '#fff4e0'),
          'ERROR': ('#b71c1c', '#fdecea'), 'INFO': ('#37474f', '#eceff1')}


@dataclass(frozen=True)
class Verdict:
    """
    The one line a page opens with: the level and why.

    Attributes
    ----------
    level : str
        'OK', 'WARN', 'ERROR' or 'INFO' (undetermined, or nothing to judge).
    text : str
        Why, in one or two sentences (Markdown subset: bold, code).

    """

    level: str
    text: str

    def __post_init__(self) -> None:
        if self.level not in LEVELS:
            raise ValueError(f'verdict level must be one of {sorted(LEVELS)}, got {self.level!r}')


@dataclass(frozen=True)
class Page:
    """
    Everything one ``report.html`` shows.

    Attributes
    ----------
    title : str
        Page title.
    data : dict
        The tool's JSON document (exactly what the tool writes as JSON), embedded verbatim.
    in_short_markdown : str
        The tool's "In short" Markdown (the same function its Markdown report uses).
    verdict : Verdict or None
        The line the page opens with (None: no verdict line).
    card : tuple of Table
        The key numbers, shown right under the verdict (the first screen).
    card_title : str
        Heading of the card.
    card_blocks : tuple
        ``(title, text)`` preformatted blocks shown with the card (imu.yaml, ready to copy).
    glossary_markdown : str
        What the numbers mean, folded under "In short" (Markdown subset).
    units : str
        The unit policy stated under the verdict.
    figures : tuple
        ``(caption, bokeh model)`` pairs, in order.
    images : tuple
        ``(caption, png bytes)`` figures drawn by the tool as PNG files, embedded as data.
    tables : tuple of Table
        The tables, in order.
    method_markdown : str
        How the numbers were made (Markdown subset: paragraphs, ``*`` lists, bold, code).
    command : tuple of str or None
        The exact command line (None: called from Python).
    inputs : tuple of str
        Input files or folders (a folder lists every file in it).
    version : str
        Package version.
    extra_versions : tuple
        ``(name, version)`` of further libraries the numbers depend on.

    """

    title: str
    data: dict
    in_short_markdown: str
    verdict: Verdict | None = None
    card: tuple = ()
    card_title: str = 'The numbers'
    card_blocks: tuple = ()
    glossary_markdown: str = ''
    units: str = UNIT_POLICY
    figures: tuple = ()
    images: tuple = ()
    tables: tuple = ()
    method_markdown: str = ''
    command: tuple | None = None
    inputs: tuple = ()
    version: str = ''
    extra_versions: tuple = field(default_factory=tuple)


def plus_minus_cell(value: str, sigma: str, fmt: str, scale: float = 1.0) -> tuple[Num, str, Num]:
    """
    Return the :data:`Cell` ``value +/- sigma`` of two values of the document, in one unit.

    ``value`` and ``sigma`` are the JSON Pointers of the value and its standard uncertainty,
    ``fmt`` the ``format()`` spec of both and ``scale`` their unit factor (:attr:`Num.scale`).

    """
    return (Num(value, fmt, scale=scale), ' +/- ', Num(sigma, fmt, scale=scale))


_BOLD = re.compile(r'\*\*(.+?)\*\*')
_CODE = re.compile(r'`([^`]+)`')


def _inline(text: str) -> str:
    text = html.escape(text, quote=False)
    text = _CODE.sub(r'<code>\1</code>', text)
    return _BOLD.sub(r'<strong>\1</strong>', text)


def markdown_to_html(text: str) -> str:
    """
    Convert the Markdown subset of the tools' "In short" sections to HTML.

    Headings (``#`` to ``####``), ``*`` / ``-`` lists, paragraphs separated by blank lines,
    ``**bold**`` and ``code``; everything else is escaped text. The words are unchanged, so the
    page's "In short" reads exactly as the Markdown's.

    Parameters
    ----------
    text : str
        Markdown.

    Returns
    -------
    str
        HTML.

    """
    out: list[str] = []
    para: list[str] = []
    items: list[str] = []

    def flush() -> None:
        if para:
            out.append('<p>' + _inline(' '.join(para)) + '</p>')
            para.clear()
        if items:
            out.append('<ul>' + ''.join(f'<li>{_inline(i)}</li>' for i in items) + '</ul>')
            items.clear()

    for line in text.splitlines():
        stripped = line.strip()
        heading = re.match(r'(#{1,4})\s+(.*)', stripped)
        if not stripped:
            flush()
        elif heading:
            flush()
            level = len(heading.group(1))
            out.append(f'<h{level + 1}>{_inline(heading.group(2))}</h{level + 1}>')
        elif re.match(r'[*-]\s', stripped):
            if para:
                flush()
            items.append(stripped[2:])
        elif items:
            items[-1] += ' ' + stripped  # a list item's continuation line
        else:
            para.append(stripped)
    flush()
    return '\n'.join(out)


def input_files(paths: Iterable[StrPath]) -> list[tuple[str, int | None, str | None]]:
    """
    Return ``[(path, size_bytes, sha256_hex)]`` of the input files (folders: every file inside).

    Parameters
    ----------
    paths : iterable of str or os.PathLike
        Input files or folders; a missing one gives ``(path, None, None)``.

    Returns
    -------
    list of tuple

    """
    rows: list[tuple[str, int | None, str | None]] = []
    for path in paths:
        p = Path(path)
        files = sorted(f for f in p.rglob('*') if f.is_file()) if p.is_dir() else [p]
        for f in files:
            try:
                digest = hashlib.sha256()
                with open(f, 'rb') as fh:
                    for block in iter(lambda: fh.read(_HASH_BLOCK), b''):
                        digest.update(block)
                rows.append((str(f), f.stat().st_size, digest.hexdigest()))
            except OSError:
                rows.append((str(f), None, None))
    return rows


def _versions(page: Page) -> list[tuple[str, str]]:
    import bokeh
    import numpy

    return [('gyro_noise_ros', page.version), ('Python', platform.python_version()),
            ('numpy', numpy.__version__), ('bokeh', bokeh.__version__),
            *page.extra_versions]


_PRETTY_UNITS = (('sqrt(Hz)', '\u221aHz'), ('sqrt(h)', '\u221ah'), ('sqrt(s)', '\u221as'),
                 ('^2', '\u00b2'), ('^3', '\u00b3'), ('^4', '\u2074'))


def pretty_unit(unit: str) -> str:
    """
    Return a unit as a page shows it: ``sqrt(h)`` as a root sign, ``^2`` as a superscript.

    Parameters
    ----------
    unit : str
        The package's ASCII spelling (``'m/s^2/sqrt(Hz)'``).

    Returns
    -------
    str
        ``'m/s\u00b2/\u221aHz'``.

    """
    for ascii_form, shown in _PRETTY_UNITS:
        unit = unit.replace(ascii_form, shown)
    return unit


def _part(doc: dict[str, Any] | list[Any], part: CellPart) -> str:
    if isinstance(part, Num):
        value = resolve_pointer(doc, part.pointer)
        scale = (f' data-scale="{part.scale!r}"' if part.scale != 1.0 else '')
        return (f'{html.escape(part.prefix)}<span class="num" '
                f'data-json="{html.escape(part.pointer)}" '
                f'data-fmt="{html.escape(part.fmt)}"{scale}>'
                f'{html.escape(format_value(value, part.fmt, part.scale))}</span>')
    if isinstance(part, Key):
        return f'<code class="key">{html.escape(part.name)}</code>'
    if isinstance(part, Unit):
        return f'<span class="unit">{html.escape(pretty_unit(part.name))}</span>'
    if isinstance(part, Aside):
        return ('<span class="aside">' + ''.join(_part(doc, p) for p in part.parts)
                + '</span>')
    return html.escape(str(part))


def _cell(doc: dict[str, Any] | list[Any], cell: Cell) -> str:
    parts = cell if isinstance(cell, tuple) else (cell,)
    if not any(isinstance(p, Aside) for p in parts):
        return '<td>' + ''.join(_part(doc, p) for p in parts) + '</td>'
    # a value with an aside: the value on one unbroken line, the aside wrapping under it
    main = ''.join(_part(doc, p) for p in parts if not isinstance(p, Aside))
    aside = ''.join(_part(doc, p) for p in parts if isinstance(p, Aside))
    return f'<td><span class="main">{main}</span>{aside}</td>'


def _table(doc: dict[str, Any] | list[Any], table: Table, level: int = 3) -> str:
    lines = [f'<h{level}>{html.escape(table.title)}</h{level}>'] if table.title else []
    if table.note:
        lines.append(f'<p class="note">{html.escape(table.note)}</p>')
    # a table wider than the page scrolls inside its own box, never the page
    lines.append('<div class="scroll"><table><thead><tr>'
                 + ''.join(f'<th>{html.escape(c)}</th>' for c in table.columns)
                 + '</tr></thead><tbody>')
    for row in table.rows:
        lines.append('<tr>' + ''.join(_cell(doc, c) for c in row) + '</tr>')
    lines.append('</tbody></table></div>')
    return '\n'.join(lines)


_STYLE = """
body { font-family: sans-serif; max-width: 1180px; margin: 0.6em auto; padding: 0 16px;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.45em; margin: 0.3em 0; } h2 { border-bottom: 1px solid #ccc; margin-top: 1.4em; }
h3 { margin: 1em 0 0.3em; }
.scroll { max-width: 100%; overflow-x: auto; }
table { border-collapse: collapse; margin: 0.3em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; vertical-align: top; }
th { background: #f3f3f3; overflow-wrap: break-word; } td:first-child { text-align: left; }
td code, #inputs td { overflow-wrap: anywhere; word-break: break-all; }
.note { color: #555; font-size: 0.9em; margin: 0.2em 0; }
.units { color: #555; font-size: 0.85em; margin: 0.2em 0 0.6em; }
.figure { margin: 1em 0 2em; } img.png { max-width: 100%; height: auto; }
pre { background: #f6f6f6; padding: 0.5em; overflow-x: auto; white-space: pre-wrap;
      overflow-wrap: anywhere; }
.verdict { padding: 0.45em 0.8em; border-left: 8px solid; font-size: 1.08em; margin: 0.3em 0; }
.verdict .level { font-weight: bold; margin-right: 0.5em; }
.aside { display: block; color: #666; font-size: 0.85em; }
#card table { font-size: 0.92em; } #card h2 { margin-top: 0.6em; }
.num, .unit, .main { white-space: nowrap; }
#card pre { font-size: 0.82em; margin: 0.3em 0; }
.card-item { display: inline-block; vertical-align: top; margin-right: 2em; max-width: 100%; }
details summary { cursor: pointer; color: #333; }
"""


def _verdict_html(verdict: Verdict | None) -> list[str]:
    if verdict is None:
        return []
    fg, bg = LEVELS[verdict.level]
    text = markdown_to_html(verdict.text)
    text = text[3:-4] if text.startswith('<p>') and text.endswith('</p>') else text
    return [f'<div id="verdict" class="verdict verdict-{verdict.level.lower()}" '
            f'style="color: {fg}; background: {bg}; border-color: {fg};">'
            f'<span class="level">{verdict.level}</span>{text}</div>']


def _card_html(page: Page) -> list[str]:
    if not page.card and not page.card_blocks:
        return []
    parts = ['<section id="card">', f'<h2>{html.escape(page.card_title)}</h2>']
    # small tables side by side, a wide one alone on its line
    parts += [f'<div class="card-item">{_table(page.data, t, level=3)}</div>' for t in page.card]
    for title, text in page.card_blocks:
        parts.append(f'<h3>{html.escape(title)}</h3><pre class="block">{html.escape(text)}</pre>')
    parts.append('</section>')
    return parts


def _in_short_html(page: Page) -> list[str]:
    parts = ['<section id="in-short">', markdown_to_html(page.in_short_markdown)]
    if page.glossary_markdown:
        parts += ['<details id="glossary"><summary>What the numbers mean</summary>',
                  markdown_to_html(page.glossary_markdown), '</details>']
    return parts + ['</section>']


def _figures_html(page: Page, divs: Iterable[str]) -> list[str]:
    if not page.figures and not page.images:
        return []
    parts = ['<section id="figures"><h2>Figures</h2>']
    if page.figures:
        parts.append('<p class="note">Drag to pan, wheel or box to zoom, hover a point for its '
                     'values; the full data are in the CSV files beside this page.</p>')
    for (caption, _), div in zip(page.figures, divs):
        parts.append(f'<div class="figure"><p>{html.escape(caption)}</p>{div}</div>')
    for caption, png in page.images:
        data = base64.b64encode(png).decode('ascii')
        parts.append(f'<div class="png-figure"><p>{html.escape(caption)}</p>'
                     f'<img class="png" alt="{html.escape(caption)}" '
                     f'src="data:image/png;base64,{data}"></div>')
    return parts + ['</section>']


def _method_html(page: Page) -> list[str]:
    parts = ['<section id="method"><h2>Method</h2>', markdown_to_html(page.method_markdown)]
    command = (shlex.join(page.command) if page.command is not None
               else '(called from Python, no command line)')
    parts.append(f'<h3>Command</h3><pre id="command">{html.escape(command)}</pre>')
    parts.append('<h3>Versions</h3><table id="versions"><tbody>' + ''.join(
        f'<tr><td>{html.escape(n)}</td><td>{html.escape(str(v))}</td></tr>'
        for n, v in _versions(page)) + '</tbody></table>')
    rows = input_files(page.inputs)
    parts.append('<h3>Input files</h3><div class="scroll"><table id="inputs"><thead><tr>'
                 '<th>File</th><th>Size (bytes)</th><th>SHA-256</th></tr></thead><tbody>'
                 + ''.join(f'<tr><td>{html.escape(p)}</td><td>{"missing" if s is None else s}'
                           f'</td><td><code>{h or ""}</code></td></tr>' for p, s, h in rows)
                 + '</tbody></table></div>')
    return parts + ['</section>']


def render_html(page: Page) -> str:
    """
    Return the whole ``report.html`` of a page as text.

    Parameters
    ----------
    page : Page
        What to show.

    Returns
    -------
    str

    """
    from bokeh.embed import components
    from bokeh.resources import Resources

    # BokehJS core only (~1.3 MB), inline: the figures use no WebGL, widgets, tables or MathJax
    # (those bundles would add ~2.7 MB to every page).
    inline = Resources(mode='inline', components=['bokeh'])

    doc = page.data
    # "</script" or "<!--<script" inside the JSON would end the script element early or hide its
    # end (the HTML parser's escaped states): every "<" is written as JSON's \u003c. NaN is kept
    # as the tools' own json.dumps writes it (the same tokens as their file): a page must never
    # fail a run whose JSON file was written.
    data = json.dumps(doc, indent=1).replace('<', '\\u003c')
    figures = [m for _, m in page.figures]
    script, divs = components(figures) if figures else ('', ())
    parts = [
        '<!DOCTYPE html>', '<html lang="en">', '<head>', '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f'<title>{html.escape(page.title)}</title>', f'<style>{_STYLE}</style>',
    ]
    if figures:
        parts += [inline.render_js(), inline.render_css(), script]
    parts += ['</head>', '<body>', f'<h1>{html.escape(page.title)}</h1>']
    parts += _verdict_html(page.verdict)
    if page.units:
        parts.append(f'<p class="units" id="units">{html.escape(page.units)}</p>')
    parts += _card_html(page)
    parts += _in_short_html(page)
    parts += _figures_html(page, divs)
    if page.tables:
        parts.append('<section id="tables"><h2>Tables</h2>')
        parts += [_table(doc, t) for t in page.tables]
        parts.append('</section>')
    parts += _method_html(page)
    parts.append(f'<script type="application/json" id="{DATA_ID}">{data}</script>')
    parts += ['</body>', '</html>', '']
    return '\n'.join(parts)


def write_report_html(page: Page, path: StrPath) -> Path:
    """
    Write ``page`` to ``path`` atomically (a temporary sibling renamed into place).

    Parameters
    ----------
    page : Page
        What to show.
    path : str or os.PathLike
        Usually ``report.html`` inside the tool's staged ``--out`` folder.

    Returns
    -------
    pathlib.Path
        ``path``.

    """
    atomic_write_text(path, render_html(page))
    return Path(os.fspath(path))
