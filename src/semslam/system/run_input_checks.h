#pragma once
// Checks of a run's inputs made before its first frame, so that a run that cannot give the user anything
// useful says so at once instead of after every frame: paths that are not UTF-8, a GPS log without one usable
// fix or whose times miss the frames, landmarks far from where the GPS says the drive was.

#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "semslam/geo/gps.h"
#include "semslam/landmarks/catalogue.h"

namespace semslam {

// Throws InvalidArgument when `path` (made absolute) is not UTF-8; `what` names the option ("--sequence").
void RequireUtf8Argument(const std::filesystem::path& path, std::string_view what);

// Throws InputError naming the log when it holds no usable fix (every line was skipped, or none was there).
// Warns when no fix lies within the frames' time range (after GuessTimeOffset), so none can be used, and
// when both are clock times that do not overlap (GuessTimeOffset then assumes they start together).
void CheckGpsLog(const GpsLog& log, const std::vector<double>& frame_times);

// Warns about landmarks more than far_m from every GPS fix (a catalogue of another town, swapped latitude and
// longitude), naming them; and that landmarks are not placed at all without GPS. Returns how many are far.
size_t WarnAboutFarLandmarks(const std::vector<Landmark>& landmarks, const std::filesystem::path& file,
                             const std::optional<GpsLog>& gps, double far_m = 50e3);

// Great-circle distance on a sphere of the Earth's mean radius (metres); plenty for "how far away".
double HorizontalDistanceM(const Wgs84& a, const Wgs84& b);

}  // namespace semslam
