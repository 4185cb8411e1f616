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
A private ROS 2 graph on one host: a ``ROS_DOMAIN_ID`` nobody uses, held, and localhost discovery.

What the tests, the demo and the soak bench start must neither hear another robot's graph nor
publish into it. Two things keep them apart:

- **A domain checked free and held.** RTPS maps domain d onto the 250 UDP ports from
  ``7400 + 250 d`` (DDS-RTPS 2.2 section 9.6.1.1; participant p listens on ``7410 + 250 d + 2 p``
  and the next port). A domain is in use when any UDP socket of this host (``/proc/net/udp`` and
  ``udp6``) is bound inside its block; where ``/proc`` cannot be read, binding the first
  participant's two unicast ports decides. A free domain is held with an exclusive ``fcntl.flock``
  on ``<lock dir>/domain_<d>.lock`` (released by the kernel when the holder dies).
- **Localhost-only discovery.** ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (Jazzy); what would
  add peers or replace the discovery (``ROS_LOCALHOST_ONLY``, ``ROS_STATIC_PEERS``,
  ``ROS_DISCOVERY_SERVER``, a Fast DDS XML profile) is removed from the environment.

Candidate domains are 1..101: never 0 (the one a robot uses unless told otherwise), and only those
whose ports for :data:`MAX_PARTICIPANTS` participants stay below the Linux ephemeral port range
(``/proc/sys/net/ipv4/ip_local_port_range``). Why each rule, and the measurements: docs/testing.md.

No ROS is imported here: the tests, ``cli/demo.py`` and ``bench/`` call it before any rclpy.
"""

from collections.abc import Callable, Iterable, Mapping, MutableMapping, Sequence
import errno
import fcntl
import os
from pathlib import Path
import socket
import tempfile

from .errors import GyroNoiseError

#: RTPS port mapping (DDS-RTPS 2.2 section 9.6.1.1): base, domain gain, participant gain.
PORT_BASE, DOMAIN_GAIN, PARTICIPANT_GAIN = 7400, 250, 2
#: Offset of a participant's discovery (metatraffic) unicast port; the user unicast is one above.
DISCOVERY_UNICAST_OFFSET = 10

#: Domain IDs considered, before the ephemeral-range check (ROS 2 docs: 0-101 are safe on Linux).
DOMAIN_IDS = tuple(range(1, 102))

#: Participants per domain whose unicast ports must stay below the ephemeral range (a test graph
#: has fewer than ten processes; domain 101 leaves room for 53).
MAX_PARTICIPANTS = 50

#: Linux default of ``ip_local_port_range`` when it cannot be read.
DEFAULT_EPHEMERAL_LOW = 32768

#: Environment variables removed from a private graph's environment (see the module docstring).
UNSET_VARIABLES = ('ROS_LOCALHOST_ONLY', 'ROS_STATIC_PEERS', 'ROS_DISCOVERY_SERVER',
                   'ROS_SUPER_CLIENT', 'FASTRTPS_DEFAULT_PROFILES_FILE',
                   'FASTDDS_DEFAULT_PROFILES_FILE', 'RMW_FASTRTPS_USE_QOS_FROM_XML',
                   'CYCLONEDDS_URI')

_PROC_NET_UDP = ('/proc/net/udp', '/proc/net/udp6')


class DomainUnavailableError(GyroNoiseError):
    """No ROS domain in the candidate range is free on this host (all bound or held)."""


def domain_ports(domain_id: int) -> range:
    """
    Return the block of UDP ports RTPS assigns to a domain.

    Parameters
    ----------
    domain_id : int
        ROS domain ID.

    Returns
    -------
    range
        ``range(7400 + 250 d, 7650 + 250 d)``.

    """
    start = PORT_BASE + DOMAIN_GAIN * int(domain_id)
    return range(start, start + DOMAIN_GAIN)


def participant_ports(domain_id: int, participant_id: int) -> tuple[int, int]:
    """Return the discovery and user unicast ports of one participant of a domain."""
    port = (PORT_BASE + DOMAIN_GAIN * int(domain_id) + DISCOVERY_UNICAST_OFFSET
            + PARTICIPANT_GAIN * int(participant_id))
    return port, port + 1


def ephemeral_low(path: str | os.PathLike[str] = '/proc/sys/net/ipv4/ip_local_port_range'
                  ) -> int:
    """Return the first port of the Linux ephemeral range (32768 when it cannot be read)."""
    try:
        return int(Path(path).read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return DEFAULT_EPHEMERAL_LOW


def candidate_domains(low: int | None = None) -> list[int]:
    """
    Return the domain IDs a private graph may use, in increasing order.

    Parameters
    ----------
    low : int or None
        First ephemeral port; None: :func:`ephemeral_low`.

    Returns
    -------
    list of int
        IDs of :data:`DOMAIN_IDS` whose user unicast port of participant
        ``MAX_PARTICIPANTS`` is below ``low``.

    """
    low = ephemeral_low() if low is None else int(low)
    return [d for d in DOMAIN_IDS if participant_ports(d, MAX_PARTICIPANTS)[1] < low]


def udp_ports_in_use(paths: Iterable[str] = _PROC_NET_UDP) -> set[int] | None:
    """
    Return the local ports of every UDP socket of this network namespace.

    Parameters
    ----------
    paths : sequence of str
        The kernel's socket tables (``/proc/net/udp``, ``/proc/net/udp6``).

    Returns
    -------
    set of int or None
        Bound ports; None when no table can be read (not Linux).

    """
    ports: set[int] = set()
    read_any = False
    for path in paths:
        try:
            lines = Path(path).read_text().splitlines()[1:]
        except OSError:
            continue
        read_any = True
        for line in lines:
            fields = line.split()
            if len(fields) > 1 and ':' in fields[1]:
                ports.add(int(fields[1].rsplit(':', 1)[1], 16))
    return ports if read_any else None


def _bind_probe(port: int) -> bool:
    """Return True when a UDP socket can bind ``port`` on every interface right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(('', port))
        except OSError:
            return False
    return True


def domain_in_use(domain_id: int, ports: set[int] | None = None) -> bool:
    """
    Tell whether any process of this host has a socket in the domain's port block.

    Parameters
    ----------
    domain_id : int
        ROS domain ID.
    ports : set of int or None
        Bound UDP ports (:func:`udp_ports_in_use`); None: read them now.

    Returns
    -------
    bool

    """
    ports = udp_ports_in_use() if ports is None else ports
    if ports is not None:
        block = domain_ports(domain_id)
        return any(p in ports for p in block)
    # No socket table: a first participant in the domain would hold these two ports.
    return not all(_bind_probe(p) for p in participant_ports(domain_id, 0))


def default_lock_dir() -> Path:
    """Return the directory of the domain lock files (shared by every user of the host)."""
    return Path(tempfile.gettempdir()) / 'gyro_noise_ros_domains'


def _open_lock(lock_dir: Path, domain_id: int) -> int:
    lock_dir.mkdir(mode=0o777, parents=True, exist_ok=True)
    try:
        # Sticky and world-writable like /tmp, so every user of the host shares the locks.
        os.chmod(lock_dir, 0o1777)
    except OSError:
        pass  # created by another user: theirs to set
    path = lock_dir / f'domain_{domain_id}.lock'
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            os.fchmod(fd, 0o666)
        except OSError:
            pass
    except PermissionError:
        fd = os.open(path, os.O_RDONLY)  # flock needs no write access
    return fd


def isolated_env(domain_id: int, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """
    Return the environment of a process in a private graph.

    Parameters
    ----------
    domain_id : int
        ROS domain ID (from :func:`lease_domain`).
    base : mapping or None
        Environment to start from; None: ``os.environ``.

    Returns
    -------
    dict
        ``base`` with ``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and
        without :data:`UNSET_VARIABLES`.

    """
    env = dict(os.environ if base is None else base)
    for name in UNSET_VARIABLES:
        env.pop(name, None)
    env['ROS_DOMAIN_ID'] = str(int(domain_id))
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    return env


class DomainLease:
    """
    A domain ID held by this process (exclusive file lock) until :meth:`release`.

    Use it as a context manager. Obtained from :func:`lease_domain`.

    Attributes
    ----------
    domain_id : int
        The domain held.
    lock_path : pathlib.Path
        Its lock file.

    """

    def __init__(self, domain_id: int, fd: int, lock_path: Path) -> None:
        self.domain_id = int(domain_id)
        self.lock_path = lock_path
        self._fd: int | None = fd

    @property
    def held(self) -> bool:
        """bool: The lock is still held."""
        return self._fd is not None

    def env(self, base: Mapping[str, str] | None = None) -> dict[str, str]:
        """Return :func:`isolated_env` for this domain."""
        return isolated_env(self.domain_id, base)

    def export(self, environ: MutableMapping[str, str] | None = None) -> None:
        """Make ``environ`` (default ``os.environ``) this graph's environment, in place."""
        environ = os.environ if environ is None else environ
        for name in UNSET_VARIABLES:
            environ.pop(name, None)
        environ.update(self.env(environ))

    def release(self) -> None:
        """Release the lock (idempotent)."""
        if self._fd is not None:
            try:
                fcntl.flock(self._fd, fcntl.LOCK_UN)
            finally:
                os.close(self._fd)
                self._fd = None

    def __enter__(self) -> 'DomainLease':
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def __repr__(self) -> str:
        return f'DomainLease(domain_id={self.domain_id}, held={self.held})'


_next_start = [os.getpid()]


def lease_domain(*, candidates: Sequence[int] | None = None,
                 lock_dir: str | os.PathLike[str] | None = None,
                 in_use: Callable[[int], bool] | None = None) -> DomainLease:
    """
    Find a domain nobody on this host uses and hold it.

    The candidates are tried round-robin from where the previous lease of this process stopped
    (so consecutive tests of one run take different domains, and a straggling process of one test
    cannot reach the next); the first whose lock can be taken and whose ports are free is held.

    Parameters
    ----------
    candidates : sequence of int or None, keyword-only
        Domain IDs to try; None: :func:`candidate_domains`.
    lock_dir : path-like or None, keyword-only
        Directory of the lock files; None: :func:`default_lock_dir`.
    in_use : callable or None, keyword-only
        ``in_use(domain_id) -> bool``; None: :func:`domain_in_use` on one read of the socket
        tables.

    Returns
    -------
    DomainLease

    Raises
    ------
    DomainUnavailableError
        Every candidate is bound or held.

    """
    candidates = list(candidate_domains() if candidates is None else candidates)
    if not candidates:
        raise DomainUnavailableError('no ROS domain ID is available below the ephemeral port '
                                     f'range (first port {ephemeral_low()})')
    lock_dir = default_lock_dir() if lock_dir is None else Path(lock_dir)
    if in_use is None:
        ports = udp_ports_in_use()

        def in_use(domain_id: int) -> bool:
            return domain_in_use(domain_id, ports)

    start = _next_start[0] % len(candidates)
    busy = held = 0
    for k in range(len(candidates)):
        domain_id = candidates[(start + k) % len(candidates)]
        fd = _open_lock(lock_dir, domain_id)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            held += 1
            continue
        # Checked after the lock is taken: a holder that found it free may have started since.
        if in_use(domain_id):
            fcntl.flock(fd, fcntl.LOCK_UN)
            os.close(fd)
            busy += 1
            continue
        _next_start[0] = start + k + 1
        return DomainLease(domain_id, fd, lock_dir / f'domain_{domain_id}.lock')
    raise DomainUnavailableError(
        f'no free ROS domain ID among {candidates[0]}..{candidates[-1]}: {busy} have sockets '
        f'bound on this host, {held} are held by other runs (locks in {lock_dir})')
