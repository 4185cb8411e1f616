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
Who publishes on a topic: the writer of every message taken, and the publishers' names.

rclpy 7 (Jazzy) gives a taken message's ``MessageInfo`` without the publisher GID that rmw fills in
(``rmw_message_info_t.publisher_gid``): :class:`RawTaker` takes serialised messages through
``rcl_take_serialized_message`` itself (ctypes on the rcl library rclpy has loaded, the
subscription handle rclpy owns), so every message comes with its writer's GID, the same 16 bytes
the graph reports as ``TopicEndpointInfo.endpoint_gid``. Measured as fast as rclpy's
``take_message``: ~8 us per message on the 2-core test machine. The layout of the C structures is
checked on every batch (the GID's implementation identifier must be the loaded rmw's); if the
library or the check fails, the taker falls back to rclpy's ``take_message`` and says so, and the
writer is then unknown (key None).

:class:`PublisherWatch` keeps the per-publisher counts (the pure
:class:`~gyro_noise_ros.link.sequence.PublisherCounts`), names the writers from
``get_publishers_info_by_topic`` (namespace and node name), and returns a warning when a publisher
starts delivering while another one still does. It
judges from the messages, not from the graph: a killed driver stays in the graph for its lease
(3 s as the package's nodes announce it, ``_dds_profile``; 20 s, Fast DDS's default, for other
nodes) while its restarted successor, a new writer, already publishes. The recorder and
the analyzer use both.
"""

from collections.abc import Sequence
import ctypes
from typing import Any

import numpy as np
from numpy.typing import NDArray
from rclpy.impl.rcutils_logger import RcutilsLogger
from rclpy.node import Node
from rclpy.subscription import Subscription

from ._ros_common import take_all
from ..link.sequence import PublisherCounts

# rmw_message_info_t (rmw 7, Jazzy): source and received timestamps (int64), publication and
# reception sequence numbers (uint64), rmw_gid_t {const char * implementation_identifier;
# uint8_t data[RMW_GID_STORAGE_SIZE = 16]}, bool from_intra_process.
_INFO_DTYPE = np.dtype([('source_ns', '<i8'), ('received_ns', '<i8'), ('publication', '<u8'),
                        ('reception', '<u8'), ('identifier', '<u8'), ('gid', 'V16'),
                        ('intra', 'u1')], align=True)
# rmw writes the struct it was built with; a generous buffer keeps a larger one (another rmw
# version) from writing past it, and the identifier check then catches the mismatch.
_INFO_BUFFER_BYTES = 512
_RCL_RET_OK = 0
_RCL_RET_SUBSCRIPTION_TAKE_FAILED = 401
#: The writers of a batch: GIDs (dtype ``V16``), 16-byte strings, or None when unknown.
_Gids = NDArray[np.void] | Sequence[bytes] | None


class _Allocator(ctypes.Structure):
    _fields_ = [('allocate', ctypes.c_void_p), ('deallocate', ctypes.c_void_p),
                ('reallocate', ctypes.c_void_p), ('zero_allocate', ctypes.c_void_p),
                ('state', ctypes.c_void_p)]


class _Uint8Array(ctypes.Structure):
    # rcutils_uint8_array_t, which rcl_serialized_message_t is.
    _fields_ = [('buffer', ctypes.c_void_p), ('buffer_length', ctypes.c_size_t),
                ('buffer_capacity', ctypes.c_size_t), ('allocator', _Allocator)]


# the libraries and their functions, by name (CDLL objects and function pointers)
_LIB: dict[str, Any] = {}


def _libraries() -> dict[str, Any]:
    """Load (once) the rcl and rcutils libraries rclpy has already loaded."""
    if not _LIB:
        rcl = ctypes.CDLL('librcl.so')
        rcutils = ctypes.CDLL('librcutils.so')
        rcutils.rcutils_get_default_allocator.restype = _Allocator
        rcutils.rcutils_uint8_array_init.argtypes = [ctypes.POINTER(_Uint8Array), ctypes.c_size_t,
                                                     ctypes.POINTER(_Allocator)]
        rcutils.rcutils_uint8_array_fini.argtypes = [ctypes.POINTER(_Uint8Array)]
        rcutils.rcutils_reset_error.argtypes = []
        rcl.rcl_subscription_get_rmw_handle.argtypes = [ctypes.c_void_p]
        rcl.rcl_subscription_get_rmw_handle.restype = ctypes.c_void_p
        take = rcl.rcl_take_serialized_message
        take.argtypes = [ctypes.c_void_p] * 4
        take.restype = ctypes.c_int32
        _LIB.update(take=take, rcutils=rcutils, rmw_handle=rcl.rcl_subscription_get_rmw_handle)
    return _LIB


def _rmw_identifier(lib: dict[str, Any], sub: Subscription) -> int:
    """
    Return the address of the rmw implementation identifier, as the subscription carries it.

    ``rmw_subscription_t`` starts with ``const char * implementation_identifier``, the same static
    string rmw puts into every message's ``publisher_gid``; its text must be the rmw rclpy uses.
    """
    from rclpy.utilities import get_rmw_implementation_identifier

    with sub.handle:
        rmw_sub = lib['rmw_handle'](sub.handle.pointer)
    if not rmw_sub:
        raise OSError('no rmw handle')
    address = ctypes.c_void_p.from_address(rmw_sub).value
    if not address or ctypes.string_at(address).decode() != get_rmw_implementation_identifier():
        raise OSError('unexpected rmw_subscription_t layout')
    return address


class RawTaker:
    """
    Take every queued message of a raw subscription, each with its writer's GID.

    Parameters
    ----------
    sub : rclpy.subscription.Subscription
        Created with ``raw=True`` (in a :class:`~._ros_common.PolledGroup`).
    msg_type : type
        Its message class (used by the fallback).
    logger : rclpy logger or None
        Told once when the GID path is not available.

    """

    def __init__(self, sub: Subscription, msg_type: type,
                 logger: RcutilsLogger | None = None) -> None:
        self.sub, self.msg_type, self._logger = sub, msg_type, logger
        self._array: _Uint8Array | None = None
        self.with_gid = False
        try:
            lib = _libraries()
            self._identifier = _rmw_identifier(lib, sub)
            array = _Uint8Array()
            allocator = lib['rcutils'].rcutils_get_default_allocator()
            if lib['rcutils'].rcutils_uint8_array_init(ctypes.byref(array), 4096,
                                                       ctypes.byref(allocator)) != 0:
                raise OSError('rcutils_uint8_array_init failed')
        except (OSError, AttributeError) as err:
            self._fall_back(f'rcl not reachable through ctypes ({err})')
            return
        self._lib, self._array = lib, array
        self._info = ctypes.create_string_buffer(_INFO_BUFFER_BYTES)
        self.with_gid = True

    def _fall_back(self, why: str) -> None:
        self.with_gid = False
        if self._logger is not None:
            self._logger.warn(f'{self.sub.topic_name}: messages are taken without their '
                              f'publisher ({why}); per-publisher counts are not available')

    def take(self, limit: int | None = None) -> tuple[list[bytes], list[int], list[int], _Gids]:
        """
        Take every queued message, or the oldest ``limit`` of them.

        Parameters
        ----------
        limit : int or None
            Most messages to take (None: all): a caller that processes a backlog in bounded
            batches keeps its temporaries small (a heap that grew for one large batch stays).

        Returns
        -------
        raws : list of bytes
            Serialised messages, oldest first.
        received_ns : list of int
            Receive time of each (system clock, ns; 0 where the middleware gave none).
        sequence : list of int
            DDS publication sequence number of each (0: none given).
        gids : numpy.ndarray or list or None
            The writer GID of each (dtype ``V16``: 16 bytes), an empty list when nothing was
            taken, or None when not available.

        """
        if not self.with_gid:
            return self._take_rclpy(limit)
        take, array, info = self._lib['take'], self._array, self._info
        left = -1 if limit is None else int(limit)
        assert array is not None  # with_gid: the buffer exists until close()
        a_array, a_info = ctypes.addressof(array), ctypes.addressof(info)
        size, string_at = _INFO_DTYPE.itemsize, ctypes.string_at
        raws, infos = [], []
        handle = self.sub.handle
        with handle:
            pointer = handle.pointer
            ret = _RCL_RET_SUBSCRIPTION_TAKE_FAILED
            while left != 0:
                ret = take(pointer, a_array, a_info, None)
                if ret != _RCL_RET_OK:
                    break
                raws.append(string_at(array.buffer, array.buffer_length))
                infos.append(string_at(a_info, size))
                left -= 1
        if ret not in (_RCL_RET_OK, _RCL_RET_SUBSCRIPTION_TAKE_FAILED):
            self._lib['rcutils'].rcutils_reset_error()
            raise RuntimeError(f'{self.sub.topic_name}: rcl_take_serialized_message returned '
                               f'{ret}')
        if not raws:
            return [], [], [], []
        rec = np.frombuffer(b''.join(infos), dtype=_INFO_DTYPE)
        if not np.all(rec['identifier'] == self._identifier):
            # Not the layout this module was written for: keep the messages, drop the GIDs.
            self._fall_back('rmw_message_info_t layout differs from rmw 7')
            return raws, [0] * len(raws), [0] * len(raws), None
        return raws, rec['received_ns'].tolist(), rec['publication'].tolist(), rec['gid'].copy()

    def _take_rclpy(self, limit: int | None) -> tuple[list[bytes], list[int], list[int], None]:
        return (*take_all(self.sub, self.msg_type, limit), None)

    def close(self) -> None:
        """Free the serialisation buffer (idempotent)."""
        if self._array is not None:
            self._lib['rcutils'].rcutils_uint8_array_fini(ctypes.byref(self._array))
            self._array = None
            self.with_gid = False


def publisher_names(node: Node, topic: str) -> dict[bytes, str]:
    """
    Name the publishers of a topic from the graph.

    Parameters
    ----------
    node : rclpy.node.Node
        Any node of the graph.
    topic : str
        Fully qualified topic name.

    Returns
    -------
    dict
        ``{gid (16 bytes): '/namespace/node'}``.

    """
    names: dict[bytes, str] = {}
    for info in node.get_publishers_info_by_topic(topic):
        ns = info.node_namespace.rstrip('/')
        names[bytes(info.endpoint_gid)[:16]] = f'{ns}/{info.node_name}'
    return names


class PublisherWatch:
    """
    Per-publisher counts of one topic, publisher names, and the second-publisher warning.

    A publisher that starts delivering while another one delivered within ``overlap_s`` is a
    second publisher (warning); one that starts after the others fell silent for longer replaced
    them (a restarted driver gets a new writer GID; information only). The graph names them.

    Parameters
    ----------
    topic : str
        Fully qualified topic name (in the lines).
    consequence : str
        What a second publisher does to this node's output (the end of the warning).
    overlap_s : float
        Silence after which a publisher no longer counts as present (s).

    """

    def __init__(self, topic: str, consequence: str, overlap_s: float = 2.0) -> None:
        self.topic, self.consequence, self.overlap_s = topic, consequence, float(overlap_s)
        self.counts = PublisherCounts()
        # gid -> '/ns/node' (from the graph, kept after it leaves)
        self.names: dict[bytes, str] = {}
        self.last_seen: dict[bytes | None, float] = {}  # gid -> monotonic s of its latest message
        # (gid, [gids present when it started]) not yet reported
        self._news: list[tuple[bytes | None, list[bytes | None]]] = []

    def update(self, gids: _Gids, sequence: Sequence[int], now_s: float) -> None:
        """
        Count one batch.

        Parameters
        ----------
        gids : numpy.ndarray or sequence of bytes or None
            :meth:`RawTaker.take`'s writers (None: unknown).
        sequence : list of int
            Their publication sequence numbers.
        now_s : float
            Monotonic time of the take (s).

        """
        before = self.counts.publishers()
        batch = self.counts.update(gids, sequence)
        present = [g for g in before if now_s - self.last_seen[g] <= self.overlap_s]
        for gid in batch:  # in order of first message: the earlier ones were there first
            if gid not in self.last_seen:
                self._news.append((gid, [g for g in present if g != gid]))
            self.last_seen[gid] = now_s
            if gid not in present:
                present.append(gid)

    def active(self, now_s: float) -> list[bytes | None]:
        """Return the publishers that delivered within ``overlap_s`` of ``now_s``."""
        return [g for g, t in self.last_seen.items() if now_s - t <= self.overlap_s]

    def name(self, gid: bytes | None) -> str:
        """Return the publisher's name, with a short GID where two share one."""
        if gid is None:
            return 'unknown publisher'
        name = self.names.get(gid)
        if name is None:
            return f'publisher {gid.hex()[:12]}'
        if sum(n == name for n in self.names.values()) > 1:
            return f'{name} ({gid.hex()[:12]})'
        return name

    def check(self, node: Node) -> list[tuple[str, str]]:
        """
        Name the publishers that appeared since the last call; return the lines to log.

        Parameters
        ----------
        node : rclpy.node.Node
            The subscribing node (its graph names the writers).

        Returns
        -------
        list of (str, str)
            ``('warn', line)`` for a publisher that joined another one, ``('info', line)`` for
            the first one or a replacement.

        """
        if not self._news:
            return []
        self.names.update(publisher_names(node, self.topic))
        lines: list[tuple[str, str]] = []
        for gid, present in self._news:
            if present:
                lines.append(('warn', f'another publisher on {self.topic}: {self.name(gid)} '
                              f'(besides {", ".join(self.name(g) for g in present)}); '
                              f'{self.consequence}'))
            elif len(self.last_seen) > 1:
                lines.append(('info', f'new publisher on {self.topic}: {self.name(gid)} (the '
                              f'previous one silent for more than {self.overlap_s:g} s)'))
            else:
                lines.append(('info', f'receiving {self.topic} from {self.name(gid)}'))
        self._news = []
        return lines

    def summary(self) -> str:
        """Return ``'/ns/node 1234 (0 dropped); ...'`` over the publishers that sent messages."""
        parts = [f'{self.name(g)} {n} ({d} dropped)' for g, n, d in self.counts.table()]
        return '; '.join(parts) if parts else 'none'
