#pragma once
// Simulated GPS/IMU readings of the drive in KITTI raw's OXTS format: position of the left camera in WGS84
// (through the ENU frame of the town origin) with Gaussian noise, optional dropouts and outliers, the true
// attitude, velocities, accelerations (gravity included in az / au, as a real IMU measures) and angular
// rates.

#include <vector>

#include "semslam/io/kitti_raw.h"
#include "semslam/sim/synthetic_city.h"

namespace semslam::sim {

// One reading every options().gps.every frames (frame 0 always), stamped start_epoch + frame time. The
// random draws depend on the GPS seed and the frame only, so changing the dropout rate keeps the noise of
// the fixes that remain.
std::vector<StampedOxts> SimulateOxts(const SyntheticCity& sim);

// The frame a reading belongs to (its timestamp minus the start epoch, at the camera rate).
int OxtsFrame(const SyntheticCity& sim, const StampedOxts& reading);

}  // namespace semslam::sim
