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
Portenta H7 + LSM6DSO32 link.

Wire protocol, decoder, datasheet scaling, device clock, SD logs, board model.

Pure Python on numpy (no ROS). The wire contract is ``docs/portenta_link.md``.

- :mod:`.protocol`: frames, :class:`~.protocol.Decoder` (never raises), counters.
- :mod:`.lsm6dso32`: full scales, ODRs, raw words to SI.
- :mod:`.clock`: uint32 unwrapping and the device-to-host time estimator.
- :mod:`.sdlog`: SD-card log files (writer, streaming reader).
- :mod:`.emulator`: the board model used by ``portenta_emulator`` and the tests.
"""
