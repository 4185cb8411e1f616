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

Order of the page: title; "In short" (the same text as the tool's Markdown, converted); the
figures (Bokeh, its script embedded once); the tables; the method, the exact command, the package,
Python, numpy and Bokeh versions and the input files with their size and SHA-256. The tool's JSON
document is embedded verbatim in ``<script type="application/json" id="gyro-noise-data">``.

Every number in a table is a :class:`Num`: a JSON Pointer (RFC 6901) into that document and a
format. The page looks the value up itself, so a table cannot show a number the JSON does not
hold; the cell carries the pointer and the format (``data-json``, ``data-fmt``) so a test checks
every visible cell against the document.
"""

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

from ..outputs import atomic_write_text, StrPath

#: id of the embedded JSON document.
DATA_ID = 'gyro-noise-data'
#: Bytes read at a time when hashing input files.
_HASH_BLOCK = 1 << 20


@dataclass(frozen=True)
class Num:
    """
    One value of the page's JSON document, shown in a table cell.

    Attributes
    ----------
    pointer : str
        JSON Pointer (RFC 6901) into the document, e.g. ``/bags/0/axes/x/chunks``.
    fmt : str
        ``format()`` spec for numbers (ignored for strings and booleans).
    prefix : str
        Text before the value (e.g. ``'<= '`` for an upper bound); no digits.
    scale : float
        Unit conversion at the edge: the cell shows ``value * scale`` (e.g. m/s^2 -> mg when
        the JSON is SI and the table customary); 1 shows the JSON value itself.

    """

    pointer: str
    fmt: str = '.6g'
    prefix: str = ''
    scale: float = 1.0


@dataclass(frozen=True)
class Key:
    """
    A JSON key name shown in a table cell (as code; its digits are a unit, not a number).

    Attributes
    ----------
    name : str
        The key, e.g. ``noise_density_m_s2_per_sqrt_hz``.

    """

    name: str


#: One part of a table cell: plain text, a value of the JSON document or a key name.
CellPart = str | Num | Key
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
    figures : tuple
        ``(caption, bokeh model)`` pairs, in order.
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
    figures: tuple = ()
    tables: tuple = ()
    method_markdown: str = ''
    command: tuple | None = None
    inputs: tuple = ()
    version: str = ''
    extra_versions: tuple = field(default_factory=tuple)


def resolve_pointer(doc: dict[str, Any] | list[Any], pointer: str) -> Any:
    """
    Return the value at a JSON Pointer (RFC 6901) in ``doc``.

    Parameters
    ----------
    doc : dict or list
        The JSON document.
    pointer : str
        ``''`` (the whole document) or ``/key/0/...`` with ``~1`` for ``/`` and ``~0`` for ``~``.

    Returns
    -------
    object

    Raises
    ------
    KeyError
        A key or index that the document does not have.

    """
    value = doc
    if pointer == '':
        return value
    if not pointer.startswith('/'):
        raise KeyError(f'JSON pointer must start with "/", got {pointer!r}')
    for raw in pointer[1:].split('/'):
        key = raw.replace('~1', '/').replace('~0', '~')
        if isinstance(value, list):
            try:
                value = value[int(key)]
            except (ValueError, IndexError) as err:
                raise KeyError(f'{pointer}: no index {key!r}') from err
        elif isinstance(value, dict):
            if key not in value:
                raise KeyError(f'{pointer}: no key {key!r}')
            value = value[key]
        else:
            raise KeyError(f'{pointer}: {key!r} inside a {type(value).__name__}')
    return value


def pointer(*parts: str | int) -> str:
    """
    Build a JSON Pointer from keys and indices (escaping ``~`` and ``/``).

    Parameters
    ----------
    *parts : str or int
        Keys and list indices, outermost first.

    Returns
    -------
    str

    """
    return ''.join('/' + str(p).replace('~', '~0').replace('/', '~1') for p in parts)


def plus_minus_cell(value: str, sigma: str, fmt: str, scale: float = 1.0) -> tuple[Num, str, Num]:
    """
    Return the cell ``value +/- sigma`` of two values of the document, in one unit.

    Parameters
    ----------
    value, sigma : str
        JSON Pointers of the value and of its standard uncertainty.
    fmt : str
        ``format()`` spec of both.
    scale : float
        Unit factor of both (:attr:`Num.scale`).

    Returns
    -------
    tuple
        A :data:`Cell` of three parts.

    """
    return (Num(value, fmt, scale=scale), ' +/- ', Num(sigma, fmt, scale=scale))


def format_value(value: object, fmt: str, scale: float = 1.0) -> str:
    """
    Format one JSON value for a table cell: None as ``n/a``, booleans as yes/no.

    Parameters
    ----------
    value : object
        A JSON scalar.
    fmt : str
        ``format()`` spec applied to numbers.
    scale : float
        Factor applied to numbers first (a unit conversion).

    Returns
    -------
    str

    """
    if value is None:
        return 'n/a'
    if isinstance(value, bool):
        return 'yes' if value else 'no'
    if isinstance(value, int) and fmt in ('', 'd') and scale == 1.0:
        return str(value)
    if isinstance(value, (int, float)):
        return format(value * scale if scale != 1.0 else value, fmt)
    return str(value)


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


def _cell(doc: dict[str, Any] | list[Any], cell: Cell) -> str:
    parts = cell if isinstance(cell, tuple) else (cell,)
    out = []
    for part in parts:
        if isinstance(part, Num):
            value = resolve_pointer(doc, part.pointer)
            scale = (f' data-scale="{part.scale!r}"' if part.scale != 1.0 else '')
            out.append(f'{html.escape(part.prefix)}<span class="num" '
                       f'data-json="{html.escape(part.pointer)}" '
                       f'data-fmt="{html.escape(part.fmt)}"{scale}>'
                       f'{html.escape(format_value(value, part.fmt, part.scale))}</span>')
        elif isinstance(part, Key):
            out.append(f'<code class="key">{html.escape(part.name)}</code>')
        else:
            out.append(html.escape(str(part)))
    return '<td>' + ''.join(out) + '</td>'


def _table(doc: dict[str, Any] | list[Any], table: Table) -> str:
    lines = [f'<h3>{html.escape(table.title)}</h3>']
    if table.note:
        lines.append(f'<p class="note">{html.escape(table.note)}</p>')
    lines.append('<table><thead><tr>'
                 + ''.join(f'<th>{html.escape(c)}</th>' for c in table.columns)
                 + '</tr></thead><tbody>')
    for row in table.rows:
        lines.append('<tr>' + ''.join(_cell(doc, c) for c in row) + '</tr>')
    lines.append('</tbody></table>')
    return '\n'.join(lines)


_STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 1em auto; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: right; }
th { background: #f3f3f3; } td:first-child { text-align: left; }
.note { color: #555; font-size: 0.9em; }
.figure { margin: 1em 0 2em; }
pre { background: #f6f6f6; padding: 0.5em; overflow-x: auto; white-space: pre-wrap; }
"""


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
    # "</" inside the JSON would end the script element early: escape it as JSON allows. NaN is
    # kept as the tools' own json.dumps writes it (the same tokens as their file): a page must
    # never fail a run whose JSON file was written.
    data = json.dumps(doc, indent=1).replace('</', '<\\/')
    figures = [m for _, m in page.figures]
    script, divs = components(figures) if figures else ('', ())
    parts = [
        '<!DOCTYPE html>', '<html lang="en">', '<head>', '<meta charset="utf-8">',
        f'<title>{html.escape(page.title)}</title>', f'<style>{_STYLE}</style>',
    ]
    if figures:
        parts += [inline.render_js(), inline.render_css(), script]
    parts += ['</head>', '<body>', f'<h1>{html.escape(page.title)}</h1>',
              '<section id="in-short">', markdown_to_html(page.in_short_markdown), '</section>']
    if figures:
        parts.append('<section id="figures"><h2>Figures</h2>')
        parts.append('<p class="note">Drag to pan, wheel or box to zoom, hover a point for its '
                     'values; the full data are in the CSV files beside this page.</p>')
        for (caption, _), div in zip(page.figures, divs):
            parts.append(f'<div class="figure"><p>{html.escape(caption)}</p>{div}</div>')
        parts.append('</section>')
    if page.tables:
        parts.append('<section id="tables"><h2>Tables</h2>')
        parts += [_table(doc, t) for t in page.tables]
        parts.append('</section>')
    parts.append('<section id="method"><h2>Method</h2>')
    parts.append(markdown_to_html(page.method_markdown))
    command = (shlex.join(page.command) if page.command is not None
               else '(called from Python, no command line)')
    parts.append(f'<h3>Command</h3><pre id="command">{html.escape(command)}</pre>')
    parts.append('<h3>Versions</h3><table id="versions"><tbody>' + ''.join(
        f'<tr><td>{html.escape(n)}</td><td>{html.escape(str(v))}</td></tr>'
        for n, v in _versions(page)) + '</tbody></table>')
    rows = input_files(page.inputs)
    parts.append('<h3>Input files</h3><table id="inputs"><thead><tr><th>File</th>'
                 '<th>Size (bytes)</th><th>SHA-256</th></tr></thead><tbody>' + ''.join(
                     f'<tr><td>{html.escape(p)}</td><td>{"missing" if s is None else s}</td>'
                     f'<td><code>{h or ""}</code></td></tr>' for p, s, h in rows)
                 + '</tbody></table>')
    parts.append('</section>')
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
