"""Free-gyro drift: calibration of the drift rate from calibration series (seed 000), drift
correction of free-gyro surveys with in-run/out-run QC, and Allan-variance noise analysis
with the compassing dwell it implies (DOMAIN.md §4)."""
