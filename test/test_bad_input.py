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
The bad-input sweep (issue 33): every tool and node against every class of bad input.

Each case of :data:`CASES` is ``Case(tool, klass, args, code, text)``: the command line (with
``{in}`` the shared inputs, ``{out}`` a new folder, ``{full}`` a folder holding a user's file,
``{file}`` a file, ``{ro}`` a place nobody may write), the README's exit code and a piece of the
one error line. Every case is run in-process and checked for: the code; stderr without a
traceback or a numpy warning, ending in one ``<tool>: error:`` line (or ``interrupted``); nothing
lost (every file that existed is byte-identical) and nothing new beside it (no empty folder, no
hidden stage) unless the run succeeded. The ``signal`` cases send SIGINT or SIGTERM to this
process from inside the tool's work: the code is 130 or 143 and nothing is left under a final
name. Nodes run their ``main`` in-process in a private graph (a watchdog ends a node that would
spin). The slow part sends real signals to tools and nodes in subprocesses and times the stop.
``docs/scripts/bad_input_table.py`` counts the cases per class into ``docs/bad_input.md``.
"""

import hashlib
import importlib
import json
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import NamedTuple
import warnings

from gyro_noise_ros.errors import EXIT_CODES
import numpy as np
import pytest

#: The classes of bad input the issue lists, and --help (a node must not start for it).
CLASSES = ('garbage bytes', 'bad parameter', 'missing topic', 'corrupt bag', 'NaN samples',
           'unwritable output', 'existing output', 'signal', 'overflow number', 'CSV dialect',
           'help')

#: Where every tool and node lives (``main(argv)``; ``record repair`` is ``main(['repair', ..])``).
PROGS = {
    'gyro_noise_analyze': 'gyro_noise_ros.cli.analyze',
    'gyro_noise_explain': 'gyro_noise_ros.cli.explain',
    'gyro_noise_thermal': 'gyro_noise_ros.cli.thermal',
    'gyro_noise_calibrate': 'gyro_noise_ros.cli.calibrate',
    'gyro_noise_reliability': 'gyro_noise_ros.cli.reliability',
    'gyro_noise_excitation': 'gyro_noise_ros.cli.excitation',
    'gyro_noise_import': 'gyro_noise_ros.cli.importer',
    'gyro_noise_record repair': 'gyro_noise_ros.cli.record',
    'portenta_emulator': 'gyro_noise_ros.cli.emulator',
    'gyro_noise_demo': 'gyro_noise_ros.cli.demo',
    'lsm6dso32_driver': 'gyro_noise_ros.nodes.driver',
    'noise_analyzer': 'gyro_noise_ros.nodes.analyzer',
    'imu_compensator': 'gyro_noise_ros.nodes.compensator',
    'gyro_noise_record': 'gyro_noise_ros.nodes.recorder',
    'gyro_noise_monitor': 'gyro_noise_ros.nodes.monitor',
    'imu_chain': 'gyro_noise_ros.nodes.chain',
}
NODES = ('lsm6dso32_driver', 'noise_analyzer', 'imu_compensator', 'gyro_noise_record',
         'gyro_noise_monitor', 'imu_chain')

RATE_HZ = 200.0
N = 9000  # 45 s at 200 Hz: explain's floor (8,192) and 15 analyze chunks of 600
FAST = ['--chunk-size', '600', '--memory', '50', '--order-grid', '0:2:0.1', '--quiet',
        '--jobs', '1', '--no-figures', '--no-html']
UNWRITABLE = '/proc/gyro_noise_bad_input'  # mkdir fails there even as root


class Case(NamedTuple):
    """One bad input to one tool."""

    tool: str
    klass: str
    args: tuple
    code: int
    text: str = ''
    hook: str = ''  # 'module:attribute' that sends the signal of a signal case when called


def _c(tool, klass, code, text, *args, hook=''):
    return Case(tool, klass, tuple(args), code, text, hook)


def _analyze_cases():
    t = 'gyro_noise_analyze'
    o = ('--out', '{out}')
    sig = 'gyro_noise_ros.app.analyze:_run_bags'
    return [
        _c(t, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.mcap', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.db3', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.bag', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'cannot read CSV', '{in}/garbage.csv', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'cannot read ULog', '{in}/garbage.ulg', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'garbage_meta', '{in}/garbage_meta', *FAST, *o),
        _c(t, 'garbage bytes', 3, 'reference summary', '{in}/bag', *FAST, '--reference',
           '{in}/garbage.json', *o),
        _c(t, 'bad parameter', 2, '--jobs', '{in}/bag', *FAST, '--jobs', '0', *o),
        _c(t, 'bad parameter', 2, 'order', '{in}/bag', *FAST, '--order-grid', 'abc', *o),
        _c(t, 'bad parameter', 2, '--reference-bag names a bag', '{in}/bag', *FAST,
           '--reference-bag', 'x', *o),
        _c(t, 'bad parameter', 2, 'invalid choice', '{in}/bag', *FAST, '--axis', 'q', *o),
        _c(t, 'bad parameter', 2, 'gap', '{in}/bag', *FAST, '--gap-factor', 'nan', *o),
        _c(t, 'bad parameter', 2, '--label', '{in}/bag', *FAST, '--label', 'a', 'b', *o),
        _c(t, 'missing topic', 3, "'/nope'", '{in}/bag', *FAST, '--topic', '/nope', *o),
        _c(t, 'missing topic', 3, 'no such file', '{in}/missing.csv', *FAST, *o),
        _c(t, 'missing topic', 3, '/nope', '{in}/bag', *FAST, '--temperature-topic', '/nope',
           *o),
        # a killed recording is read as far as it goes, said in a warning (docs/bags.md)
        _c(t, 'corrupt bag', 0, '', '{in}/truncated_mcap', *FAST, *o),
        _c(t, 'corrupt bag', 3, 'garbled_mcap', '{in}/garbled_mcap', *FAST, *o),
        _c(t, 'corrupt bag', 3, 'garbled_db3', '{in}/garbled_db3', *FAST, *o),
        _c(t, 'NaN samples', 4, 'no chunk could be analysed', '{in}/nan_bag', *FAST, *o),
        _c(t, 'NaN samples', 4, 'NaN/Inf', '{in}/nan_time.csv', *FAST, *o),
        _c(t, 'unwritable output', 6, 'not writable', '{in}/bag', *FAST, '--out', UNWRITABLE),
        _c(t, 'unwritable output', 6, 'is an existing file', '{in}/bag', *FAST, '--out',
           '{file}'),
        _c(t, 'unwritable output', 6, 'cannot be created', '{in}/bag', *FAST, '--out',
           '{file}/sub'),
        _c(t, 'existing output', 6, 'is not empty', '{in}/bag', *FAST, '--out', '{full}'),
        _c(t, 'unwritable output', 6, '--out is empty', '{in}/bag', *FAST, '--out', ''),
        _c(t, 'overflow number', 2, 'GiB', '{in}/bag', *FAST, '--chunk-size',
           '99999999999999999999999', *o),
        _c(t, 'overflow number', 4, 'nothing left to analyse', '{in}/bag', *FAST, '--start',
           '1e308', *o),
        _c(t, 'overflow number', 4, 'beyond any record', '{in}/stamp_1e308.csv', *FAST, *o),
        _c(t, 'overflow number', 2, 'rate_hz', '{in}/bag', *FAST, '--rate-hz', '1e-320', *o),
        _c(t, 'overflow number', 2, 'has 2e+300 points', '{in}/bag', *FAST, '--order-grid',
           '0:2:1e-300', *o),
        _c(t, 'overflow number', 2, 'has inf points', '{in}/bag', *FAST, '--order-grid',
           '0:1e308:1e-308', *o),
        # refused before any worker is forked (--jobs 99999 once forked 4,500 processes)
        _c(t, 'overflow number', 2, 'per usable CPU', '{in}/bag', *FAST[:-4], '--jobs',
           '99999', *o),
        _c(t, 'CSV dialect', 0, '', '{in}/bom.csv', *FAST, *o),
        _c(t, 'CSV dialect', 0, '', '{in}/crlf.csv', *FAST, *o),
        _c(t, 'CSV dialect', 0, '', '{in}/semicolon.csv', *FAST, *o),
        _c(t, 'CSV dialect', 3, 'decimal commas', '{in}/decimal_comma.csv', *FAST, *o),
        _c(t, 'CSV dialect', 3, 'cannot read CSV', '{in}/utf16.csv', *FAST, *o),
        _c(t, 'signal', 130, '', '{in}/bag', *FAST, *o, hook=sig),
        _c(t, 'signal', 143, '', '{in}/bag', *FAST, *o, hook=sig),
    ]


def _explain_cases():
    t = 'gyro_noise_explain'
    o = ('--out', '{out}', '--quiet')
    sig = 'gyro_noise_ros.cli.explain:run_explain'
    return [
        _c(t, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.mcap', *o),
        _c(t, 'garbage bytes', 3, 'cannot read CSV', '{in}/garbage.csv', *o),
        _c(t, 'bad parameter', 2, '--ensemble', '{in}/ok.csv', '--ensemble', '2', *o),
        _c(t, 'bad parameter', 2, '--bootstrap', '{in}/ok.csv', '--bootstrap', '-1', *o),
        _c(t, 'missing topic', 3, "'/nope'", '{in}/bag', '--topic', '/nope', *o),
        _c(t, 'corrupt bag', 4, 'too short', '{in}/truncated_mcap', *o),
        _c(t, 'corrupt bag', 3, 'garbled_db3', '{in}/garbled_db3', *o),
        _c(t, 'NaN samples', 4, 'NaN/Inf', '{in}/nan_bag', *o),
        _c(t, 'unwritable output', 6, 'not writable', '{in}/ok.csv', '--out', UNWRITABLE),
        _c(t, 'existing output', 6, 'is not empty', '{in}/ok.csv', '--out', '{full}'),
        _c(t, 'overflow number', 2, '--rate-hz', '{in}/ok.csv', '--rate-hz', '1e-300', *o),
        _c(t, 'overflow number', 2, '--ensemble', '{in}/ok.csv', '--ensemble',
           '99999999999999999999999', *o),
        # a window past the end proves the table was read (explain itself takes ~10 s)
        _c(t, 'CSV dialect', 4, 'nothing left to analyse', '{in}/bom.csv', '--start', '1e9',
           *o),
        _c(t, 'CSV dialect', 4, 'nothing left to analyse', '{in}/semicolon.csv', '--start',
           '1e9', *o),
        _c(t, 'signal', 130, '', '{in}/ok.csv', '--axis', 'z', *o, hook=sig),
        _c(t, 'signal', 143, '', '{in}/ok.csv', '--axis', 'z', *o, hook=sig),
    ]


def _thermal_cases():
    t = 'gyro_noise_thermal'
    o = ('--out', '{out}', '--quiet', '--no-figures')
    sim = ('simulate', '--hours', '0.02', '--rate-hz', '10', '--out', '{out}')
    apply = ('apply', '{in}/thermal_bag', '--model', '{in}/model/model.json')
    sig = 'gyro_noise_ros.thermal.simulate:write_pair'
    return [
        _c(t, 'garbage bytes', 3, 'is not a bag', 'fit', '{in}/garbage.mcap', *o),
        _c(t, 'garbage bytes', 3, 'garbage.json', *apply[:2], '--model', '{in}/garbage.json',
           *o),
        _c(t, 'garbage bytes', 3, 'garbage.json', 'export', '--model', '{in}/garbage.json',
           '--out', '{out}'),
        _c(t, 'bad parameter', 2, '--f-lo-hz', *apply, '--f-lo-hz', '0', *o),
        _c(t, 'bad parameter', 2, '--f-hi-hz', *apply, '--f-hi-hz', '1e-9', *o),
        _c(t, 'bad parameter', 2, '--range-margin-c', *apply, '--range-margin-c', 'nan', *o),
        _c(t, 'bad parameter', 2, "unknown method 'nope'", 'fit', '{in}/thermal_bag',
           '--method', 'nope', *o),
        _c(t, 'bad parameter', 2, '--hours', *sim[:1], '--hours', '-1', '--out', '{out}'),
        _c(t, 'bad parameter', 2, '--seed', *sim, '--seed', '-1'),
        _c(t, 'bad parameter', 2, '--seed', 'fit', '{in}/thermal_bag', '--seed', '-1', *o),
        _c(t, 'bad parameter', 2, '--rate-hz', *sim[:1], '--rate-hz', 'nan', '--out', '{out}'),
        _c(t, 'missing topic', 3, '/nope', 'fit', '{in}/thermal_bag', '--topic', '/nope', *o),
        _c(t, 'missing topic', 3, 'Temperature', 'fit', '{in}/bag', *o),
        _c(t, 'missing topic', 3, 'missing.json', *apply[:2], '--model', '{in}/missing.json',
           *o),
        _c(t, 'corrupt bag', 3, 'garbled_db3', 'fit', '{in}/garbled_db3', *o),
        _c(t, 'NaN samples', 4, 'NaN', 'fit', '{in}/nan_thermal_bag', *o),
        _c(t, 'unwritable output', 6, 'not writable', 'fit', '{in}/thermal_bag', '--out',
           UNWRITABLE),
        _c(t, 'unwritable output', 6, 'cannot be created', *sim[:-1], '{file}/sim'),
        _c(t, 'existing output', 6, 'is not empty', *apply, '--out', '{full}'),
        _c(t, 'existing output', 6, 'is not empty', *sim[:-1], '{full}'),
        _c(t, 'existing output', 6, 'is not empty', 'export', '--model',
           '{in}/model/model.json', '--out', '{full}'),
        _c(t, 'overflow number', 2, 'GiB', 'simulate', '--hours', '1e6', '--out', '{out}'),
        _c(t, 'overflow number', 2, 'GiB', 'simulate', '--rate-hz', '1e300', '--out',
           '{out}'),
        _c(t, 'overflow number', 2, '--f-lo-hz', *apply, '--f-lo-hz', 'inf', *o),
        _c(t, 'signal', 130, '', *sim, hook=sig),
        _c(t, 'signal', 143, '', *sim, hook=sig),
    ]


def _calibration_cases():
    cal, rel, exc = 'gyro_noise_calibrate', 'gyro_noise_reliability', 'gyro_noise_excitation'
    o = ('--out', '{out}')
    rel_in = ('--before-calibration', '{in}/bag', '--after-calibration', '{in}/bag')
    exc_in = ('--sensor', 'accel', '--axis', 'x', '--dwell', '8')
    return [
        _c(cal, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.mcap', *o),
        _c(cal, 'bad parameter', 2, '--gravity', '{in}/bag', '--gravity', '100', *o),
        _c(cal, 'bad parameter', 2, '--alpha', '{in}/bag', '--alpha', '2', *o),
        _c(cal, 'missing topic', 3, '/nope', '{in}/bag', '--topic', '/nope', *o),
        _c(cal, 'corrupt bag', 3, 'garbled_db3', '{in}/garbled_db3', *o),
        _c(cal, 'NaN samples', 4, 'NaN', '{in}/nan_bag', *o),
        _c(cal, 'unwritable output', 6, 'not writable', '{in}/bag', '--out', UNWRITABLE),
        _c(cal, 'existing output', 6, 'is not empty', '{in}/bag', '--out', '{full}'),
        _c(cal, 'overflow number', 2, '--gravity', '{in}/bag', '--gravity', '1e308', *o),
        _c(cal, 'overflow number', 2, '--rate-hz', '{in}/bag', '--rate-hz', '1e-320', *o),
        _c(cal, 'signal', 130, '', '{in}/bag', *o,
           hook='gyro_noise_ros.cli.calibrate:run_calibration'),
        _c(cal, 'signal', 143, '', '{in}/bag', *o,
           hook='gyro_noise_ros.cli.calibrate:run_calibration'),
        _c(rel, 'garbage bytes', 3, 'is not a bag', '--before-calibration',
           '{in}/garbage.mcap', '--after-calibration', '{in}/bag', *o),
        _c(rel, 'bad parameter', 2, '--tolerance', *rel_in, '--tolerance', '-1', *o),
        _c(rel, 'missing topic', 3, '/nope', *rel_in, '--topic', '/nope', *o),
        _c(rel, 'corrupt bag', 3, 'garbled_db3', '--before-calibration',
           '{in}/garbled_db3', '--after-calibration', '{in}/bag', *o),
        _c(rel, 'NaN samples', 4, 'NaN', '--before-static', '{in}/nan_bag', '--after-static',
           '{in}/bag', *o),
        _c(rel, 'unwritable output', 6, 'cannot be created', *rel_in, '--out', '{file}/x'),
        _c(rel, 'existing output', 6, 'is not empty', *rel_in, '--out', '{full}'),
        _c(rel, 'overflow number', 2, '--gravity', *rel_in, '--gravity', '1e308', *o),
        _c(rel, 'overflow number', 2, '--rate-hz', '--before-static', '{in}/bag',
           '--after-static', '{in}/bag', '--rate-hz', '1e-320', *o),
        _c(exc, 'garbage bytes', 3, 'is not a bag', '{in}/garbage.mcap', *exc_in, *o),
        _c(exc, 'bad parameter', 2, 'Nyquist', '{in}/bag', '--sensor', 'accel', '--axis', 'x',
           '--dwell', '150', *o),
        _c(exc, 'missing topic', 3, '/nope', '{in}/bag', *exc_in, '--topic', '/nope', *o),
        _c(exc, 'corrupt bag', 3, 'garbled_db3', '{in}/garbled_db3', *exc_in, *o),
        _c(exc, 'NaN samples', 4, 'NaN', '{in}/nan_bag', '--sensor', 'gyro', '--axis', 'x',
           '--dwell', '8', *o),
        _c(exc, 'unwritable output', 6, 'not writable', '{in}/bag', *exc_in, '--out',
           UNWRITABLE),
        _c(exc, 'existing output', 6, 'is not empty', '{in}/bag', *exc_in, '--out', '{full}'),
        _c(exc, 'overflow number', 2, '--dwell', '{in}/bag', '--sensor', 'accel', '--axis', 'x',
           '--dwell', '1e308', *o),
    ]


def _import_cases():
    t, r = 'gyro_noise_import', 'gyro_noise_record repair'
    logs = '{in}/sd/S001F000.GNL'
    o = ('--out', '{out}')
    return [
        _c(t, 'garbage bytes', 4, 'no readable log header', '{in}/garbage.GNL', *o),
        _c(t, 'bad parameter', 2, 'chunk_bytes', logs, '--chunk-bytes', '0', *o),
        _c(t, 'bad parameter', 2, '--start-time', logs, '--start-time', 'yesterday', *o),
        _c(t, 'bad parameter', 2, 'topic', logs, '--topic', 'a b', *o),
        _c(t, 'bad parameter', 2, 'both', logs, '--topic', '/imu/temperature', *o),
        _c(t, 'missing topic', 3, 'does not exist', '{in}/sd/S001F999.GNL', *o),
        _c(t, 'corrupt bag', 0, '', '{in}/sd_corrupt/S001F000.GNL', *o),
        _c(t, 'unwritable output', 6, 'cannot be created', logs, '--out', '{file}/bag'),
        _c(t, 'unwritable output', 6, 'not writable', logs, '--out', UNWRITABLE + '/bag'),
        _c(t, 'existing output', 6, 'already exists', logs, '--out', '{full}'),
        _c(t, 'unwritable output', 6, '--out is empty', logs, '--out', ' '),
        _c(t, 'existing output', 6, 'is a folder that is not a bag', logs, '--out', '{full}',
           '--overwrite'),
        _c(t, 'overflow number', 2, '--start-time', logs, '--start-time', '1e30', *o),
        _c(t, 'overflow number', 2, '--start-time', logs, '--start-time', 'inf', *o),
        _c(t, 'overflow number', 2, 'temperature_rate_hz', logs, '--temperature-rate-hz',
           'nan', *o),
        _c(t, 'signal', 130, '', logs, *o, hook='gyro_noise_ros.app.importer:_convert'),
        _c(t, 'signal', 143, '', logs, *o, hook='gyro_noise_ros.app.importer:_convert'),
        _c(r, 'garbage bytes', 3, 'garbage.mcap', 'repair', '{in}/garbage.mcap', *o),
        _c(r, 'garbage bytes', 3, 'garbage_meta', 'repair', '{in}/garbage_meta', *o),
        _c(r, 'bad parameter', 2, 'invalid choice', 'repair', '{in}/bag', '--storage', 'zip',
           *o),
        _c(r, 'missing topic', 3, 'does not exist', 'repair', '{in}/nope', *o),
        _c(r, 'corrupt bag', 3, 'garbled_db3', 'repair', '{in}/garbled_db3', *o),
        _c(r, 'unwritable output', 6, 'cannot be created', 'repair', '{in}/bag', '--out',
           '{file}/x'),
        _c(r, 'existing output', 6, 'already exists', 'repair', '{in}/bag', '--out', '{full}'),
        _c(r, 'existing output', 6, 'is the input', 'repair', '{in}/bag', '--out', '{in}/bag'),
        _c(r, 'signal', 130, '', 'repair', '{in}/bag', *o,
           hook='gyro_noise_ros.bag.repair:write_raw'),
        _c(r, 'signal', 143, '', 'repair', '{in}/bag', *o,
           hook='gyro_noise_ros.bag.repair:write_raw'),
    ]


def _emulator_cases():
    t = 'portenta_emulator'
    sd = ('--write-sd', '{out}')
    bag = ('--write-bag', '{out}')
    return [
        _c(t, 'bad parameter', 2, '--samples must be >= 1', *sd, '--samples', '0'),
        _c(t, 'bad parameter', 2, '--duration-s must be > 0', *bag, '--duration-s', '0'),
        _c(t, 'bad parameter', 2, 'holds no sample', *bag, '--duration-s', '1e-9'),
        _c(t, 'bad parameter', 2, '--samples must be >= 1', '--tcp', '127.0.0.1:0',
           '--samples', '-5'),
        _c(t, 'bad parameter', 2, '--temp-c', *sd, '--samples', '10', '--temp-c', 'nan'),
        _c(t, 'bad parameter', 2, '--temp-c', *sd, '--samples', '10', '--temp-c', '1000'),
        _c(t, 'bad parameter', 2, 'exclude each other', *sd, '--write-bag', '{out}2',
           '--samples', '10'),
        _c(t, 'bad parameter', 2, '--speed', '--speed', '0'),
        _c(t, 'bad parameter', 2, '--bias-dps', *sd, '--samples', '10', '--bias-dps', '1,nan,2'),
        _c(t, 'bad parameter', 2, '--tcp', '--tcp', 'nowhere', '--samples', '10'),
        _c(t, 'bad parameter', 2, '--seed', *sd, '--samples', '10', '--seed', '-1'),
        _c(t, 'bad parameter', 2, '--seq0', *sd, '--samples', '10', '--seq0', str(2**32)),
        _c(t, 'bad parameter', 2, '--sequence-id', *sd, '--samples', '10', '--sequence-id',
           '1000'),
        _c(t, 'bad parameter', 2, 'topic of the board', *bag, '--samples', '10', '--scenario',
           'sine', '--reference-topic', 'imu/data_raw'),
        _c(t, 'overflow number', 2, 'overflow', *sd, '--samples', '10', '--alpha', '1e300'),
        _c(t, 'unwritable output', 6, 'cannot be created', '--write-sd', '{file}/sd',
           '--samples', '10'),
        _c(t, 'unwritable output', 6, 'not writable', '--write-bag', UNWRITABLE,
           '--samples', '10'),
        _c(t, 'unwritable output', 6, 'is a folder', '--truth-out', '{full}', *sd, '--samples',
           '10'),
        _c(t, 'existing output', 6, 'is not empty', '--write-sd', '{full}', '--samples', '10'),
        # '' once read as "not given": the board was served on a pty for ever
        _c(t, 'unwritable output', 6, '--write-bag is empty', '--write-bag', '', '--samples',
           '10'),
        _c(t, 'existing output', 6, 'already exists', '--write-bag', '{full}', '--samples',
           '10'),
        _c(t, 'existing output', 6, 'already exists', '--stats-out', '{file}', *sd,
           '--samples', '10'),
        _c(t, 'overflow number', 2, 'GiB', *sd, '--samples', str(10**15)),
        _c(t, 'overflow number', 2, 'GiB', *bag, '--duration-s', '1e12'),
        _c(t, 'overflow number', 2, 'finite', *bag, '--duration-s', 'inf'),
        _c(t, 'overflow number', 2, 'finite', *sd, '--samples', '10', '--speed', '1e400'),
        _c(t, 'signal', 130, '', *bag, '--samples', '140000',
           hook='gyro_noise_ros.bag.writer:ImuBagWriter.write_imu'),
        _c(t, 'signal', 143, '', *bag, '--samples', '140000',
           hook='gyro_noise_ros.bag.writer:ImuBagWriter.write_imu'),
        _c(t, 'signal', 130, '', *sd, '--samples', '200000',
           hook='gyro_noise_ros.link.sdlog:SdLogWriter.write_samples'),
        _c(t, 'signal', 143, '', *sd, '--samples', '200000',
           hook='gyro_noise_ros.link.sdlog:SdLogWriter.write_samples'),
    ]


def _demo_cases():
    t = 'gyro_noise_demo'
    return [
        _c(t, 'bad parameter', 2, '--speed', '--speed', '0', '--out', '{out}'),
        _c(t, 'bad parameter', 2, '--domain-id', '--domain-id', '1000', '--out', '{out}'),
        _c(t, 'bad parameter', 2, '--seed', '--seed', '-1', '--out', '{out}'),
        _c(t, 'unwritable output', 6, 'is an existing file', '--out', '{file}'),
        _c(t, 'unwritable output', 6, 'not writable', '--out', UNWRITABLE),
        _c(t, 'existing output', 6, 'not a previous demo output', '--out', '{full}'),
        _c(t, 'existing output', 6, 'not a previous demo output', '--out', '{full}',
           '--overwrite'),
        _c(t, 'existing output', 6, 'holds a previous demo output', '--out', '{in}/old_demo'),
    ]


def _node_cases():
    d, a, c, r, m, chain = NODES
    ra = '--ros-args'
    cases = [
        *[_c(n, 'help', 0, '', flag) for n in (d, a, c, r, chain) for flag in ('--help', '-h')],
        _c(d, 'bad parameter', 2, "'odr_hz'", ra, '-p', 'odr_hz:=abc'),
        _c(d, 'bad parameter', 2, "'odr_hz'", ra, '-p', 'odr_hz:=1.0'),
        _c(d, 'bad parameter', 2, 'unknown parameter', ra, '-p', 'odr:=104.0'),
        _c(d, 'bad parameter', 2, 'unknown argument', '--port', '/dev/ttyACM0'),
        _c(d, 'bad parameter', 2, 'unknown ROS arguments', ra, '--bogus'),
        _c(d, 'bad parameter', 2, 'bad ROS arguments', ra, '-p', 'port:='),
        _c(a, 'bad parameter', 2, "'chunk_sise' (did you mean 'chunk_size'?)", ra, '-p',
           'chunk_sise:=100'),
        _c(a, 'bad parameter', 2, "'chunk_size'", ra, '-p', 'chunk_size:=1'),
        _c(a, 'bad parameter', 2, "'axes'", ra, '-p', 'axes:=q'),
        _c(a, 'overflow number', 2, "'chunk_size'", ra, '-p',
           'chunk_size:=99999999999999999999999'),
        _c(c, 'bad parameter', 2, 'array of floating-point numbers', ra, '-p',
           'gyro_bias_rad_s:=abc'),
        _c(c, 'bad parameter', 2, 'array of floating-point numbers', ra, '-p',
           'gyro_bias_rad_s:=[1,2,3]'),
        _c(c, 'bad parameter', 2, 'must be 3 finite', ra, '-p', 'gyro_bias_rad_s:=[1.0,2.0]'),
        _c(c, 'bad parameter', 2, 'must be 3 finite', ra, '-p',
           'gyro_bias_rad_s:=[1.0,.nan,2.0]'),
        _c(c, 'garbage bytes', 3, 'cannot be read as YAML', ra, '-p',
           'calibration_file:={in}/garbage.yaml'),
        _c(c, 'garbage bytes', 3, 'garbage.json', ra, '-p',
           'thermal_model_file:={in}/garbage.json'),
        _c(c, 'missing topic', 3, 'does not exist', ra, '-p',
           'calibration_file:={in}/missing.yaml'),
        _c(c, 'missing topic', 3, 'missing.json', ra, '-p',
           'thermal_model_file:={in}/missing.json'),
        _c(c, 'garbage bytes', 2, 'bad ROS arguments', ra, '--params-file',
           '{in}/garbage.yaml'),
        _c(r, 'unwritable output', 6, "afile' is a file", ra, '-p', 'output:={file}/bag'),
        _c(r, 'unwritable output', 6, 'not writable', ra, '-p', f'output:={UNWRITABLE}/bag'),
        _c(r, 'existing output', 6, 'already exists: give -p overwrite:=true', ra, '-p',
           'output:={full}'),
        _c(r, 'existing output', 6, 'a folder that is not a bag', ra, '-p',
           'output:={full}', '-p', 'overwrite:=true'),
        _c(r, 'bad parameter', 2, "'storage'", ra, '-p', 'storage:=zip'),
        _c(m, 'bad parameter', 2, "unknown parameter 'chunk_size'", ra, '-p',
           'chunk_size:=100'),
        _c(m, 'bad parameter', 2, 'unknown ROS arguments', ra, '--bogus'),
    ]
    # imu_chain, both nodes' parameters on one command line: it refuses what each node refuses,
    # as that node does, and a name neither declares
    return [*cases, *[_c(chain, case.klass, case.code, case.text, *case.args) for case in cases
                      if case.tool in (d, c) and case.klass != 'help'],
            _c(chain, 'bad parameter', 2, 'nor does any other node', ra, '-p', 'odr:=104.0')]


CASES = [*_analyze_cases(), *_explain_cases(), *_thermal_cases(), *_calibration_cases(),
         *_import_cases(), *_emulator_cases(), *_demo_cases(), *_node_cases()]


def _case_id(case):
    return f'{case.tool}|{case.klass}|' + ' '.join(case.args)[:60]


def _params(tools):
    return [pytest.param(case, id=_case_id(case)) for case in CASES if case.tool in tools]


# --- the inputs -----------------------------------------------------------------------------


def _gyro(n, seed):
    return np.random.default_rng(seed).standard_normal((n, 3)) * 1e-3


def _write_tables(d, gyro):
    t = np.arange(N) / RATE_HZ
    header = 'time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s'
    rows = [','.join(repr(float(v)) for v in (t[i], *g)) for i, g in enumerate(gyro)]
    (d / 'bom.csv').write_bytes(('\ufeff' + '\n'.join([header, *rows]) + '\n').encode())
    (d / 'crlf.csv').write_bytes(('\r\n'.join([header, *rows]) + '\r\n').encode())
    (d / 'semicolon.csv').write_text('\n'.join([header.replace(',', ';'),
                                                *(r.replace(',', ';') for r in rows)]) + '\n')
    (d / 'decimal_comma.csv').write_text(
        '\n'.join([header.replace(',', ';'),
                   *(r.replace(',', ';').replace('.', ',') for r in rows)]) + '\n')
    (d / 'utf16.csv').write_bytes('\n'.join([header, *rows[:50]]).encode('utf-16'))
    (d / 'stamp_1e308.csv').write_text('\n'.join([header, *rows[:-1],
                                                  '1e308,0.0,0.0,0.0']) + '\n')
    (d / 'nan_time.csv').write_text('\n'.join([header, *rows[:-1], 'nan,0.0,0.0,0.0']) + '\n')


def _write_garbage(d):
    rng = np.random.default_rng(33)
    for name in ('garbage.mcap', 'garbage.db3', 'garbage.bag', 'garbage.csv', 'garbage.ulg',
                 'garbage.json', 'garbage.yaml', 'garbage.GNL'):
        (d / name).write_bytes(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    (d / 'garbage_meta').mkdir()
    (d / 'garbage_meta' / 'metadata.yaml').write_bytes(rng.integers(0, 256, 512,
                                                                    dtype=np.uint8).tobytes())


def _write_corrupt_bags(d, make_record):
    mcap = make_record(d / 'truncated_mcap', _gyro(N, 4), rate_hz=RATE_HZ, storage='mcap')
    (storage,) = mcap.glob('*.mcap')
    storage.write_bytes(storage.read_bytes()[:storage.stat().st_size // 3])
    mcap = make_record(d / 'garbled_mcap', _gyro(N, 7), rate_hz=RATE_HZ, storage='mcap')
    (storage,) = mcap.glob('*.mcap')
    data = bytearray(storage.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 4096] = np.random.default_rng(8).integers(
        0, 256, 4096, dtype=np.uint8).tobytes()
    storage.write_bytes(bytes(data))
    db3 = make_record(d / 'garbled_db3', _gyro(N, 5), rate_hz=RATE_HZ)
    (storage,) = db3.glob('*.db3')
    data = bytearray(storage.read_bytes())
    data[100:4196] = np.random.default_rng(6).integers(0, 256, 4096, dtype=np.uint8).tobytes()
    storage.write_bytes(bytes(data))


def _write_thermal(d):
    """Write a bag with temperature (the emulator), a poly3 model fitted on it, a NaN copy."""
    from gyro_noise_ros.bag import ImuBagReader, ImuBagWriter
    from gyro_noise_ros.cli import emulator, thermal

    assert emulator.main(['--write-bag', str(d / 'thermal_bag'), '--odr-hz', '104',
                          '--duration-s', '120', '--temp-c', '20', '--temp-drift-c-per-h',
                          '600', '--temp-sensitivity-dps-per-c', '0.01',
                          '--bag-temperature-decimation', '2']) == 0
    assert thermal.main(['fit', str(d / 'thermal_bag'), '--method', 'poly3', '--quiet',
                         '--no-figures', '--out', str(d / 'model')]) == 0
    with ImuBagReader(d / 'thermal_bag') as reader, ImuBagWriter(d / 'nan_thermal_bag') as w:
        t_stamp, t_value = reader.read_temperature()
        for batch in reader.iter_batches(100_000):
            gyro = batch.gyro.copy()
            gyro[::7] = np.nan
            w.write_imu(batch.stamp_ns, gyro, batch.accel)
        w.write_temperature(t_stamp, t_value)


@pytest.fixture(scope='module')
def inputs(tmp_path_factory, make_record):
    from gyro_noise_ros.cli import emulator

    d = tmp_path_factory.mktemp('bad_inputs')
    gyro = _gyro(N, 1)
    make_record(d / 'ok.csv', gyro, rate_hz=RATE_HZ, storage='csv')
    make_record(d / 'bag', gyro, rate_hz=RATE_HZ)
    make_record(d / 'nan_bag', np.full((N, 3), np.nan), rate_hz=RATE_HZ)
    _write_tables(d, gyro)
    _write_garbage(d)
    _write_corrupt_bags(d, make_record)
    _write_thermal(d)
    for name, extra in (('sd', []), ('sd_corrupt', ['--corrupt-rate', '1e-4'])):
        assert emulator.main(['--write-sd', str(d / name), '--samples', '30000', '--seed', '3',
                              *extra]) == 0
    (d / 'old_demo').mkdir()
    (d / 'old_demo' / 'GYRO_NOISE_DEMO.txt').write_text('Written by gyro_noise_ros.cli.demo\n')
    return d


# --- the checks -----------------------------------------------------------------------------


def _snapshot(folder):
    """Every entry under ``folder`` (hidden ones included): path -> sha256 or 'dir'."""
    out = {}
    for path in sorted(Path(folder).rglob('*')):
        rel = str(path.relative_to(folder))
        out[rel] = 'dir' if path.is_dir() else hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _stat_snapshot(folder):
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in sorted(Path(folder).rglob('*')) if p.is_file()}


def check_stderr(prog, err, code, text):
    """One error (or interrupted) line last, no traceback, no numpy or Python warning."""
    assert 'Traceback' not in err and 'Warning:' not in err, err
    lines = [ln for ln in err.strip().splitlines()
             if not ln.startswith(('[INFO]', '[WARN]', '[ERROR]'))]
    if code == 0:
        assert not any(': error:' in ln for ln in lines), err
        return
    assert lines, f'exit {code} without a word'
    last = lines[-1]
    if code in (130, 143):
        want = f'{prog}: interrupted' + ('' if code == 130 else ' (SIGTERM)')
        assert last == want, err
        return
    assert last.startswith(f'{prog}: error: '), err
    assert text in last, err
    # warnings may precede the error; a second error may not
    assert not any(ln.startswith(f'{prog}: error: ') for ln in lines[:-1]), err


def _hooked(monkeypatch, hook, sig):
    """Make ``module:attr`` (or ``module:Class.method``) send ``sig`` to this process once."""
    module_name, _, attr = hook.partition(':')
    owner = importlib.import_module(module_name)
    *path, name = attr.split('.')
    for part in path:
        owner = getattr(owner, part)
    real = getattr(owner, name)
    sent = []

    def hooked(*args, **kwargs):
        if not sent:
            sent.append(sig)
            os.kill(os.getpid(), sig)  # delivered to this thread before kill returns
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, hooked)
    return sent


def _prepare(tmp_path, inputs):
    work = tmp_path / 'work'
    work.mkdir()
    (work / 'full').mkdir()
    (work / 'full' / 'precious.txt').write_text('keep me\n')
    (work / 'afile').write_text('a file, not a folder\n')
    subs = {'in': str(inputs), 'out': str(work / 'out'), 'full': str(work / 'full'),
            'file': str(work / 'afile'), 'ro': UNWRITABLE}
    return work, subs


def run_case(case, inputs, tmp_path, capsys, monkeypatch):
    """Run one case in-process and check its code, its stderr and what it left (module doc)."""
    work, subs = _prepare(tmp_path, inputs)
    argv = [a.format(**subs) for a in case.args]
    before, inputs_before = _snapshot(work), _stat_snapshot(inputs)
    prog = case.tool
    if prog == 'gyro_noise_record repair':
        argv = ['repair', *argv[1:]] if argv[:1] == ['repair'] else argv
    if case.hook:
        sent = _hooked(monkeypatch, case.hook, signal.SIGINT if case.code == 130
                       else signal.SIGTERM)
    main = importlib.import_module(PROGS[prog]).main
    monkeypatch.chdir(work)
    # a warning a program would print on stderr (numpy's RuntimeWarning, a UserWarning): pytest
    # would only collect it, so it is recorded here and refused below
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        code = _run_node(main, prog, argv) if prog in NODES else main(argv)
    shown = [f'{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})' for w in caught
             if not issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning,
                                            ImportWarning, ResourceWarning))]
    captured = capsys.readouterr()
    err = captured.err + (captured.out if prog in NODES and case.code == 2 else '')
    assert code == case.code, f'{_case_id(case)}: exit {code}, expected {case.code}\n{err}'
    if case.hook:
        assert sent, 'the signal was never sent: the hook is not on the path'
    check_stderr(prog, err, code, case.text)
    assert not shown, shown
    if case.klass == 'help':
        assert '--ros-args' in captured.out and ' = ' in captured.out
    after = _snapshot(work)
    assert {k: v for k, v in after.items() if k in before} == before  # nothing lost
    if code != 0:
        # a refusal, a failure or an interrupt leaves nothing new: no folder, no hidden stage
        assert after == before, sorted(set(after) - set(before))
    assert _stat_snapshot(inputs) == inputs_before  # the inputs are only read


def _run_node(main, prog, argv):
    """Run a node's main in-process; a watchdog shuts rclpy down if it starts spinning."""
    import rclpy

    stop = threading.Event()

    def watchdog():
        if not stop.wait(20.0):
            rclpy.try_shutdown()  # a node that should have refused spins: end it, exit 0

    thread = threading.Thread(target=watchdog, daemon=True)
    thread.start()
    try:
        return main([prog, *argv])
    finally:
        stop.set()
        thread.join()


# --- the tests --------------------------------------------------------------------------------


@pytest.mark.parametrize('case', _params(['gyro_noise_analyze', 'gyro_noise_explain']))
def test_analysis_tools(case, inputs, tmp_path, capsys, monkeypatch):
    run_case(case, inputs, tmp_path, capsys, monkeypatch)


@pytest.mark.parametrize('case', _params(['gyro_noise_thermal']))
def test_thermal_tool(case, inputs, tmp_path, capsys, monkeypatch):
    run_case(case, inputs, tmp_path, capsys, monkeypatch)


@pytest.mark.parametrize('case', _params(['gyro_noise_calibrate', 'gyro_noise_reliability',
                                          'gyro_noise_excitation']))
def test_reliability_tools(case, inputs, tmp_path, capsys, monkeypatch):
    run_case(case, inputs, tmp_path, capsys, monkeypatch)


@pytest.mark.parametrize('case', _params(['gyro_noise_import', 'gyro_noise_record repair',
                                          'portenta_emulator', 'gyro_noise_demo']))
def test_recording_tools(case, inputs, tmp_path, capsys, monkeypatch):
    run_case(case, inputs, tmp_path, capsys, monkeypatch)


@pytest.mark.ros
@pytest.mark.parametrize('case', _params(NODES))
def test_nodes(case, inputs, tmp_path, capsys, monkeypatch):
    run_case(case, inputs, tmp_path, capsys, monkeypatch)


def test_every_tool_and_node_meets_every_class_it_can():
    by_tool = {}
    for case in CASES:
        by_tool.setdefault(case.tool, set()).add(case.klass)
    assert set(by_tool) == set(PROGS), set(PROGS) - set(by_tool)
    assert {case.klass for case in CASES} == set(CLASSES)
    for tool in ('gyro_noise_analyze', 'gyro_noise_explain', 'gyro_noise_thermal',
                 'gyro_noise_calibrate', 'gyro_noise_import', 'gyro_noise_record repair',
                 'portenta_emulator'):
        assert {'bad parameter', 'unwritable output', 'existing output'} <= by_tool[tool], tool
    for tool in ('gyro_noise_analyze', 'gyro_noise_explain', 'gyro_noise_thermal',
                 'gyro_noise_calibrate', 'gyro_noise_import', 'gyro_noise_record repair',
                 'portenta_emulator'):
        assert 'signal' in by_tool[tool], tool
    assert all(case.code in EXIT_CODES for case in CASES)


def test_readme_exit_table_is_errors_exit_codes():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'tools'))
    try:
        exit_codes = importlib.import_module('exit_codes')
    finally:
        sys.path.pop(0)
    assert exit_codes.readme_table(exit_codes.README.read_text()) == exit_codes.markdown_table()
    assert set(EXIT_CODES) == {0, 1, 2, 3, 4, 5, 6, 130, 143}


def test_signals_are_noted_early_only_in_a_program_of_the_package(tmp_path, monkeypatch):
    from gyro_noise_ros.cli import _startup

    assert not _startup.launched_as_program()  # pytest imported the tools: hands off
    assert signal.getsignal(signal.SIGINT) is not getattr(_startup, '_note')
    stub = tmp_path / 'noise_analyzer'  # what pip writes for a console script
    stub.write_text('import sys\nfrom gyro_noise_ros.nodes.analyzer import main\n'
                    "if __name__ == '__main__':\n    sys.exit(main())\n")
    mine = tmp_path / 'my_tool'  # a user's program that uses the package keeps its Ctrl-C
    mine.write_text(stub.read_text() + '# more of my own code\n' * 100)
    for argv, program in (([str(stub)], True), ([str(mine)], False),
                          (['-m', 'gyro_noise_ros.cli.analyze'], True), (['-m', 'pytest'], False)):
        monkeypatch.setattr(sys, 'argv', argv[-1:])
        monkeypatch.setattr(sys, 'orig_argv', [sys.executable, *argv])
        assert _startup.launched_as_program() == program, argv


def test_every_error_class_has_a_documented_code():
    import gyro_noise_ros
    from gyro_noise_ros.errors import GyroNoiseError
    import pkgutil

    for info in pkgutil.walk_packages(gyro_noise_ros.__path__, 'gyro_noise_ros.'):
        if '.nodes' in info.name:
            continue  # they import rclpy; their errors are the package's
        importlib.import_module(info.name)

    def subclasses(cls):
        for sub in cls.__subclasses__():
            yield sub
            yield from subclasses(sub)

    found = list(subclasses(GyroNoiseError))
    assert len(found) >= 10
    assert all(cls.exit_code in EXIT_CODES for cls in found), [
        (cls.__name__, cls.exit_code) for cls in found if cls.exit_code not in EXIT_CODES]


# --- --overwrite, stages of killed runs, the page's JSON, a full disk ------------------------


def test_overwrite_writes_into_a_folder_and_keeps_other_files(inputs, tmp_path, capsys):
    from gyro_noise_ros.cli.analyze import main

    out = tmp_path / 'report'
    out.mkdir()
    (out / 'precious.txt').write_text('keep me\n')
    (out / 'summary.json').write_text('old\n')
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out), '--overwrite']) == 0
    assert (out / 'precious.txt').read_text() == 'keep me\n'
    assert json.loads((out / 'summary.json').read_text())['bags'][0]['samples'] == N
    # and without it the same folder is refused, unchanged
    before = _snapshot(out)
    assert main([str(inputs / 'bag'), *FAST, '--out', str(out)]) == 6
    assert 'is not empty' in capsys.readouterr().err
    assert _snapshot(out) == before


def test_overwrite_replaces_a_bag_only_when_the_new_one_is_complete(
        inputs, tmp_path, capsys, monkeypatch):
    from gyro_noise_ros.cli.importer import main

    logs = [str(p) for p in sorted((inputs / 'sd').glob('*.GNL'))]
    bag = tmp_path / 'bag'
    assert main([*logs, '--out', str(bag), '--start-time', '0']) == 0
    first = _snapshot(bag)
    assert main([*logs, '--out', str(bag)]) == 6
    _hooked(monkeypatch, 'gyro_noise_ros.app.importer:_convert', signal.SIGTERM)
    assert main([*logs, '--out', str(bag), '--overwrite', '--start-time', '5']) == 143
    assert _snapshot(bag) == first and sorted(os.listdir(tmp_path)) == ['bag']
    monkeypatch.undo()
    assert main([*logs, '--out', str(bag), '--overwrite', '--start-time', '5']) == 0
    assert _snapshot(bag) != first and sorted(os.listdir(tmp_path)) == ['bag']
    capsys.readouterr()


def test_write_sd_overwrite_replaces_the_whole_sequence(tmp_path, capsys):
    from gyro_noise_ros.cli.emulator import main

    sd = tmp_path / 'sd'
    assert main(['--write-sd', str(sd), '--samples', '20000', '--sd-file-bytes', '100000']) == 0
    (sd / 'notes.txt').write_text('mine\n')
    old = sorted(p.name for p in sd.glob('*.GNL'))
    assert len(old) == 5
    first = (sd / 'S001F000.GNL').read_bytes()
    assert main(['--write-sd', str(sd), '--samples', '20000', '--seed', '9']) == 6
    assert (sd / 'S001F000.GNL').read_bytes() == first  # the lost log
    assert main(['--write-sd', str(sd), '--samples', '8000', '--seed', '9',
                 '--sd-file-bytes', '100000', '--overwrite']) == 0
    assert sorted(p.name for p in sd.glob('*.GNL')) == old[:2]  # no file of the old run left
    assert (sd / 'S001F000.GNL').read_bytes() != first
    assert (sd / 'notes.txt').read_text() == 'mine\n'
    capsys.readouterr()


@pytest.mark.parametrize('tool', ['analyze', 'import', 'write-bag', 'write-sd', 'repair'])
def test_a_stage_left_by_a_killed_run_is_removed_by_the_next_and_a_live_one_kept(
        tool, inputs, tmp_path, capsys):
    import fcntl
    import importlib as il

    out = tmp_path / 'out'
    inside = tool in ('analyze', 'write-sd')  # stages inside --out, else beside the bag
    where = out if inside else tmp_path
    where.mkdir(exist_ok=True)
    name = '.partial-{}-dead' if inside else '.out.partial-{}'
    dead, live = where / name.format(999999), where / name.format(os.getpid())
    for stage in (dead, live):
        stage.mkdir()
        (stage / 'half.bin').write_bytes(b'x' * 1000)
    fd = os.open(live, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX)  # a run in progress holds its stage
    argv = {'analyze': ('gyro_noise_ros.cli.analyze', [str(inputs / 'bag'), *FAST]),
            'import': ('gyro_noise_ros.cli.importer', [str(inputs / 'sd' / 'S001F000.GNL')]),
            'write-bag': ('gyro_noise_ros.cli.emulator', ['--samples', '100', '--write-bag']),
            'write-sd': ('gyro_noise_ros.cli.emulator', ['--samples', '100', '--write-sd']),
            'repair': ('gyro_noise_ros.cli.record', ['repair', str(inputs / 'bag')])}[tool]
    out_option = [] if tool.startswith('write') else ['--out']
    try:
        code = il.import_module(argv[0]).main([*argv[1], *out_option, str(out)])
    finally:
        os.close(fd)
    assert code == 0, capsys.readouterr().err
    assert not dead.exists() and (live / 'half.bin').exists()


def test_the_page_json_survives_a_label_that_opens_a_script(inputs, tmp_path):
    from gyro_noise_ros.cli.analyze import main

    label = '<!--<script></script>x'
    out = tmp_path / 'out'
    argv = [str(inputs / 'bag'), *[a for a in FAST if a != '--no-html'], '--label', label]
    assert main([*argv, '--out', str(out)]) == 0
    text = (out / 'report.html').read_text()
    start = text.index('<script type="application/json" id="gyro-noise-data">')
    body = text[text.index('>', start) + 1:text.index('</script>', start)]
    # no "<" at all: the HTML tokenizer cannot leave the script data state early or enter its
    # escaped states ("<!--" then "<script"), whatever a label holds
    assert '<' not in body
    assert json.loads(body)['bags'][0]['label'] == label
    assert json.loads(body) == json.loads((out / 'summary.json').read_text())


def test_repair_on_a_full_disk_is_an_output_error(inputs, tmp_path, capsys, monkeypatch):
    import errno

    from gyro_noise_ros.bag import repair
    from gyro_noise_ros.cli.record import main

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(repair, 'write_raw', full)
    assert main(['repair', str(inputs / 'bag'), '--out', str(tmp_path / 'r')]) == 6
    check_stderr('gyro_noise_record repair', capsys.readouterr().err, 6,
                 'No space left on device')
    assert list(tmp_path.iterdir()) == []


@pytest.mark.ros
def test_recorder_overwrite_replaces_only_a_bag_and_only_when_data_come(inputs, tmp_path):
    import rclpy
    from rclpy.parameter import Parameter

    from gyro_noise_ros.errors import OutputError
    from gyro_noise_ros.nodes.recorder import RecorderNode

    bag = tmp_path / 'bag'
    shutil.copytree(inputs / 'bag', bag)
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        with pytest.raises(OutputError, match='overwrite:=true'):
            RecorderNode(context=ctx, parameter_overrides=[Parameter('output', value=str(bag))])
        node = RecorderNode(context=ctx, parameter_overrides=[
            Parameter('output', value=str(bag)), Parameter('overwrite', value=True)])
        try:
            assert (bag / 'metadata.yaml').exists()  # kept until the first message
            node._open('imu_link')
            assert not (bag / 'metadata.yaml').exists()
        finally:
            node.destroy_node()
        assert (bag / 'metadata.yaml').exists()  # the new, empty recording, closed
    finally:
        rclpy.try_shutdown(context=ctx)


# --- real signals to real processes, timed (slow) ---------------------------------------------

#: ``GYRO_NOISE_STOP_TIMES=FILE`` appends one JSON line per stop measured below (the table of
#: docs/bad_input.md is made from them by docs/scripts/bad_input_table.py).
STOP_TIMES = os.environ.get('GYRO_NOISE_STOP_TIMES')
#: Longest stop accepted here: a hang detector on a loaded machine, not the 2 s target, whose
#: measurements (with the load) are in docs/bad_input.md.
STOP_LIMIT_S = 15.0


def _default_signals():
    """Give the child default SIGINT/SIGTERM (a shell's background job starts with SIGINT off)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def stop_when_ready(argv, ready, sig, *, cwd, env=None, what):
    """
    Start ``python -m argv`` and send ``sig`` once it is ready; time the stop.

    Ready: stderr holds ``ready`` (a str), the file ``ready`` (a Path) is not empty, ``ready()``
    is true (a callable), or ``ready`` seconds passed (a float). Returns (exit code, stderr,
    seconds from the signal to the exit).
    """
    proc = subprocess.Popen([sys.executable, '-m', *argv], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, cwd=cwd, env=env,
                            preexec_fn=_default_signals)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, '')),
                              daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + (ready if isinstance(ready, float) else 180.0)
        while time.monotonic() < deadline:
            if isinstance(ready, str) and any(ready in ln for ln in lines):
                break
            if isinstance(ready, Path) and ready.exists() and ready.stat().st_size:
                break
            if callable(ready) and ready():
                break
            assert proc.poll() is None, f'{what} ended before the signal: ' + ''.join(lines)
            time.sleep(0.05)
        else:
            assert isinstance(ready, float), f'{what}: no {ready!r} in ' + ''.join(lines)
        t0 = time.monotonic()
        proc.send_signal(sig)
        proc.wait(timeout=120)
        seconds = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    reader.join(10)
    if STOP_TIMES:
        with open(STOP_TIMES, 'a') as fh:
            fh.write(json.dumps({'what': what, 'signal': signal.Signals(sig).name,
                                 'code': proc.returncode, 'seconds': round(seconds, 3),
                                 'load': os.getloadavg()[0]}) + '\n')
    return proc.returncode, ''.join(lines), seconds


def check_stopped(prog, code, err, seconds, sig):
    assert code == 128 + sig, err
    check_stderr(prog, err, code, '')
    assert seconds < STOP_LIMIT_S, f'{prog} took {seconds:.1f} s to stop'


@pytest.fixture(scope='module')
def long_inputs(tmp_path_factory, make_record):
    """Write inputs whose processing takes long enough to be interrupted half-way."""
    from gyro_noise_ros.cli import emulator

    d = tmp_path_factory.mktemp('long_inputs')
    make_record(d / 'long_bag', _gyro(400_000, 9), rate_hz=RATE_HZ)
    assert emulator.main(['--write-sd', str(d / 'sd'), '--samples', '3000000']) == 0
    return d


# slow: tools in subprocesses interrupted half-way by a real signal (5-20 s each)
@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
@pytest.mark.parametrize('tool', ['analyze', 'explain', 'import', 'write-bag', 'write-sd',
                                  'serve', 'simulate', 'repair', 'while-importing'])
def test_a_real_signal_stops_a_tool_leaving_nothing(tool, sig, inputs, long_inputs, tmp_path):
    out = tmp_path / 'out'
    runs = {
        'analyze': (PROGS['gyro_noise_analyze'], [str(long_inputs / 'long_bag'), *FAST[:6],
                                                  '--jobs', '2', '--batch-size', '2000',
                                                  '--out', str(out)], '10%'),
        'explain': (PROGS['gyro_noise_explain'], [str(inputs / 'ok.csv'), '--out', str(out)],
                    'axis x'),
        # ready once the bag's storage file is being written in its stage
        'import': (PROGS['gyro_noise_import'], [*map(str, sorted(
            (long_inputs / 'sd').glob('*.GNL'))), '--out', str(out)],
                   lambda: any(tmp_path.glob('.out.partial-*/out/*'))),
        'write-bag': (PROGS['portenta_emulator'], ['--write-bag', str(out), '--duration-s',
                                                   '300'], 2.0),
        'write-sd': (PROGS['portenta_emulator'], ['--write-sd', str(out), '--samples',
                                                  '40000000'], 2.0),
        # ready once it samples: the truth of every sample is appended while it serves
        'serve': (PROGS['portenta_emulator'], ['--tcp', '127.0.0.1:0', '--stats-out',
                                               str(tmp_path / 'stats.json'), '--truth-out',
                                               str(tmp_path / 'truth.bin')],
                  tmp_path / 'truth.bin'),
        # ready once its stage exists (a fixed delay met it still importing under load)
        'simulate': (PROGS['gyro_noise_thermal'], ['simulate', '--hours', '3', '--out',
                                                   str(out)],
                     lambda: any(tmp_path.glob('out/.partial-*'))),
        'repair': ('gyro_noise_ros.cli.record', ['repair', str(long_inputs / 'long_bag'),
                                                 '--out', str(out)],
                   lambda: any(tmp_path.glob('.out.partial-*/out/*'))),
        # 0.8 s: past the interpreter's start (a signal before the package's first import ends
        # Python by its default action), numpy, numba and rosbags still being imported
        'while-importing': (PROGS['portenta_emulator'], ['--write-bag', str(out),
                                                         '--duration-s', '300'], 0.8),
    }
    module, argv, ready = runs[tool]
    prog = next(p for p, m in PROGS.items() if m == module)
    prog = 'gyro_noise_record repair' if tool == 'repair' else prog
    code, err, seconds = stop_when_ready([module, *argv], ready, sig, cwd=tmp_path,
                                         what=f'{prog} ({tool})')
    check_stopped(prog, code, err, seconds, sig)
    left = sorted(p.name for p in tmp_path.iterdir())
    # no result, no stage; the board served: its statistics and truth are written
    assert left == (['stats.json', 'truth.bin'] if tool == 'serve' else []), left


# slow: a real kill -9 half-way through an import, then the retry (15 s)
@pytest.mark.slow
@pytest.mark.timeout(600)
def test_a_killed_import_leaves_a_stage_that_the_retry_removes(long_inputs, tmp_path):
    logs = [*map(str, sorted((long_inputs / 'sd').glob('*.GNL')))]
    out = tmp_path / 'bag'
    proc = subprocess.Popen([sys.executable, '-m', PROGS['gyro_noise_import'], *logs, '--out',
                             str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not list(tmp_path.glob('.bag.partial-*/bag/*')) and time.monotonic() < deadline:
            assert proc.poll() is None
            time.sleep(0.05)
        time.sleep(0.3)  # half-way through writing
    finally:
        proc.kill()
        proc.wait()
    stages = [p.name for p in tmp_path.iterdir()]
    assert not out.exists() and len(stages) == 1 and stages[0].startswith('.bag.partial-'), stages
    done = subprocess.run([sys.executable, '-m', PROGS['gyro_noise_import'], *logs, '--out',
                           str(out)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert [p.name for p in tmp_path.iterdir()] == ['bag']


_NODE_READY = {'lsm6dso32_driver': 'retrying', 'noise_analyzer': 'analysing',
               'imu_compensator': 'compensating', 'gyro_noise_record': 'recording',
               'gyro_noise_monitor': 2.0, 'imu_chain': 'retrying'}


# slow: every node started for real and stopped by a real signal (3-8 s each)
@pytest.mark.slow
@pytest.mark.ros
@pytest.mark.timeout(600)
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
@pytest.mark.parametrize('node', NODES)
def test_a_real_signal_stops_every_node(node, sig, ros_graph, tmp_path):
    args = {'lsm6dso32_driver': ['-p', 'port:=socket://127.0.0.1:9'],
            'imu_chain': ['-p', 'port:=socket://127.0.0.1:9'],
            'gyro_noise_record': ['-p', f'output:={tmp_path / "bag"}']}.get(node, [])
    code, err, seconds = stop_when_ready([PROGS[node], '--ros-args', *args], _NODE_READY[node],
                                         sig, cwd=tmp_path, env=ros_graph.env(), what=node)
    check_stopped(node, code, err, seconds, sig)


@pytest.mark.ros
def test_rclpy_own_parameters_are_not_unknown(tmp_path):
    import rclpy
    from rclpy.parameter import Parameter

    from gyro_noise_ros.errors import ParameterError
    from gyro_noise_ros.nodes.recorder import RecorderNode

    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        own = [Parameter('use_sim_time', value=True),
               Parameter('start_type_description_service', value=False)]
        node = RecorderNode(context=ctx, parameter_overrides=[
            Parameter('output', value=str(tmp_path / 'bag')), *own])
        node.destroy_node()
        with pytest.raises(ParameterError, match=r"unknown parameter 'outptu' \(did you mean "
                                                 r"'output'\?\)"):
            RecorderNode(context=ctx, parameter_overrides=[
                Parameter('outptu', value=str(tmp_path / 'bag')), *own])
    finally:
        rclpy.try_shutdown(context=ctx)


def test_a_stop_raised_where_python_drops_it_is_delivered_again(capsys):
    import ctypes

    from gyro_noise_ros.cli._common import run_cli

    libc = ctypes.CDLL(None)
    compare = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_int),
                               ctypes.POINTER(ctypes.c_int))
    sent = []

    def in_c_callback(a, b):
        # the handler's exception is raised inside a ctypes callback: Python prints it as
        # "Exception ignored" and the C caller goes on (llvmlite's object-cache hook while numba
        # compiles did exactly this; the run then ended with exit 0)
        if not sent:
            sent.append(True)
            os.kill(os.getpid(), signal.SIGTERM)
        return a[0] - b[0]

    def body(argv):
        values = (ctypes.c_int * 8)(*range(8, 0, -1))
        libc.qsort(values, len(values), ctypes.sizeof(ctypes.c_int), compare(in_c_callback))
        assert sent  # the signal went off inside the callback, and was dropped there
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:  # the work goes on: the stop must come again
            time.sleep(0.01)
        return 0

    assert run_cli('tool', body, []) == 143
    err = capsys.readouterr().err
    assert err == 'tool: interrupted (SIGTERM)\n', err
