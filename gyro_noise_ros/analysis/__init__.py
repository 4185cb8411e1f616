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
The files of an offline analysis (gyro_noise_analyze), renderers only, ROS-free.

:mod:`.summary_json` (the entries of summary.json), :mod:`.summary_md` (summary.md),
:mod:`.csv_tables` (chunks.csv, allan.csv), :mod:`.imu_yaml` (Kalibr's imu.yaml), :mod:`.figures`
(the PNG figures): one module per file. The workflow that computes the numbers and calls them is
:mod:`..app.analyze`; the HTML page, :mod:`..htmlreport.analyze`.
"""
