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
Drain raw subscriptions as their messages arrive: a thread waiting on an rcl wait set of its own.

The executor wakes per message and builds a wait set of every entity of the node each time; a
timer-driven drain adds up to its period to every message's latency. :class:`WaitSetDrain` waits
on a wait set holding only the given (polled, ``raw=True``) subscriptions and a guard condition
that stops it, and calls ``on_ready()`` whenever one of them has data, or every ``timeout_s``
(for time-outs the caller handles). ``on_ready`` takes every queued message itself (``take_all``,
:class:`~._publishers.RawTaker`): one wake-up serves a whole burst. The wait releases the GIL.
"""

from collections.abc import Callable, Sequence
from contextlib import ExitStack
import threading
import time

from rclpy.context import Context
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription


class WaitSetDrain:
    """
    A thread that calls ``on_ready()`` whenever one of the subscriptions has messages.

    Parameters
    ----------
    context : rclpy.context.Context
        The subscriptions' context.
    subscriptions : sequence of rclpy.subscription.Subscription
        Polled raw subscriptions (:class:`~._ros_common.PolledGroup`): the executor never takes
        them.
    on_ready : callable
        ``on_ready()``, called in the thread after each wake-up (data or time-out).
    timeout_s : float, keyword-only
        Longest wait without data (s): ``on_ready`` also runs then.
    name : str, keyword-only
        Thread name.

    """

    def __init__(self, context: Context, subscriptions: Sequence[Subscription],
                 on_ready: Callable[[], object], *, timeout_s: float = 0.05,
                 linger_s: float = 0.0, name: str = 'waitset_drain') -> None:
        self._context = context
        self._subs = list(subscriptions)
        self._on_ready = on_ready
        self._timeout_ns = int(timeout_s * 1e9)
        self._linger_s = float(linger_s)
        handle = context.handle
        assert handle is not None  # an initialised context
        with handle:
            self._guard = _rclpy.GuardCondition(handle)
        self._stop = threading.Event()
        self.wakeups = 0
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def start(self) -> None:
        """Start the thread."""
        self._thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Wake the thread, let it finish its pass, and join it (idempotent)."""
        self._stop.set()
        try:
            self._guard.trigger_guard_condition()
        except Exception:  # noqa: BLE001 - a context already shut down: the time-out ends the wait
            pass
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)

    def _run(self) -> None:
        try:
            wait_set = _rclpy.WaitSet(len(self._subs), 1, 0, 0, 0, 0, self._context.handle)
            handles = [sub.handle for sub in self._subs]
            with ExitStack() as stack:
                # In use while this thread runs (entered once: ~5 us a wake-up otherwise):
                # destroying the node meanwhile defers their destruction (the nodes stop the
                # thread first).
                for handle in handles:
                    stack.enter_context(handle)
                while not self._stop.is_set():
                    wait_set.clear_entities()
                    for handle in handles:
                        wait_set.add_subscription(handle)
                    wait_set.add_guard_condition(self._guard)
                    wait_set.wait(self._timeout_ns)
                    if self._stop.is_set() or not self._context.ok():
                        break
                    if self._linger_s > 0:
                        time.sleep(self._linger_s)
                    self.wakeups += 1
                    self._on_ready()
        except BaseException as err:  # noqa: BLE001 - kept for the node; shutdown races end here
            if not self._stop.is_set() and self._context.ok():
                self.error = err
                raise
