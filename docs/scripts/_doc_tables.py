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

"""Put a script's printed tables into a page of docs/ between its markers, with the command."""

import contextlib
import io
import os
import sys

DOCS = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')


def print_and_write(run, script, page, argv):
    """
    Run ``run()`` (it prints the tables), put its output into ``docs/<page>`` and print it.

    The block between ``<!-- <script>: begin -->`` and ``<!-- <script>: end -->`` is replaced by
    the output, headed by the command that made it.
    """
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        run()
    text = buf.getvalue()
    begin, end = f'<!-- {script}: begin -->', f'<!-- {script}: end -->'
    path = os.path.join(DOCS, page)
    with open(path) as fh:
        doc = fh.read()
    if doc.count(begin) != 1 or doc.count(end) != 1:
        sys.exit(f'{path}: needs exactly one {begin} and one {end}')
    cmd = ' '.join([f'nice python docs/scripts/{script}'] + list(argv))
    head, rest = doc.split(begin)
    with open(path + '.tmp', 'w') as fh:
        block = f'{begin}\nMade by `{cmd}`.\n{text.rstrip()}\n{end}'
        fh.write(head + block + rest.split(end, 1)[1])
    os.replace(path + '.tmp', path)
    print(text)
