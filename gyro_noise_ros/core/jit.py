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
Compilation flags of the package's numba kernels (public: modules outside core compile with them).

The kernels themselves are private (``core/_kernels*.py``, each with a plain-numpy twin in
``test/``); a kernel elsewhere in the package (thermal simulation, for example) decorates with
``@numba.njit(**JIT_OPTIONS)`` so every kernel is compiled the same way.
"""

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

__all__ = ['JIT_OPTIONS']

#: Compilation flags of every kernel in the package (read-only). ``fastmath`` is left off: the
#: kernels feed estimators that are compared to references at 1e-9 relative, and re-association
#: of long sums would make results depend on the vector width of the machine. ``cache`` avoids
#: re-JIT on start-up; ``nogil`` lets worker threads run kernels side by side.
JIT_OPTIONS: Mapping[str, Any] = MappingProxyType(
    {'cache': True, 'nogil': True, 'fastmath': False})
