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
``make demo`` in its short mode.

The whole chain runs, the drift is detected, the report is written, and every subprocess is gone
afterwards, also after a Ctrl-C in the middle. The demo leases its own private graph
(:func:`gyro_noise_ros.rosgraph.lease_domain`, the function ``ros_graph`` in ``conftest.py`` uses):
the domain it prints is free, not the one this test holds, and its processes are found by it.
"""

import json
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading
import time

from _html_report import check_in_browser, check_static
import pytest

pytestmark = pytest.mark.ros


def _printed_domain(stdout, held):
    """Return the ROS_DOMAIN_ID the demo printed first; check it is private and not ``held``."""
    found = re.search(r'ROS_DOMAIN_ID=(\d+) \(localhost only\)', stdout)
    assert found, stdout[:2000]
    domain = int(found.group(1))
    # The test holds its own domain's lock: the demo's lease must have skipped it.
    assert 1 <= domain <= 101 and domain != held
    return domain


def _our_processes(domain_id):
    """Return the PIDs of live processes whose environment has our private ROS_DOMAIN_ID."""
    needle = f'ROS_DOMAIN_ID={domain_id}'.encode() + b'\x00'
    found = []
    for proc in Path('/proc').iterdir():
        if not proc.name.isdigit():
            continue
        try:
            env = (proc / 'environ').read_bytes()
            state = (proc / 'stat').read_text().split(') ', 1)[1][0]
        except OSError:
            continue
        if needle in env + b'\x00' and state != 'Z':
            found.append(int(proc.name))
    return found


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_quick_demo_runs_the_story_and_writes_the_report(tmp_path, ros_graph):
    out = tmp_path / 'demo'
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.demo', '--quick', '--out',
                           str(out)], capture_output=True, text=True, timeout=560)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    domain = _printed_domain(done.stdout, ros_graph.domain_id)
    assert 'story checked' in done.stdout
    assert any(line.strip().split('] ', 1)[-1].startswith('WARN')
               for line in done.stdout.splitlines())
    report = out / 'report'
    for name in ('report.html', 'summary.md', 'summary.json', 'chunks.csv', 'allan.csv',
                 'imu.yaml', 'bias.png', 'allan.png'):
        assert (report / name).is_file(), name
        assert str(report / name) in done.stdout  # the demo ends by saying where they are
    # the one page to open: the summary's numbers, under 5 MB, drawn in a browser
    assert (report / 'report.html').stat().st_size <= 5 * 1024 * 1024
    check_static(report / 'report.html', json.loads((report / 'summary.json').read_text()))
    # five figures: the Allan deviation of the gyro and of the accelerometer, bias, variance,
    # orders; the verdict line and the datasheet card on the first 1280x800 screen
    check_in_browser(report / 'report.html', tmp_path, figures=5)
    assert (out / 'recording' / 'metadata.yaml').is_file()
    assert 'finished: the report is complete' in (out / 'GYRO_NOISE_DEMO.txt').read_text()
    assert _our_processes(domain) == []


# slow: the live chain of the demo in real time until its first chunk (20-30 s)
def _sigint_default():
    """Give the child the default SIGINT (a shell's background job starts with it ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_ctrl_c_stops_every_process_and_keeps_the_recording(tmp_path, ros_graph):
    out = tmp_path / 'demo'
    proc = subprocess.Popen([sys.executable, '-m', 'gyro_noise_ros.cli.demo', '--quick', '--out',
                             str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_sigint_default)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stdout.readline, '')),
                              daemon=True)
    reader.start()
    try:
        # Interrupt in the live part: every process runs and the bag is being written.
        deadline = time.monotonic() + 150
        while time.monotonic() < deadline and not any('] ' in ln and ' chunk ' in ln
                                                      for ln in lines):
            assert proc.poll() is None, ''.join(lines) + proc.stderr.read()
            time.sleep(0.2)
        domain = _printed_domain(''.join(lines), ros_graph.domain_id)
        assert len(_our_processes(domain)) == 5, ''.join(lines)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, err
    assert 'interrupted' in err and 'Traceback' not in err
    deadline = time.monotonic() + 10
    while _our_processes(domain) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert _our_processes(domain) == []
    # The recorder was stopped with SIGINT, so the bag was closed properly.
    assert (out / 'recording' / 'metadata.yaml').is_file()
    # ... but the demo output is not a finished one, and says so
    assert 'NOT FINISHED' in (out / 'GYRO_NOISE_DEMO.txt').read_text()
    assert not (out / 'report').exists()


def test_refuses_an_output_that_is_not_a_demo_output(tmp_path):
    (tmp_path / 'precious.txt').write_text('keep me')
    done = subprocess.run([sys.executable, '-m', 'gyro_noise_ros.cli.demo', '--out',
                           str(tmp_path)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 6  # an output problem (README exit codes)
    assert done.stderr.strip().startswith(
        'gyro_noise_demo: error:') and 'not a previous demo' in done.stderr
    assert (tmp_path / 'precious.txt').read_text() == 'keep me'


def test_a_failing_component_is_named_with_its_log(tmp_path, ros_graph):
    from gyro_noise_ros.app.demo import DemoError, Processes

    procs = Processes(ros_graph.env(), tmp_path)
    procs.start('gyro_noise_record', ['gyro_noise_ros.nodes.recorder', '--ros-args', '-p',
                                      'storage:=zip'])
    try:
        with pytest.raises(
                DemoError,
                match=r'gyro_noise_record exited with code 2; log .*gyro_noise_record.log: '
                r".*parameter 'storage'"):
            procs.wait_for_log('gyro_noise_record', r'recording ', 60, 'start-up')
    finally:
        procs.stop_all([])
