#pragma once
// The ratio of the units of a drive's two sides of a stretch without poses (a loss of tracking, after which a
// monocular map starts in units of its own), from the camera centres on each side, by the car's speed.

#include <optional>

#include "semslam/geometry/trajectory.h"

namespace semslam {

// One speed that changes linearly in time (a constant acceleration) fitted to both sides by least squares,
// with the ratio of their units as the third unknown: a car leaving a junction or braking for one does not
// keep its speed over a few seconds, but does keep its acceleration far better.
// `before` ends at the gap's start and `after` starts at its end, each in time order; each side needs three
// poses (two steps), of which only the camera centres count. Returns the length in the units before the gap
// of one unit after it; nullopt where the fit is undetermined (too few steps, standing still after the gap)
// or gives no positive ratio or speed.
std::optional<double> FitScaleAcrossGap(const Trajectory& before, const Trajectory& after);

}  // namespace semslam
