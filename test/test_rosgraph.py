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
The private graph of the tests (``gyro_noise_ros.rosgraph``, ``ros_graph`` in ``conftest.py``).

Pure part: the RTPS port blocks, the candidate domains (1..101, never 0, below the ephemeral
range), a bound socket or a held lock makes a domain unavailable, the environment.

ROS part, for real: the fixture's participants do not listen for multicast discovery (the PyPI
rmw_fastrtps honours ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), and a subscriber in the
fixture's graph hears a publisher inside it but neither a publisher of another domain nor one that
can only be reached over the network (a Fast DDS participant restricted to this host's LAN
address, what a robot next door looks like), while a default (subnet) subscriber does hear that
one: the control that shows the test can fail.
"""

import errno
import fcntl
import os
import socket
import subprocess
import sys
import textwrap
import time

from gyro_noise_ros import rosgraph
import pytest


# ---- pure -------------------------------------------------------------------------------------

def test_port_blocks_follow_the_rtps_mapping():
    # DDS-RTPS 2.2 9.6.1.1 with the default PB 7400, DG 250, PG 2, d1 10, d3 11.
    assert rosgraph.domain_ports(0) == range(7400, 7650)
    assert rosgraph.domain_ports(57) == range(21650, 21900)
    assert rosgraph.participant_ports(57, 0) == (21660, 21661)
    assert rosgraph.participant_ports(57, 3) == (21666, 21667)


def test_candidates_are_1_to_101_below_the_ephemeral_range():
    assert rosgraph.candidate_domains(32768) == list(range(1, 102))
    # Domain 101's participant 50 uses port 32761 (user unicast): the last one that fits.
    assert rosgraph.participant_ports(101, rosgraph.MAX_PARTICIPANTS)[1] == 32761
    # A host whose ephemeral range starts lower loses the top domains, never gains domain 0.
    low = rosgraph.candidate_domains(20000)
    assert low == list(range(1, low[-1] + 1))
    assert rosgraph.participant_ports(low[-1], 50)[1] < 20000 <= rosgraph.participant_ports(
        low[-1] + 1, 50)[1]
    assert rosgraph.candidate_domains(7000) == []


def test_socket_table_parsing(tmp_path):
    table = tmp_path / 'udp'
    table.write_text(
        '  sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  ...\n'
        ' 1: 00000000:549C 00000000:0000 07 00000000:00000000 00:00000000 00000000  1000 0\n'
        ' 2: 0100007F:1D4C 00000000:0000 07 00000000:00000000 00:00000000 00000000  1000 0\n')
    assert rosgraph.udp_ports_in_use([str(table)]) == {0x549C, 0x1D4C}
    assert rosgraph.udp_ports_in_use([str(tmp_path / 'missing')]) is None
    # 0x549C = 21660: domain 57's first participant; 0x1D4C = 7500: domain 0.
    assert rosgraph.domain_in_use(57, {0x549C, 0x1D4C})
    assert rosgraph.domain_in_use(0, {0x549C, 0x1D4C})
    assert not rosgraph.domain_in_use(58, {0x549C, 0x1D4C})


def _bind_in_block(domain_id):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    # The multicast port of the domain: what a listening participant binds (SO_REUSEADDR).
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind(('', rosgraph.domain_ports(domain_id)[0]))
    return s


def test_a_bound_port_or_a_held_lock_makes_a_domain_unavailable(tmp_path):
    free = [d for d in rosgraph.candidate_domains() if not rosgraph.domain_in_use(d)][:3]
    assert len(free) == 3
    sock = _bind_in_block(free[0])
    try:
        assert rosgraph.domain_in_use(free[0])  # read from the kernel's table
        with rosgraph.lease_domain(candidates=free, lock_dir=tmp_path) as first:
            assert first.domain_id in free[1:] and first.held
            with rosgraph.lease_domain(candidates=free, lock_dir=tmp_path) as second:
                assert second.domain_id in free[1:] and second.domain_id != first.domain_id
                with pytest.raises(rosgraph.DomainUnavailableError,
                                   match='1 have sockets bound on this host, 2 are held'):
                    rosgraph.lease_domain(candidates=free, lock_dir=tmp_path)
        assert not first.held
        # Released: available again.
        with rosgraph.lease_domain(candidates=free[1:2], lock_dir=tmp_path) as again:
            assert again.domain_id == free[1]
    finally:
        sock.close()


def test_a_lock_held_by_another_process_is_honoured(tmp_path):
    free = [d for d in rosgraph.candidate_domains() if not rosgraph.domain_in_use(d)][:1]
    holder = subprocess.Popen(
        [sys.executable, '-c', textwrap.dedent(f"""
            import sys, time
            from gyro_noise_ros import rosgraph
            lease = rosgraph.lease_domain(candidates={free}, lock_dir={str(tmp_path)!r})
            print(lease.domain_id, flush=True)
            sys.stdin.read()
        """)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert int(holder.stdout.readline()) == free[0]
        with pytest.raises(rosgraph.DomainUnavailableError, match='1 are held'):
            rosgraph.lease_domain(candidates=free, lock_dir=tmp_path)
    finally:
        holder.communicate('', timeout=30)
    # The holder exited: the kernel released its lock.
    with rosgraph.lease_domain(candidates=free, lock_dir=tmp_path) as lease:
        assert lease.domain_id == free[0]
    # The lock file is a plain flock: another tool may take it the same way.
    fd = os.open(tmp_path / f'domain_{free[0]}.lock', os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as err:  # pragma: no cover - the lease was released above
        pytest.fail(f'lock still held: {errno.errorcode[err.errno]}')
    finally:
        os.close(fd)


def test_isolated_env_is_localhost_only_without_peers():
    base = {'PATH': '/bin', 'ROS_DOMAIN_ID': '0', 'ROS_LOCALHOST_ONLY': '0',
            'ROS_STATIC_PEERS': '192.168.1.7', 'ROS_DISCOVERY_SERVER': '10.0.0.1:11811',
            'FASTRTPS_DEFAULT_PROFILES_FILE': '/etc/dds.xml',
            'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}
    env = rosgraph.isolated_env(42, base)
    assert env == {'PATH': '/bin', 'ROS_DOMAIN_ID': '42', 'ROS_AUTOMATIC_DISCOVERY_RANGE':
                   'LOCALHOST'}
    assert base['ROS_DOMAIN_ID'] == '0'  # not modified


def test_outside_the_fixture_rclpy_cannot_join_a_graph():
    rclpy = pytest.importorskip('rclpy')
    ctx = rclpy.Context()
    with pytest.raises(Exception, match='ROS_DOMAIN_ID'):
        rclpy.init(context=ctx)
    rclpy.try_shutdown(context=ctx)


# ---- ROS, for real ------------------------------------------------------------------------

_TALKER = textwrap.dedent("""
    import sys, time
    import rclpy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node(sys.argv[1])
    pub = node.create_publisher(String, 'chatter', 10)
    end = time.monotonic() + float(sys.argv[2])
    while time.monotonic() < end:
        pub.publish(String(data=sys.argv[1]))
        time.sleep(0.05)
    rclpy.try_shutdown()
""")

_LISTENER = textwrap.dedent("""
    import sys, time
    import rclpy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node('control_listener')
    heard = set()
    node.create_subscription(String, 'chatter', lambda m: heard.add(m.data), 10)
    end = time.monotonic() + float(sys.argv[1])
    while time.monotonic() < end and sys.argv[2] not in heard:
        rclpy.spin_once(node, timeout_sec=0.1)
    print(' '.join(sorted(heard)), flush=True)
    rclpy.try_shutdown()
""")

_LAN_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <transport_descriptors>
    <transport_descriptor>
      <transport_id>lan_only</transport_id>
      <type>UDPv4</type>
      <interfaceWhiteList><address>{address}</address></interfaceWhiteList>
    </transport_descriptor>
  </transport_descriptors>
  <participant profile_name="lan_peer" is_default_profile="true">
    <rtps>
      <userTransports><transport_id>lan_only</transport_id></userTransports>
      <useBuiltinTransports>false</useBuiltinTransports>
    </rtps>
  </participant>
</profiles>
"""


def _lan_address():
    """Return this host's IPv4 address on its default route, or None."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect(('203.0.113.1', 9))  # TEST-NET-3; connect() on UDP sends nothing
            address = s.getsockname()[0]
        except OSError:
            return None
    return None if address.startswith('127.') else address


def _own_udp_ports():
    """Return the local UDP ports of this process's sockets."""
    inodes = set()
    for fd in os.listdir('/proc/self/fd'):
        try:
            target = os.readlink(f'/proc/self/fd/{fd}')
        except OSError:
            continue
        if target.startswith('socket:['):
            inodes.add(target[8:-1])
    ports = set()
    for path in ('/proc/net/udp', '/proc/net/udp6'):
        for line in open(path).read().splitlines()[1:]:
            fields = line.split()
            if fields[9] in inodes:
                ports.add(int(fields[1].rsplit(':', 1)[1], 16))
    return ports


def _listen(context, until_heard, extra_s, timeout_s=60.0):
    """
    Subscribe ``chatter`` in ``context``; spin until ``until_heard`` is heard, then ``extra_s``.

    Returns the senders heard (each talker publishes its own name) and the local UDP ports of this
    process while its participant lives (rmw_fastrtps destroys it with the last node).
    """
    import rclpy
    from std_msgs.msg import String

    node = rclpy.create_node('fixture_listener', context=context)
    heard = set()
    node.create_subscription(String, 'chatter', lambda m: heard.add(m.data), 10)
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        deadline = time.monotonic() + timeout_s
        while until_heard not in heard and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        assert until_heard in heard, f'{until_heard} (inside the graph) was not heard: {heard}'
        ports = _own_udp_ports()
        end = time.monotonic() + extra_s
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.shutdown()
        node.destroy_node()
    return heard, ports


def _talker(name, env):
    return subprocess.Popen([sys.executable, '-c', _TALKER, name, '60'], env=env)


def _kill(procs):
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.communicate()


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_another_domain_is_not_heard_and_discovery_is_not_multicast(context, ros_graph):
    assert os.environ['ROS_DOMAIN_ID'] == str(ros_graph.domain_id)
    assert 1 <= ros_graph.domain_id <= 101
    assert os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] == 'LOCALHOST'
    assert context.get_domain_id() == ros_graph.domain_id
    procs = []
    try:
        procs.append(_talker('inside', ros_graph.env()))
        with rosgraph.lease_domain() as other:
            # A default (subnet) publisher of another domain on this host.
            procs.append(_talker('other_domain', {
                **os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET',
                'ROS_DOMAIN_ID': str(other.domain_id)}))
            # It runs as long; 5 s after the inside one was heard is several discovery rounds.
            heard, ports = _listen(context, 'inside', 5.0)
    finally:
        _kill(procs)
    assert heard == {'inside'}
    # This process's participant: unicast ports in the domain's block, not the multicast
    # discovery port (LOCALHOST honoured by the rmw; a subnet participant binds it).
    block = rosgraph.domain_ports(ros_graph.domain_id)
    mine = sorted(p for p in ports if p in block)
    assert mine and block[0] not in mine, mine


@pytest.mark.ros
@pytest.mark.timeout(120)
def test_a_peer_reachable_only_over_the_network_is_not_heard(context, ros_graph, tmp_path):
    lan = _lan_address()
    if lan is None:
        pytest.skip('no non-loopback IPv4 address: a network peer cannot be emulated here')
    profile = tmp_path / 'lan_peer.xml'
    profile.write_text(_LAN_PROFILE.format(address=lan))
    subnet = {**os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}
    procs = []
    try:
        procs.append(_talker('inside', ros_graph.env()))
        # Same domain, this host, but its sockets only on the LAN address: as a robot next door
        # is seen (it announces itself by multicast, listens on its LAN address).
        procs.append(_talker('lan_peer', {**subnet, 'FASTRTPS_DEFAULT_PROFILES_FILE':
                                          str(profile)}))
        # The control: a default (subnet) subscriber of the same domain.
        control = subprocess.Popen([sys.executable, '-c', _LISTENER, '40', 'lan_peer'],
                                   env=subnet, stdout=subprocess.PIPE, text=True)
        procs.append(control)
        heard, _ = _listen(context, 'inside', 5.0)
        control_heard = control.communicate(timeout=60)[0].split()
    finally:
        _kill(procs)
    if 'lan_peer' not in control_heard:
        pytest.skip(f'a subnet subscriber did not hear the peer on {lan} either (multicast not '
                    f'looped back on this host?): the test cannot tell; heard {control_heard}')
    assert heard == {'inside'}
