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

"""Staged outputs: finished or visibly unfinished, never half-written under the final names."""

import os
import subprocess
import sys

from gyro_noise_ros.errors import OutputError
from gyro_noise_ros.outputs import (
    atomic_write_text, check_out_dir, make_out_dir, PARTIAL_PREFIX, staged_new_dir,
    staged_output)
import pytest


def test_staged_output_publishes_on_success_and_keeps_other_files(tmp_path):
    out = tmp_path / 'out'
    out.mkdir()
    (out / 'mine.txt').write_text('user file')
    (out / 'old.json').write_text('old')
    with staged_output(out) as stage:
        (stage / 'old.json').write_text('new')
        (stage / 'figs').mkdir()
        (stage / 'figs' / 'a.png').write_bytes(b'x')
        assert not (out / 'figs').exists()
    assert (out / 'old.json').read_text() == 'new'
    assert (out / 'mine.txt').read_text() == 'user file'
    assert (out / 'figs' / 'a.png').read_bytes() == b'x'
    assert not list(out.glob(PARTIAL_PREFIX + '*'))


def test_staged_output_replaces_a_folder_of_a_previous_run(tmp_path):
    out = tmp_path / 'out'
    for text in ('first', 'second'):
        with staged_output(out) as stage:
            (stage / 'axis_x').mkdir()
            (stage / 'axis_x' / 'r.md').write_text(text)
    assert (out / 'axis_x' / 'r.md').read_text() == 'second'
    assert sorted(p.name for p in out.iterdir()) == ['axis_x']


def test_staged_output_leaves_nothing_on_error(tmp_path):
    out = tmp_path / 'out'
    with pytest.raises(KeyboardInterrupt):
        with staged_output(out) as stage:
            (stage / 'summary.json').write_text('{}')
            raise KeyboardInterrupt
    assert not out.exists()  # the folder the run created went with it
    out.mkdir()
    with pytest.raises(KeyboardInterrupt):
        with staged_output(out) as stage:
            raise KeyboardInterrupt
    assert list(out.iterdir()) == []  # the user's folder stays


def test_a_killed_run_leaves_a_hidden_partial_that_the_next_run_removes(tmp_path):
    out = tmp_path / 'out'
    code = ('import os, sys\n'
            'from gyro_noise_ros.outputs import staged_output\n'
            'with staged_output(sys.argv[1]) as stage:\n'
            '    (stage / "summary.json").write_text("{}")\n'
            '    os._exit(9)\n')
    proc = subprocess.run([sys.executable, '-c', code, str(out)], timeout=60)
    assert proc.returncode == 9
    left = list(out.iterdir())
    assert len(left) == 1 and left[0].name.startswith(PARTIAL_PREFIX)
    assert not (out / 'summary.json').exists()
    with staged_output(out) as stage:
        (stage / 'summary.json').write_text('{}')
    assert [p.name for p in out.iterdir()] == ['summary.json']


def test_out_errors_are_output_errors(tmp_path):
    afile = tmp_path / 'afile'
    afile.write_text('x')
    with pytest.raises(OutputError, match='existing file'):
        make_out_dir(afile)
    with pytest.raises(OutputError, match='cannot be created'):
        make_out_dir(afile / 'sub')
    assert OutputError('x').exit_code == 6


@pytest.mark.skipif(os.geteuid() == 0, reason='root writes into read-only folders')
def test_unwritable_out_is_refused(tmp_path):
    out = tmp_path / 'ro'
    out.mkdir()
    out.chmod(0o500)
    try:
        with pytest.raises(OutputError, match='not writable'):
            with staged_output(out):
                pass
    finally:
        out.chmod(0o700)


def test_unwritable_out_is_refused_as_root_too(tmp_path, monkeypatch):
    # as root os.access says yes; the refusal must then come from the failed mkdir
    out = tmp_path / 'ro'
    out.mkdir()
    real_mkdir = type(out).mkdir

    def failing_mkdir(self, *args, **kwargs):
        if self.parent == out:
            raise PermissionError(13, 'Permission denied')
        return real_mkdir(self, *args, **kwargs)

    real_open = os.open

    def failing_open(path, flags, *args, **kwargs):
        if os.fspath(path) == os.fspath(out) and flags & getattr(os, 'O_TMPFILE', 0):
            raise PermissionError(13, 'Permission denied')
        return real_open(path, flags, *args, **kwargs)

    for tmpfile in (True, False):  # the unnamed-file probe, and the folder one where it lacks
        with monkeypatch.context() as m:
            m.setattr(type(out), 'mkdir', failing_mkdir)
            m.setattr(os, 'open', failing_open)
            if not tmpfile:
                m.delattr(os, 'O_TMPFILE', raising=False)
            with pytest.raises(OutputError, match='not writable: Permission denied'):
                with staged_output(out):
                    pass


@pytest.mark.parametrize('tmpfile', [True, False])
def test_the_write_probe_leaves_nothing_when_a_signal_stops_it(tmp_path, monkeypatch, tmpfile):
    # a SIGTERM between creating the probe and removing it left '.gyro_noise_probe-*' behind
    real_close, real_mkdir = os.close, type(tmp_path).mkdir

    def interrupted(real):
        def call(*args, **kwargs):
            real(*args, **kwargs)
            raise KeyboardInterrupt  # what the tools' signal handlers raise, once it is made
        return call

    if tmpfile:
        monkeypatch.setattr(os, 'close', interrupted(real_close))
    else:
        monkeypatch.delattr(os, 'O_TMPFILE', raising=False)
        monkeypatch.setattr(type(tmp_path), 'mkdir', interrupted(real_mkdir))
    with pytest.raises(KeyboardInterrupt):
        check_out_dir(tmp_path / 'out')
    monkeypatch.undo()
    assert os.listdir(tmp_path) == []


def test_staged_new_dir_renames_on_success_and_refuses_existing(tmp_path):
    bag = tmp_path / 'run1'
    with staged_new_dir(bag) as stage:
        # the stage has the final name (rosbags names storage files after it), in a hidden holder
        assert not stage.exists() and stage.name == 'run1'
        assert stage.parent.name.startswith('.run1.partial-')
        stage.mkdir()
        (stage / 'metadata.yaml').write_text('m')
    assert (bag / 'metadata.yaml').read_text() == 'm'
    assert [p.name for p in tmp_path.iterdir()] == ['run1']
    with pytest.raises(OutputError, match='already exists'):
        with staged_new_dir(bag):
            pass


def test_staged_new_dir_removes_its_stage_on_error(tmp_path):
    bag = tmp_path / 'run2'
    with pytest.raises(RuntimeError):
        with staged_new_dir(bag) as stage:
            stage.mkdir()
            raise RuntimeError('writer failed')
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_text(tmp_path):
    target = tmp_path / 'model.json'
    atomic_write_text(target, 'a')
    atomic_write_text(target, 'b')
    assert target.read_text() == 'b'
    assert [p.name for p in tmp_path.iterdir()] == ['model.json']
    with pytest.raises(OutputError, match='cannot write'):
        atomic_write_text(tmp_path / 'missing' / 'x.json', 'c')
