"""
Rosbag reading and writing for gyro_noise_ros, ROS-free (rosbags library only).

Reads rosbag2 recordings (a directory with ``metadata.yaml``, or a bare ``.db3``/``.mcap`` file,
sqlite3 or MCAP storage) and ROS 1 ``.bag`` files; writes rosbag2 (sqlite3 or MCAP). The
``sensor_msgs/msg/Imu`` and ``sensor_msgs/msg/Temperature`` payloads are decoded and encoded in bulk
with numpy instead of one Python object per message: a batch of raw messages is grouped by byte
length, each group is viewed as a 2-D byte array, validated column-wise, and the float block is read
with one ``view``. Any message the bulk path cannot vouch for goes through rosbags' own
deserialiser, so the bulk decoder is an optimisation that can never change a value (the tests check
it against rosbags field by field). See ``docs/bags.md``.

Wire layouts (little-endian shown; XCDR1, alignment relative to the byte after the 4-byte
encapsulation header):

- ROS 2 CDR ``sensor_msgs/Imu``: ``00 01 00 00`` encapsulation, ``int32 sec``, ``uint32 nanosec``,
  ``uint32 L`` (frame_id length including its NUL), ``L`` bytes, zero padding to 8, then 37 float64:
  orientation xyzw, orientation_covariance[9], angular_velocity xyz,
  angular_velocity_covariance[9], linear_acceleration xyz, linear_acceleration_covariance[9].
  So ``len = 4 + align8(12 + L) + 296``. ``00 00`` encapsulation is the big-endian twin.
- ROS 1 ``sensor_msgs/Imu``: ``uint32 seq``, ``uint32 sec``, ``uint32 nsec``, ``uint32 L`` (no NUL),
  ``L`` bytes, the same 37 float64 unaligned: ``len = 16 + L + 296``.
- ``sensor_msgs/Temperature`` has the same header followed by two float64 (temperature, variance).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import BagError, ParameterError

__all__ = [
    'IMU_MSGTYPE',
    'TEMPERATURE_MSGTYPE',
    'TopicInfo',
    'ImuBatch',
    'ImuBagReader',
    'ImuBagWriter',
    'list_topics',
    'find_imu_topic',
    'decode_imu',
    'decode_temperature',
    'encode_imu_cdr',
    'encode_temperature_cdr',
    'count_stamp_regressions',
]

IMU_MSGTYPE = 'sensor_msgs/msg/Imu'
TEMPERATURE_MSGTYPE = 'sensor_msgs/msg/Temperature'

_NS_PER_S = 1_000_000_000
# 37 float64 after the header: orientation 4, 9, angular velocity 3, 9, linear acceleration 3, 9.
_IMU_TAIL_F8 = 37
_TEMPERATURE_TAIL_F8 = 2
_GYRO_COLS = slice(13, 16)
_ACCEL_COLS = slice(25, 28)
_CDR_LE = b'\x00\x01\x00\x00'
_STORAGES = ('sqlite3', 'mcap')

_TYPESTORES = {}


def _typestore(ros1=False):
    """
    Return rosbags' typestore, built once per flavour (it costs ~50 ms).

    ROS 1 messages need the Noetic definitions: their ``std_msgs/Header`` starts with ``uint32 seq``,
    which the ROS 2 definitions lack.
    """
    key = 'ros1' if ros1 else 'ros2'
    if key not in _TYPESTORES:
        from rosbags.typesys import Stores, get_typestore

        _TYPESTORES[key] = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_JAZZY)
    return _TYPESTORES[key]


@dataclass(frozen=True)
class TopicInfo:
    """
    One topic of a bag.

    Attributes
    ----------
    name : str
        Topic name as stored in the bag.
    msgtype : str or None
        ROS 2 style message type (``sensor_msgs/msg/Imu``); ROS 1 types are normalised by rosbags.
        None if connections on the topic disagree.
    count : int
        Number of messages the bag's index or metadata reports for the topic.
    """

    name: str
    msgtype: str | None
    count: int


@dataclass(frozen=True)
class ImuBatch:
    """
    Consecutive ``sensor_msgs/Imu`` messages of one topic, decoded to arrays.

    Attributes
    ----------
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns (``sec * 1e9 + nanosec``), in recorded order (not sorted).
    log_ns : numpy.ndarray of int64, shape (n,)
        Time the recorder received each message, in ns.
    gyro : numpy.ndarray of float64, shape (n, 3)
        ``angular_velocity`` x, y, z in rad/s; NaN stays NaN.
    accel : numpy.ndarray of float64, shape (n, 3)
        ``linear_acceleration`` x, y, z in m/s^2.
    frame_id : str
        ``header.frame_id`` of the batch's first message.
    """

    stamp_ns: np.ndarray
    log_ns: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    frame_id: str

    def __len__(self):
        return int(self.stamp_ns.shape[0])


# ---------------------------------------------------------------------------------------------
# Bulk decoding


def _align8(value):
    return (value + 7) & ~7


def _u32(rows, start, byteorder):
    """Column ``rows[:, start:start + 4]`` of a (n, N) uint8 array as int64 values."""
    return np.ascontiguousarray(rows[:, start:start + 4]).view(byteorder + 'u4')[:, 0].astype(np.int64)


def _decode_group(rows, tail_f8, ros1):
    """
    Decode same-length raw messages whose layout is header + ``tail_f8`` float64.

    Parameters
    ----------
    rows : numpy.ndarray of uint8, shape (n, N)
        One raw message per row, all of byte length N.
    tail_f8 : int
        Number of float64 after the header (37 for Imu, 2 for Temperature).
    ros1 : bool
        ROS 1 serialisation instead of CDR.

    Returns
    -------
    ok : numpy.ndarray of bool, shape (n,)
        Rows whose layout was verified; the other rows must be decoded by the slow path.
    stamp_ns : numpy.ndarray of int64, shape (n,)
    tail : numpy.ndarray of float64, shape (n, tail_f8)
        Undefined where ``ok`` is False.
    """
    n, size = rows.shape
    tail_bytes = 8 * tail_f8
    stamp_ns = np.zeros(n, np.int64)
    tail = np.zeros((n, tail_f8), np.float64)
    ok = np.zeros(n, bool)
    off = size - tail_bytes
    if ros1:
        if off < 16:
            return ok, stamp_ns, tail
        length = _u32(rows, 12, '<')
        ok = 16 + length == off
        if ok.any():
            sec = _u32(rows, 4, '<')
            nsec = _u32(rows, 8, '<')
            stamp_ns = sec * _NS_PER_S + nsec
            tail = np.ascontiguousarray(rows[:, off:]).view('<f8')
        return ok, stamp_ns, tail
    # CDR: the frame_id has at least its NUL, so the float block starts at 4 + 16 at the earliest.
    if off < 20 or (off - 4) % 8:
        return ok, stamp_ns, tail
    for order, second in (('<', 1), ('>', 0)):
        enc = (rows[:, 0] == 0) & (rows[:, 1] == second)
        if not enc.any():
            continue
        length = _u32(rows, 12, order)
        good = enc & (length >= 1) & (4 + _align8(12 + length) == off)
        if not good.any():
            continue
        # The string must end with its NUL where the length says; a mismatch means a different
        # layout (or corruption), which the slow path will judge.
        nul_at = np.where(good, 15 + length, 0)
        good &= rows[np.arange(n), nul_at] == 0
        idx = np.flatnonzero(good)
        if idx.size == 0:
            continue
        sub = rows[idx] if idx.size != n else rows
        sec = np.ascontiguousarray(sub[:, 4:8]).view(order + 'i4')[:, 0].astype(np.int64)
        nsec = _u32(sub, 8, order)
        stamp_ns[idx] = sec * _NS_PER_S + nsec
        tail[idx] = np.ascontiguousarray(sub[:, off:]).view(order + 'f8')
        ok |= good
    return ok, stamp_ns, tail


def _bulk_decode(raws, tail_f8, ros1):
    """Group ``raws`` by length and decode each group; return ok mask, stamps and float tails."""
    n = len(raws)
    lengths = np.fromiter(map(len, raws), np.int64, n)
    buf = np.frombuffer(b''.join(raws), np.uint8)
    ok = np.zeros(n, bool)
    stamp_ns = np.zeros(n, np.int64)
    tail = np.zeros((n, tail_f8), np.float64)
    if n == 0:
        return ok, stamp_ns, tail
    first = int(lengths[0])
    if first > 0 and first * n == buf.size and (lengths == first).all():
        # The usual case (one frame_id per topic): the whole batch is one (n, N) view, no copy.
        return _decode_group(buf.reshape(n, first), tail_f8, ros1)
    starts = np.zeros(n, np.int64)
    np.cumsum(lengths[:-1], out=starts[1:])
    for size in np.unique(lengths):
        if size <= 0:
            continue
        idx = np.flatnonzero(lengths == size)
        rows = buf[starts[idx, None] + np.arange(size)]
        g_ok, g_stamp, g_tail = _decode_group(rows, tail_f8, ros1)
        ok[idx] = g_ok
        stamp_ns[idx] = g_stamp
        tail[idx] = g_tail
    return ok, stamp_ns, tail


def _slow_decode(raw, msgtype, ros1):
    """Decode one message with rosbags; raise BagError if rosbags cannot."""
    store = _typestore(ros1)
    try:
        if ros1:
            return store.deserialize_ros1(raw, msgtype)
        return store.deserialize_cdr(raw, msgtype)
    except Exception as err:  # noqa: BLE001 - rosbags raises many types on corrupt bytes
        raise BagError(
            f'a {msgtype} message of {len(raw)} bytes cannot be decoded ({type(err).__name__}: {err})'
        ) from err


def _frame_id(raw, ros1):
    """``header.frame_id`` of one raw message, or None if the header cannot be parsed cheaply."""
    if len(raw) < 16:
        return None
    if ros1:
        length = int.from_bytes(raw[12:16], 'little')
        return bytes(raw[16:16 + length]).decode('utf-8', 'replace') if 16 + length <= len(raw) else None
    order = 'little' if raw[1] == 1 else 'big'
    length = int.from_bytes(raw[12:16], order)
    if length < 1 or 16 + length > len(raw):
        return None
    return bytes(raw[16:16 + length - 1]).decode('utf-8', 'replace')


def _stamp_of(msg):
    return int(msg.header.stamp.sec) * _NS_PER_S + int(msg.header.stamp.nanosec)


def _as_log_ns(log_ns, n, stamp_ns):
    if log_ns is None:
        return stamp_ns.copy()
    out = np.asarray(log_ns, dtype=np.int64).reshape(-1)
    if out.shape[0] != n:
        raise ParameterError(f'log_ns has {out.shape[0]} values for {n} messages')
    return out


def decode_imu(raws, *, log_ns=None, ros1=False, skip_undecodable=False):
    """
    Decode raw ``sensor_msgs/Imu`` messages in bulk.

    Parameters
    ----------
    raws : sequence of bytes-like
        Serialised messages: ROS 2 CDR (either endianness) or, with ``ros1=True``, ROS 1.
        Rclpy ``raw=True`` subscriptions deliver exactly these CDR bytes.
    log_ns : array_like of int, shape (n,), optional
        Receive times in ns; defaults to the header stamps.
    ros1 : bool
        Messages use the ROS 1 serialisation.
    skip_undecodable : bool
        Drop messages neither the bulk nor the rosbags decoder can read instead of raising.

    Returns
    -------
    ImuBatch
        With ``len(batch) <= len(raws)`` (shorter only when messages were skipped).

    Raises
    ------
    BagError
        A message cannot be decoded and ``skip_undecodable`` is False.
    """
    batch, _ = _decode_imu(raws, log_ns, ros1, skip_undecodable)
    return batch


def _decode_imu(raws, log_ns, ros1, skip_undecodable):
    """Decode as :func:`decode_imu`; also return the number of skipped messages."""
    n = len(raws)
    ok, stamp_ns, tail = _bulk_decode(raws, _IMU_TAIL_F8, ros1)
    gyro = tail[:, _GYRO_COLS].copy()
    accel = tail[:, _ACCEL_COLS].copy()
    log = _as_log_ns(log_ns, n, stamp_ns)
    frame_id = _frame_id(raws[0], ros1) if n else ''
    keep = None
    bad = np.flatnonzero(~ok)
    for i in bad:
        try:
            msg = _slow_decode(raws[i], IMU_MSGTYPE, ros1)
        except BagError:
            if not skip_undecodable:
                raise
            keep = np.ones(n, bool) if keep is None else keep
            keep[i] = False
            continue
        stamp_ns[i] = _stamp_of(msg)
        av, la = msg.angular_velocity, msg.linear_acceleration
        gyro[i] = (av.x, av.y, av.z)
        accel[i] = (la.x, la.y, la.z)
        if i == 0:
            frame_id = msg.header.frame_id
    if log_ns is None:
        log = stamp_ns.copy()
    skipped = 0
    if keep is not None:
        skipped = int(n - keep.sum())
        stamp_ns, log, gyro, accel = stamp_ns[keep], log[keep], gyro[keep], accel[keep]
        first = int(np.flatnonzero(keep)[0]) if keep.any() else None
        frame_id = (_frame_id(raws[first], ros1) or '') if first is not None else ''
    return ImuBatch(stamp_ns, log, gyro, accel, frame_id or ''), skipped


def decode_temperature(raws, *, ros1=False):
    """
    Decode raw ``sensor_msgs/Temperature`` messages in bulk.

    Parameters
    ----------
    raws : sequence of bytes-like
        Serialised messages (ROS 2 CDR, or ROS 1 with ``ros1=True``).
    ros1 : bool
        Messages use the ROS 1 serialisation.

    Returns
    -------
    stamp_ns : numpy.ndarray of int64, shape (n,)
        Header stamps in ns.
    temperature_c : numpy.ndarray of float64, shape (n,)
        ``temperature`` in degC.

    Raises
    ------
    BagError
        A message cannot be decoded.
    """
    ok, stamp_ns, tail = _bulk_decode(raws, _TEMPERATURE_TAIL_F8, ros1)
    temperature_c = tail[:, 0].copy()
    for i in np.flatnonzero(~ok):
        msg = _slow_decode(raws[i], TEMPERATURE_MSGTYPE, ros1)
        stamp_ns[i] = _stamp_of(msg)
        temperature_c[i] = msg.temperature
    return stamp_ns, temperature_c


def count_stamp_regressions(stamp_ns, *, previous_ns=None):
    """
    Count stamps that go backwards (strictly earlier than the stamp before them).

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Stamps in ns, in delivery order.
    previous_ns : int, optional
        Last stamp of the preceding batch, so that a stream of batches can be counted piecewise.

    Returns
    -------
    int
        Number of indices ``i`` with ``stamp_ns[i] < stamp_ns[i - 1]``.
    """
    stamps = np.asarray(stamp_ns, dtype=np.int64).reshape(-1)
    if previous_ns is not None:
        stamps = np.concatenate(([np.int64(previous_ns)], stamps))
    return int(np.count_nonzero(stamps[1:] < stamps[:-1]))


# ---------------------------------------------------------------------------------------------
# Bulk encoding


def _split_stamps(stamp_ns, name):
    stamps = np.asarray(stamp_ns)
    if stamps.dtype.kind not in 'iu':
        if stamps.dtype.kind == 'f' and np.all(np.isfinite(stamps)) and np.all(stamps == np.round(stamps)):
            stamps = stamps.astype(np.int64)
        else:
            raise ParameterError(f'{name} must be integer nanoseconds, got dtype {stamps.dtype}')
    stamps = stamps.astype(np.int64).reshape(-1)
    # ROS 2 Time keeps nanosec in [0, 1e9) also for negative times, hence floor division.
    sec = np.floor_divide(stamps, _NS_PER_S)
    nsec = stamps - sec * _NS_PER_S
    if stamps.size and (sec.min() < -(2**31) or sec.max() >= 2**31):
        raise ParameterError(f'{name} {int(stamps[np.argmax(np.abs(sec))])} does not fit builtin_interfaces/Time')
    return stamps, sec, nsec


def _vector3(values, n, name):
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape == (3,) and n == 1:
        arr = arr.reshape(1, 3)
    if arr.shape != (n, 3):
        raise ParameterError(f'{name} must have shape ({n}, 3) to match the stamps, got {arr.shape}')
    return arr


def _covariance(values, n, name):
    if values is None:
        return np.zeros((n, 9))
    arr = np.asarray(values, dtype=np.float64)
    if arr.shape in ((9,), (3, 3)):
        return np.broadcast_to(arr.reshape(9), (n, 9))
    if arr.shape == (n, 9):
        return arr
    raise ParameterError(f'{name} must have 9 values (row-major 3x3) or shape ({n}, 9), got {arr.shape}')


def _encode_cdr(sec, nsec, frame_id, tail):
    """Serialise n messages (header + float64 tail) as little-endian CDR; return one bytes each."""
    name = frame_id.encode('utf-8')
    if b'\x00' in name:
        raise ParameterError(f'frame_id {frame_id!r} must not contain NUL')
    n, k = tail.shape
    head = 4 + _align8(12 + len(name) + 1)
    size = head + 8 * k
    rows = np.zeros((n, size), np.uint8)
    rows[:, 0:4] = np.frombuffer(_CDR_LE, np.uint8)
    rows[:, 4:8] = sec.astype('<i4').view(np.uint8).reshape(n, 4)
    rows[:, 8:12] = nsec.astype('<u4').view(np.uint8).reshape(n, 4)
    rows[:, 12:16] = np.frombuffer(np.uint32(len(name) + 1).astype('<u4').tobytes(), np.uint8)
    rows[:, 16:16 + len(name)] = np.frombuffer(name, np.uint8)
    rows[:, head:] = np.ascontiguousarray(tail, dtype='<f8').view(np.uint8).reshape(n, 8 * k)
    blob = rows.tobytes()
    return [blob[i:i + size] for i in range(0, n * size, size)]


def encode_imu_cdr(stamp_ns, gyro_rad_s, accel_m_s2, *, frame_id='imu_link',
                   angular_velocity_covariance=None, linear_acceleration_covariance=None):
    """
    Serialise ``sensor_msgs/Imu`` messages to little-endian CDR in bulk.

    Byte-identical to ``typestore.serialize_cdr`` of rosbags. Orientation is unknown (REP-145):
    quaternion (0, 0, 0, 1) as in the message default, ``orientation_covariance[0] = -1``.

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Header stamps in ns.
    gyro_rad_s : array_like of float, shape (n, 3)
        Angular velocity x, y, z in rad/s.
    accel_m_s2 : array_like of float, shape (n, 3)
        Linear acceleration x, y, z in m/s^2.
    frame_id : str
        ``header.frame_id``.
    angular_velocity_covariance, linear_acceleration_covariance : array_like, shape (9,) or (n, 9)
        Row-major covariance in (rad/s)^2 and (m/s^2)^2; zeros (unknown) if None.

    Returns
    -------
    list of bytes
        One serialised message per stamp.
    """
    _, sec, nsec = _split_stamps(stamp_ns, 'stamp_ns')
    n = sec.shape[0]
    tail = np.zeros((n, _IMU_TAIL_F8))
    tail[:, 3] = 1.0
    tail[:, 4] = -1.0
    tail[:, _GYRO_COLS] = _vector3(gyro_rad_s, n, 'gyro_rad_s')
    tail[:, 16:25] = _covariance(angular_velocity_covariance, n, 'angular_velocity_covariance')
    tail[:, _ACCEL_COLS] = _vector3(accel_m_s2, n, 'accel_m_s2')
    tail[:, 28:37] = _covariance(linear_acceleration_covariance, n, 'linear_acceleration_covariance')
    return _encode_cdr(sec, nsec, frame_id, tail)


def encode_temperature_cdr(stamp_ns, temperature_c, *, frame_id='imu_link', variance=0.0):
    """
    Serialise ``sensor_msgs/Temperature`` messages to little-endian CDR in bulk.

    Parameters
    ----------
    stamp_ns : array_like of int, shape (n,)
        Header stamps in ns.
    temperature_c : array_like of float, shape (n,)
        Temperature in degC.
    frame_id : str
        ``header.frame_id``.
    variance : float or array_like, shape (n,)
        Temperature variance in degC^2 (0 = unknown).

    Returns
    -------
    list of bytes
        One serialised message per stamp.
    """
    _, sec, nsec = _split_stamps(stamp_ns, 'stamp_ns')
    n = sec.shape[0]
    temps = np.asarray(temperature_c, dtype=np.float64).reshape(-1)
    if temps.shape[0] != n:
        raise ParameterError(f'temperature_c has {temps.shape[0]} values for {n} stamps')
    tail = np.empty((n, _TEMPERATURE_TAIL_F8))
    tail[:, 0] = temps
    tail[:, 1] = np.broadcast_to(np.asarray(variance, dtype=np.float64), (n,))
    return _encode_cdr(sec, nsec, frame_id, tail)


# ---------------------------------------------------------------------------------------------
# Opening bags


_MAGIC = {
    b'#ROSBAG V2.0': 'ros1',
    b'\x89MCAP0\r\n': 'mcap',
    b'SQLite format 3\x00': 'sqlite3',
}


def _sniff(path):
    try:
        with open(path, 'rb') as fh:
            head = fh.read(16)
    except OSError as err:
        raise BagError(f'bag file {str(path)!r} cannot be read: {err.strerror or err}') from err
    for magic, kind in _MAGIC.items():
        if head.startswith(magic):
            return kind
    return None


def _describe(err):
    text = str(err).strip().rstrip('.') or type(err).__name__
    return text.splitlines()[0]


class _OpenBag:
    """A rosbags reader opened on any supported path, with its storage kind."""

    def __init__(self, path):
        self.path = Path(path)
        if not self.path.exists():
            raise BagError(f'bag path {str(self.path)!r} does not exist')
        target, self.storage = self._resolve(self.path)
        self.ros1 = self.storage == 'ros1'
        try:
            if self.ros1:
                from rosbags.rosbag1 import Reader as Ros1Reader

                self.reader = Ros1Reader(target)
            else:
                from rosbags.rosbag2 import Reader as Ros2Reader

                self.reader = Ros2Reader(target)
            self.reader.open()
            self.connections = list(self.reader.connections)
        except BagError:
            raise
        except Exception as err:  # noqa: BLE001 - rosbags/apsw/zstd raise many types on corrupt files
            raise BagError(
                f'bag {str(self.path)!r} cannot be opened as {self.storage} (corrupt or truncated?): {_describe(err)}'
            ) from err

    @staticmethod
    def _resolve(path):
        """Return (path to hand to rosbags, storage kind) or raise BagError."""
        if path.is_dir():
            meta = path / 'metadata.yaml'
            files = sorted(path.glob('*.db3')) + sorted(path.glob('*.mcap'))
            if meta.exists():
                kinds = {_sniff(f) for f in files}
                if not files:
                    raise BagError(f'bag directory {str(path)!r} has metadata.yaml but no .db3 or .mcap file')
                kind = kinds.pop() if len(kinds) == 1 else None
                if kind not in _STORAGES:
                    raise BagError(f'bag directory {str(path)!r} holds files that are not sqlite3 or MCAP')
                return path, kind
            if len(files) == 1:
                # A recording whose writer died before writing metadata.yaml: read the storage file.
                return _OpenBag._resolve(files[0])
            raise BagError(
                f'directory {str(path)!r} is not a rosbag2 bag (no metadata.yaml'
                f'{" and several storage files" if files else ""})'
            )
        if path.name == 'metadata.yaml':
            return _OpenBag._resolve(path.parent)
        kind = _sniff(path)
        expected = {'.bag': 'ros1', '.mcap': 'mcap', '.db3': 'sqlite3'}.get(path.suffix)
        if kind is None:
            raise BagError(
                f'file {str(path)!r} is not a bag (expected a rosbag2 directory, a .db3 or .mcap file, '
                'or a ROS 1 .bag file)'
            )
        if expected != kind:
            raise BagError(f'file {str(path)!r} holds {kind} data but its suffix is {path.suffix!r}; '
                           f'rename it to {{.bag, .mcap, .db3}} to match')
        return path, kind

    def topics(self):
        """Return {name: TopicInfo} merged over connections."""
        out = {}
        for conn in self.connections:
            info = out.get(conn.topic)
            count = int(conn.msgcount or 0)
            if self.ros1:
                count = sum(int(c.connection_counts.get(conn.id, 0)) for c in self.reader.chunk_infos)
            if info is None:
                out[conn.topic] = TopicInfo(conn.topic, conn.msgtype, count)
            else:
                msgtype = info.msgtype if info.msgtype == conn.msgtype else None
                out[conn.topic] = TopicInfo(conn.topic, msgtype, info.count + count)
        return out

    def duration_s(self):
        try:
            duration = int(self.reader.duration)
        except Exception:  # noqa: BLE001 - an empty bag has no meaningful duration
            return 0.0
        if not self.ros1 and duration > 0:
            duration -= 1  # rosbags reports rosbag2 duration as last - first + 1 ns
        return max(duration, 0) / 1e9

    def messages(self, topic):
        """Yield (log_ns, raw) for one topic; errors become BagError."""
        conns = [c for c in self.connections if c.topic == topic]
        count = 0
        try:
            for _, log_ns, raw in self.reader.messages(connections=conns):
                count += 1
                yield log_ns, raw
        except BagError:
            raise
        except Exception as err:  # noqa: BLE001 - corrupt/truncated storage surfaces mid-stream
            raise BagError(
                f'bag {str(self.path)!r} is corrupt or truncated after {count} messages on '
                f'{topic!r}: {_describe(err)}'
            ) from err

    def close(self):
        try:
            self.reader.close()
        except Exception:  # noqa: BLE001, S110 - closing a half-broken reader must not mask the cause
            pass


def _norm(name):
    return name.lstrip('/')


def _select_topic(topics, topic, msgtype, path, *, what):
    """Pick the topic of ``msgtype`` (the single one if ``topic`` is None); raise BagError."""
    if topic is not None:
        matches = [t for t in topics.values() if _norm(t.name) == _norm(topic)]
        if not matches:
            known = ', '.join(sorted(topics)) or 'none'
            raise BagError(f'topic {topic!r} is not in bag {str(path)!r} (topics: {known})')
        info = matches[0]
        if info.msgtype != msgtype:
            raise BagError(f'topic {info.name!r} in bag {str(path)!r} carries {info.msgtype}, not {msgtype}')
        return info.name
    candidates = sorted(t.name for t in topics.values() if t.msgtype == msgtype)
    if not candidates:
        raise BagError(f'bag {str(path)!r} has no {msgtype} topic{what}')
    if len(candidates) > 1:
        raise BagError(
            f'bag {str(path)!r} has {len(candidates)} {msgtype} topics ({", ".join(candidates)}); '
            'choose one with --topic'
        )
    return candidates[0]


def list_topics(path):
    """
    List the topics of a bag.

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory, ``.db3``/``.mcap`` file, or ROS 1 ``.bag`` file.

    Returns
    -------
    list of TopicInfo
        Sorted by name.

    Raises
    ------
    BagError
        The path is missing or not a readable bag.
    """
    bag = _OpenBag(path)
    try:
        return sorted(bag.topics().values(), key=lambda t: t.name)
    finally:
        bag.close()


def find_imu_topic(path, topic=None):
    """
    Name the ``sensor_msgs/Imu`` topic to analyse.

    Parameters
    ----------
    path : str or os.PathLike
        Bag path (see :func:`list_topics`).
    topic : str, optional
        Requested topic, matched with or without the leading slash. If None, the bag's single
        ``sensor_msgs/msg/Imu`` topic.

    Returns
    -------
    str
        The topic name as stored in the bag.

    Raises
    ------
    BagError
        No Imu topic, several Imu topics (the message lists them), unknown topic, or a topic of
        another message type.
    """
    bag = _OpenBag(path)
    try:
        return _select_topic(bag.topics(), topic, IMU_MSGTYPE, path, what='')
    finally:
        bag.close()


# ---------------------------------------------------------------------------------------------
# Reader


class ImuBagReader:
    """
    Stream ``sensor_msgs/Imu`` (and optionally ``sensor_msgs/Temperature``) out of one bag.

    Memory stays constant in the bag size: messages are read and decoded ``batch_size`` at a time
    (rosbags' ROS 1 reader is the exception: it keeps its per-message index in memory).

    Parameters
    ----------
    path : str or os.PathLike
        rosbag2 directory (sqlite3 or MCAP), a ``.db3`` or ``.mcap`` file, or a ROS 1 ``.bag`` file.
    topic : str, optional
        Imu topic (with or without leading slash); the bag's single Imu topic if None.
    temperature_topic : str, optional
        ``sensor_msgs/Temperature`` topic. If None: the bag's single Temperature topic, or when
        several exist the one in the Imu topic's namespace, else no temperature.
    skip_undecodable : bool
        Skip (and count in ``undecodable_count``) messages that cannot be decoded instead of raising.

    Attributes
    ----------
    topic, msgtype : str
        Imu topic as stored, and ``sensor_msgs/msg/Imu``.
    temperature_topic : str or None
    storage : {'sqlite3', 'mcap', 'ros1'}
    message_count : int
        Imu messages the bag reports on the topic.
    duration_s : float
        Span of the whole bag in s (first to last message of any topic, receive time).
    undecodable_count : int
        Messages skipped so far (only with ``skip_undecodable``).

    Raises
    ------
    BagError
        Missing or corrupt bag, no/ambiguous/unknown Imu topic, wrong message type.
    """

    def __init__(self, path, *, topic=None, temperature_topic=None, skip_undecodable=False):
        self.path = Path(path)
        self._bag = _OpenBag(path)
        try:
            topics = self._bag.topics()
            self.topic = _select_topic(topics, topic, IMU_MSGTYPE, path, what='')
            self.msgtype = IMU_MSGTYPE
            self.storage = self._bag.storage
            self.message_count = topics[self.topic].count
            self.duration_s = self._bag.duration_s()
            self.temperature_topic = self._pick_temperature(topics, temperature_topic)
        except BaseException:
            self._bag.close()
            raise
        self.skip_undecodable = bool(skip_undecodable)
        self.undecodable_count = 0

    def _pick_temperature(self, topics, requested):
        if requested is not None:
            return _select_topic(topics, requested, TEMPERATURE_MSGTYPE, self.path, what='')
        names = sorted(t.name for t in topics.values() if t.msgtype == TEMPERATURE_MSGTYPE)
        if len(names) == 1:
            return names[0]
        namespace = _norm(self.topic).rpartition('/')[0]
        same = [n for n in names if _norm(n).rpartition('/')[0] == namespace]
        return same[0] if len(same) == 1 else None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self):
        """Close the bag (idempotent)."""
        if self._bag is not None:
            self._bag.close()
            self._bag = None

    def _open_bag(self):
        if self._bag is None:
            raise BagError(f'bag {str(self.path)!r} was closed')
        return self._bag

    def iter_batches(self, batch_size=65536):
        """
        Yield the Imu messages in bag order as :class:`ImuBatch` es.

        Parameters
        ----------
        batch_size : int
            Messages per batch (the last one may be shorter); at least 1.

        Yields
        ------
        ImuBatch
            Stamps are delivered as recorded (see :func:`count_stamp_regressions`).

        Raises
        ------
        BagError
            The topic has no messages (raised at the end, nothing was yielded), the bag turns out
            corrupt or truncated, or a message cannot be decoded.
        """
        if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ParameterError(f'batch_size must be a positive integer, got {batch_size!r}')
        bag = self._open_bag()
        stream = bag.messages(self.topic)
        delivered = 0
        while True:
            chunk = list(itertools.islice(stream, int(batch_size)))
            if not chunk:
                if delivered == 0 and self.undecodable_count == 0:
                    raise BagError(f'bag {str(self.path)!r} has no messages on topic {self.topic!r}')
                return
            delivered += len(chunk)
            log_ns, raws = zip(*chunk)
            del chunk
            try:
                batch, skipped = _decode_imu(raws, np.fromiter(log_ns, np.int64, len(log_ns)),
                                             bag.ros1, self.skip_undecodable)
            except BagError as err:
                raise BagError(f'bag {str(self.path)!r}, topic {self.topic!r}: {err}') from err
            self.undecodable_count += skipped
            if len(batch):
                yield batch

    def read_temperature(self):
        """
        Read the whole temperature topic.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(stamp_ns int64 (n,), temperature_c float64 (n,))`` in bag order, or None if the bag
            has no temperature topic.

        Raises
        ------
        BagError
            The bag turns out corrupt or a message cannot be decoded.
        """
        if self.temperature_topic is None:
            return None
        bag = self._open_bag()
        stamps, temps = [], []
        stream = bag.messages(self.temperature_topic)
        while chunk := list(itertools.islice(stream, 65536)):
            try:
                s, t = decode_temperature([raw for _, raw in chunk], ros1=bag.ros1)
            except BagError as err:
                raise BagError(f'bag {str(self.path)!r}, topic {self.temperature_topic!r}: {err}') from err
            stamps.append(s)
            temps.append(t)
        if not stamps:
            return np.zeros(0, np.int64), np.zeros(0, np.float64)
        return np.concatenate(stamps), np.concatenate(temps)


# ---------------------------------------------------------------------------------------------
# Writer


class ImuBagWriter:
    """
    Write ``sensor_msgs/Imu`` and ``sensor_msgs/Temperature`` into a new rosbag2.

    Messages are serialised in bulk (:func:`encode_imu_cdr`) and handed to the rosbags writer.
    The bag (its ``metadata.yaml``) is complete only after :meth:`close`; the context manager
    closes it also when the body raises, so that what was recorded is kept.

    Parameters
    ----------
    path : str or os.PathLike
        Bag directory to create; must not exist.
    storage : {'sqlite3', 'mcap'}
        rosbag2 storage plugin.
    imu_topic, temperature_topic : str
        Topic names (the temperature connection is created on the first temperature write).
    frame_id : str
        ``header.frame_id`` of every message.

    Raises
    ------
    ParameterError
        Unknown storage or bad frame_id.
    BagError
        The bag cannot be created (path exists, not writable).
    """

    def __init__(self, path, *, storage='sqlite3', imu_topic='/imu/data_raw',
                 temperature_topic='/imu/temperature', frame_id='imu_link'):
        from rosbags.rosbag2 import StoragePlugin, Writer

        if storage not in _STORAGES:
            raise ParameterError(f"storage must be 'sqlite3' or 'mcap', got {storage!r}")
        if not isinstance(frame_id, str) or '\x00' in frame_id:
            raise ParameterError(f'frame_id must be a str without NUL, got {frame_id!r}')
        self.path = Path(path)
        self.storage = storage
        self.imu_topic = imu_topic
        self.temperature_topic = temperature_topic
        self.frame_id = frame_id
        self.imu_count = 0
        self.temperature_count = 0
        plugin = StoragePlugin.SQLITE3 if storage == 'sqlite3' else StoragePlugin.MCAP
        try:
            self._writer = Writer(self.path, version=9, storage_plugin=plugin)
            self._writer.open()
            self._imu_conn = self._writer.add_connection(imu_topic, IMU_MSGTYPE, typestore=_typestore())
        except Exception as err:  # noqa: BLE001 - rosbags WriterError, OSError, sqlite errors
            raise BagError(f'bag {str(self.path)!r} cannot be created: {_describe(err)}') from err
        self._temperature_conn = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _write(self, conn, log_ns, blobs):
        writer = self._writer
        if writer is None:
            raise BagError(f'bag {str(self.path)!r} is closed')
        try:
            for t, blob in zip(log_ns.tolist(), blobs):
                writer.write(conn, t, blob)
        except Exception as err:  # noqa: BLE001 - disk full, sqlite errors
            raise BagError(f'bag {str(self.path)!r}: writing failed: {_describe(err)}') from err

    def write_imu(self, stamp_ns, gyro_rad_s, accel_m_s2, *, angular_velocity_covariance=None,
                  linear_acceleration_covariance=None, log_ns=None):
        """
        Append Imu messages.

        Parameters
        ----------
        stamp_ns : int or array_like of int, shape (n,)
            Header stamps in ns.
        gyro_rad_s : array_like, shape (3,) or (n, 3)
            Angular velocity in rad/s.
        accel_m_s2 : array_like, shape (3,) or (n, 3)
            Linear acceleration in m/s^2.
        angular_velocity_covariance, linear_acceleration_covariance : array_like, shape (9,) or (n, 9)
            Row-major covariances in (rad/s)^2 and (m/s^2)^2; zeros (unknown) if None.
        log_ns : int or array_like of int, optional
            Bag (receive) time in ns; the header stamps if None.
        """
        stamps, _, _ = _split_stamps(stamp_ns, 'stamp_ns')
        blobs = encode_imu_cdr(stamps, gyro_rad_s, accel_m_s2, frame_id=self.frame_id,
                               angular_velocity_covariance=angular_velocity_covariance,
                               linear_acceleration_covariance=linear_acceleration_covariance)
        logs = stamps if log_ns is None else _split_stamps(log_ns, 'log_ns')[0]
        if logs.shape != stamps.shape:
            raise ParameterError(f'log_ns has {logs.shape[0]} values for {stamps.shape[0]} stamps')
        self._write(self._imu_conn, logs, blobs)
        self.imu_count += len(blobs)

    def write_temperature(self, stamp_ns, temperature_c, *, variance=0.0, log_ns=None):
        """
        Append Temperature messages.

        Parameters
        ----------
        stamp_ns : int or array_like of int, shape (n,)
            Header stamps in ns.
        temperature_c : float or array_like, shape (n,)
            Temperature in degC.
        variance : float or array_like, shape (n,)
            Variance in degC^2 (0 = unknown).
        log_ns : int or array_like of int, optional
            Bag (receive) time in ns; the header stamps if None.
        """
        if self.temperature_topic is None:
            raise ParameterError('temperature_topic is None, so this writer records no temperature')
        stamps, _, _ = _split_stamps(stamp_ns, 'stamp_ns')
        blobs = encode_temperature_cdr(stamps, temperature_c, frame_id=self.frame_id, variance=variance)
        logs = stamps if log_ns is None else _split_stamps(log_ns, 'log_ns')[0]
        if logs.shape != stamps.shape:
            raise ParameterError(f'log_ns has {logs.shape[0]} values for {stamps.shape[0]} stamps')
        if self._temperature_conn is None and self._writer is not None:
            try:
                self._temperature_conn = self._writer.add_connection(
                    self.temperature_topic, TEMPERATURE_MSGTYPE, typestore=_typestore())
            except Exception as err:  # noqa: BLE001
                raise BagError(f'bag {str(self.path)!r}: cannot add {self.temperature_topic!r}: '
                               f'{_describe(err)}') from err
        self._write(self._temperature_conn, logs, blobs)
        self.temperature_count += len(blobs)

    def close(self):
        """Finish the bag: write its index and ``metadata.yaml`` (idempotent)."""
        writer, self._writer = self._writer, None
        if writer is not None:
            try:
                writer.close()
            except Exception as err:  # noqa: BLE001
                raise BagError(f'bag {str(self.path)!r} cannot be finished: {_describe(err)}') from err
