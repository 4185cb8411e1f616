#!/bin/sh
# The whole paper 001 procedure on the emulator, before and after a simulated stress
# (docs/reliability.md). Writes everything under ${1:-reliability_demo}/. About 5 min on one core (two 4 h static records at 104 Hz).
set -e
D=${1:-reliability_demo}
mkdir -p "$D" && cd "$D"
EMU="portenta_emulator --odr-hz 104"
# 1. before: six-position calibration, long static record, excitation records
$EMU --seed 1 --scenario six-position --write-bag before_sixpos
$EMU --seed 2 --scenario static --duration-s 14400 --write-bag before_static
$EMU --seed 3 --scenario sine --excite-axis x --excite-amplitude 0.3 --excite-hz 8 \
     --duration-s 32 --write-bag before_sine
$EMU --seed 4 --scenario sweep --excite-axis y --excite-amplitude 0.3 --excite-hz 5 \
     --sweep-to-hz 10 --sweep-rate-hz-s 0.5 --duration-s 42 --write-bag before_sweep
# 2. the stress (here simulated: Table 6 "after" values, cross-axis x2, flicker x1.7)
# 3. after: the same again
$EMU --seed 11 --stress --scenario six-position --write-bag after_sixpos
$EMU --seed 12 --stress --scenario static --duration-s 14400 --write-bag after_static
$EMU --seed 13 --stress --scenario sine --excite-axis x --excite-amplitude 0.3 --excite-hz 8 \
     --duration-s 32 --write-bag after_sine
$EMU --seed 14 --stress --scenario sweep --excite-axis y --excite-amplitude 0.3 --excite-hz 5 \
     --sweep-to-hz 10 --sweep-rate-hz-s 0.5 --duration-s 42 --write-bag after_sweep
# the verdict
gyro_noise_reliability --before-calibration before_sixpos --before-static before_static \
    --after-calibration after_sixpos --after-static after_static --latitude 45 --out report
gyro_noise_excitation before_sine after_sine --topic /imu/data_raw --sensor accel --axis x \
    --dwell 8 --out dwell
gyro_noise_excitation before_sweep after_sweep --sensor accel --axis y --sweep 5 10 0.5 \
    --topic /imu/data_raw --reference-topic /shaker/imu --out sweep
