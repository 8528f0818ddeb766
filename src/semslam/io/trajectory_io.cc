#include "semslam/io/trajectory_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/text_reader.h"
#include "semslam/geometry/rigid3.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

// A quaternion whose norm is further than this from 1 is an error (columns swapped, a wrong format);
// smaller deviations (rounding in text files) are normalized away.
constexpr double kQuaternionNormTolerance = 1e-2;

constexpr const char* kTumFields[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
constexpr const char* kKittiFields[12] = {"r00", "r01", "r02", "tx",  "r10", "r11",
                                          "r12", "ty",  "r20", "r21", "r22", "tz"};

bool IsDataLine(std::string_view line) {
  const std::string_view trimmed = Trim(line);
  return !trimmed.empty() && trimmed.front() != '#';
}

// Whitespace (and, for files written by other tools, commas) separate the columns.
std::vector<std::string_view> Columns(std::string_view line) { return SplitTokens(line, " \t\r,"); }

void RequireColumns(const std::vector<std::string_view>& tokens, size_t expected, const SourceLocation& where,
                    std::string_view format) {
  if (tokens.size() != expected) {
    throw InputError(
        where, "columns",
        fmt::format("expected {} numbers per line ({}), found {}", expected, format, tokens.size()));
  }
}

Rigid3d ParseKittiPose(const std::vector<std::string_view>& tokens, const SourceLocation& where) {
  RequireColumns(tokens, 12, where, "KITTI pose: row-major 3x4 [R|t]");
  Eigen::Matrix3x4d m;
  for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = ParseDouble(tokens[i], where, kKittiFields[i]);
  if (const auto defect = RotationDefect(m.leftCols<3>()))
    throw InputError(where, "r00..r22", "rotation is " + *defect);
  return Rigid3d::FromMatrix(m);
}

std::string FormatKittiPose(const Rigid3d& pose) {
  const Eigen::Matrix3x4d m = pose.ToMatrix();
  std::string line;
  for (int i = 0; i < 12; ++i) {
    if (i > 0) line += ' ';
    line += fmt::format("{:.12e}", m(i / 4, i % 4));
  }
  line += '\n';
  return line;
}

}  // namespace

Trajectory ReadTumTrajectory(const fs::path& path) {
  TextReader reader(path);
  Trajectory trajectory;
  while (const auto line = reader.NextLine()) {
    if (!IsDataLine(*line)) continue;
    const SourceLocation where = reader.Where();
    const auto tokens = Columns(*line);
    RequireColumns(tokens, 8, where, "TUM: timestamp tx ty tz qx qy qz qw");
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = ParseDouble(tokens[i], where, kTumFields[i]);
    if (!trajectory.empty() && !(v[0] > trajectory.back().timestamp)) {
      throw InputError(where, "timestamp",
                       fmt::format("timestamps must increase: {} follows {}", tokens[0],
                                   fmt::format("{:.9f}", trajectory.back().timestamp)));
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
      throw InputError(where, "qx qy qz qw", fmt::format("quaternion has norm {:.6g}, expected 1", norm));
    }
    trajectory.push_back({v[0], Rigid3d(q.normalized(), Eigen::Vector3d(v[1], v[2], v[3]))});
  }
  return trajectory;
}

void WriteTumTrajectory(const fs::path& path, const Trajectory& trajectory) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& pose : trajectory) {
    const Eigen::Quaterniond& q = pose.world_from_camera.rotation;
    const Eigen::Vector3d& t = pose.world_from_camera.translation;
    text += fmt::format("{:.9f} {:.9f} {:.9f} {:.9f} {:.12f} {:.12f} {:.12f} {:.12f}\n", pose.timestamp,
                        t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  }
  WriteFileAtomically(path, text);
}

std::vector<Rigid3d> ReadKittiPoses(const fs::path& path) {
  TextReader reader(path);
  std::vector<Rigid3d> poses;
  while (const auto line = reader.NextLine()) {
    if (!IsDataLine(*line)) continue;
    poses.push_back(ParseKittiPose(Columns(*line), reader.Where()));
  }
  return poses;
}

size_t CountKittiPoses(const fs::path& path) {
  TextReader reader(path);
  size_t count = 0;
  while (const auto line = reader.NextLine()) count += IsDataLine(*line) ? 1 : 0;
  return count;
}

void WriteKittiPoses(const fs::path& path, const std::vector<Rigid3d>& world_from_camera) {
  std::string text;
  text.reserve(world_from_camera.size() * 12 * 20);
  for (const Rigid3d& pose : world_from_camera) text += FormatKittiPose(pose);
  WriteFileAtomically(path, text);
}

void WriteKittiPoses(const fs::path& path, const Trajectory& trajectory) {
  std::string text;
  text.reserve(trajectory.size() * 12 * 20);
  for (const StampedPose& pose : trajectory) text += FormatKittiPose(pose.world_from_camera);
  WriteFileAtomically(path, text);
}

std::vector<double> ReadTimes(const fs::path& path) {
  TextReader reader(path);
  std::vector<double> times;
  while (const auto line = reader.NextLine()) {
    if (!IsDataLine(*line)) continue;
    const SourceLocation where = reader.Where();
    const auto tokens = SplitTokens(*line);
    if (tokens.size() != 1) {
      throw InputError(where, "timestamp",
                       fmt::format("expected one timestamp per line, found {} values", tokens.size()));
    }
    const double t = ParseDouble(tokens[0], where, "timestamp");
    if (!times.empty() && !(t > times.back())) {
      throw InputError(where, "timestamp",
                       fmt::format("timestamps must increase: {} follows {:.9f}", tokens[0], times.back()));
    }
    times.push_back(t);
  }
  return times;
}

void WriteTimes(const fs::path& path, const std::vector<double>& timestamps) {
  std::string text;
  text.reserve(timestamps.size() * 24);
  for (const double t : timestamps) text += fmt::format("{:.9f}\n", t);
  WriteFileAtomically(path, text);
}

void DenseTrajectoryOptions::Check() const {
  Require(max_predicted_frames >= 0, "max_predicted_frames must not be negative");
  Require(max_velocity_bridge_frames >= 0, "max_velocity_bridge_frames must not be negative");
}

size_t DenseTrajectory::Count(PoseSource what) const {
  return static_cast<size_t>(std::count(source.begin(), source.end(), what));
}

namespace {

// When each frame of a dense trajectory was taken: its timestamp, or its index when none are given (frames
// evenly spaced). Frames dropped by the camera show as a jump in time, which the motion carries over.
class FrameClock {
 public:
  FrameClock(size_t first_frame, std::span<const double> times) : first_(first_frame), times_(times) {}
  double operator()(size_t frame) const {
    return times_.empty() ? static_cast<double>(frame) : times_[frame - first_];
  }

 private:
  size_t first_;
  std::span<const double> times_;
};

// The motion per clock unit, as a twist of camera_earlier_from_camera_later, between two estimated frames.
Eigen::Vector6d Velocity(const IndexedPose& earlier, const IndexedPose& later, const FrameClock& clock) {
  const double elapsed = clock(later.frame_index) - clock(earlier.frame_index);
  return (earlier.world_from_camera.Inverse() * later.world_from_camera).Log() / elapsed;
}

// A gap between the estimated frames `start` and `end`. The motion over it is taken to change steadily: the
// twist varies linearly in time, from the velocity of the step into the gap (taken at that step's middle) to the
// velocity of the step out of it; without a neighbour outside the gap, or over a long gap, an end takes the gap's
// own mean motion (at the gap's middle). A turn that eases out within the gap does not fit that line: carried
// from the turning end, the motion turns on long after the car has stopped turning, and over the synthetic city's
// 2 s black-out at a corner's end the bridge strayed 0.66 m. So a bump that vanishes at both ends (6 s (1 - s)
// over the gap's share s) adds the constant twist that makes the motion carried from the start reach the end.
// The bridge still leaves each end at that end's velocity, and is exact for steady motion (a turn included) and
// for a steadily accelerating drive, where the bump is nil. The motion is carried from each end into the gap,
// and the two, which then agree, are blended by nearness in time.
class GapBridge {
 public:
  GapBridge(const IndexedPose& start, const IndexedPose& end, const IndexedPose* before_start,
            const IndexedPose* after_end, bool use_end_velocities, const FrameClock& clock)
      : start_(start), end_(end), duration_(clock(end.frame_index) - clock(start.frame_index)) {
    const TimedVelocity mean{0.5 * duration_, Velocity(start, end, clock)};
    start_velocity_ = end_velocity_ = mean;
    if (use_end_velocities && before_start != nullptr) {
      start_velocity_ = {-0.5 * (clock(start.frame_index) - clock(before_start->frame_index)),
                         Velocity(*before_start, start, clock)};
    }
    if (use_end_velocities && after_end != nullptr) {
      end_velocity_ = {duration_ + 0.5 * (clock(after_end->frame_index) - clock(end.frame_index)),
                       Velocity(end, *after_end, clock)};
    }
    // The bump's twist, by fixed-point steps on what the carried motion misses of the ends' relative pose. Each
    // step cuts the miss about five times at the turns of a drive; should one not (a gap turning half a circle),
    // the bump stays as it was and the blend spreads the rest.
    if (!(duration_ > 0.0)) return;
    const Rigid3d start_to_end = start_.world_from_camera.Inverse() * end_.world_from_camera;
    double last_miss = std::numeric_limits<double>::infinity();
    Eigen::Vector6d last_step = Eigen::Vector6d::Zero();
    for (int step = 0; step < 10; ++step) {
      const Eigen::Vector6d miss = (Motion(0.0, duration_).Inverse() * start_to_end).Log();
      if (miss.norm() >= last_miss) {
        bump_twist_ -= last_step;
        break;
      }
      if (miss.norm() < 1e-9) break;
      last_miss = miss.norm();
      last_step = miss / duration_;
      bump_twist_ += last_step;
    }
  }

  // `since_start`: the frame's time after the start's.
  Rigid3d WorldFromCamera(double since_start) const {
    const Rigid3d from_start_side = start_.world_from_camera * Motion(0.0, since_start);
    const Rigid3d from_end_side = end_.world_from_camera * Motion(since_start, duration_).Inverse();
    return Interpolate(from_start_side, from_end_side, since_start / duration_);
  }

 private:
  struct TimedVelocity {
    double time = 0.0;  // after the start's
    Eigen::Vector6d twist = Eigen::Vector6d::Zero();
  };

  Eigen::Vector6d VelocityAt(double time) const {
    const double share = time / duration_;
    const Eigen::Vector6d bump = bump_twist_ * (6.0 * share * (1.0 - share));
    const double span = end_velocity_.time - start_velocity_.time;
    if (!(span > 0.0)) return start_velocity_.twist + bump;  // both ends take the mean motion
    return start_velocity_.twist +
           (end_velocity_.twist - start_velocity_.twist) * ((time - start_velocity_.time) / span) + bump;
  }

  // camera_at_a_from_camera_at_b, integrated in short steps at their middle's velocity: exact while the
  // twists commute (a steady turn, a straight drive), and close to it over the short gaps bridged this way.
  Rigid3d Motion(double a, double b) const {
    constexpr double kStepsPerGap = 64.0;
    const int steps = std::max(1, static_cast<int>(std::ceil(kStepsPerGap * (b - a) / duration_)));
    const double step = (b - a) / steps;
    Rigid3d motion;
    for (int i = 0; i < steps; ++i) motion = motion * Rigid3d::Exp(VelocityAt(a + (i + 0.5) * step) * step);
    return motion;
  }

  const IndexedPose& start_;
  const IndexedPose& end_;
  double duration_;
  TimedVelocity start_velocity_;
  TimedVelocity end_velocity_;
  Eigen::Vector6d bump_twist_ = Eigen::Vector6d::Zero();  // per clock unit, at the bump's mean
};

}  // namespace

DenseTrajectory FillFrameGaps(const std::vector<IndexedPose>& estimated, size_t first_frame, size_t end_frame,
                              const DenseTrajectoryOptions& options, std::span<const double> times) {
  options.Check();
  Require(first_frame <= end_frame,
          fmt::format("frames {}:{}: the range ends before it starts", first_frame, end_frame));
  for (size_t i = 1; i < estimated.size(); ++i) {
    Require(estimated[i].frame_index > estimated[i - 1].frame_index,
            "estimated poses must be in strictly increasing frame order");
  }
  const size_t n = end_frame - first_frame;
  Require(times.empty() || times.size() == n,
          fmt::format("{} timestamps for the {} frames {}:{}", times.size(), n, first_frame, end_frame));
  for (size_t i = 1; i < times.size(); ++i) {
    Require(times[i] > times[i - 1], fmt::format("timestamps must increase (frame {})", first_frame + i));
  }
  const FrameClock clock(first_frame, times);
  DenseTrajectory dense;
  dense.first_frame = first_frame;
  dense.world_from_camera.resize(n);
  dense.source.assign(n, PoseSource::kNone);
  std::vector<const IndexedPose*> in_range;
  for (const IndexedPose& pose : estimated) {
    if (pose.frame_index >= first_frame && pose.frame_index < end_frame) in_range.push_back(&pose);
  }
  if (in_range.empty()) return dense;  // identities: nothing better is known

  const auto max_predicted = static_cast<size_t>(options.max_predicted_frames);
  size_t next = 0;                    // the next estimated pose in in_range
  const IndexedPose* last = nullptr;  // the last estimated pose before frame i
  const IndexedPose* before_last = nullptr;
  std::optional<GapBridge> bridge;  // set while frame i lies between two estimated frames
  for (size_t i = 0; i < n; ++i) {
    const size_t frame = first_frame + i;
    if (next < in_range.size() && in_range[next]->frame_index == frame) {
      before_last = last;
      last = in_range[next++];
      bridge.reset();
      dense.world_from_camera[i] = last->world_from_camera;
      dense.source[i] = PoseSource::kEstimated;
      continue;
    }
    if (last == nullptr) {
      dense.world_from_camera[i] = in_range.front()->world_from_camera;
      dense.source[i] = PoseSource::kFirstPose;
      continue;
    }
    if (next < in_range.size()) {
      if (!bridge) {
        const IndexedPose& gap_end = *in_range[next];
        const IndexedPose* after_end = next + 1 < in_range.size() ? in_range[next + 1] : nullptr;
        const size_t gap = gap_end.frame_index - last->frame_index - 1;
        bridge.emplace(*last, gap_end, before_last, after_end,
                       gap <= static_cast<size_t>(options.max_velocity_bridge_frames), clock);
      }
      dense.world_from_camera[i] = bridge->WorldFromCamera(clock(frame) - clock(last->frame_index));
      dense.source[i] = PoseSource::kInterpolated;
      continue;
    }
    // After the last estimated frame, the tracker's motion model: the last step's motion, per frame (or second),
    // carried on to each frame up to max_predicted_frames after it; then held.
    const size_t since = frame - last->frame_index;
    const size_t horizon = last->frame_index + std::min(since, max_predicted);
    dense.world_from_camera[i] =
        before_last == nullptr
            ? last->world_from_camera
            : last->world_from_camera *
                  Rigid3d::Exp(Velocity(*before_last, *last, clock) * (clock(horizon) - clock(last->frame_index)));
    dense.source[i] = before_last != nullptr && since <= max_predicted ? PoseSource::kMotionModel : PoseSource::kHeld;
  }
  return dense;
}

TrajectoryFormat DetectTrajectoryFormat(const fs::path& path) {
  TextReader reader(path);
  while (const auto line = reader.NextLine()) {
    if (!IsDataLine(*line)) continue;
    const size_t columns = Columns(*line).size();
    if (columns == 8) return TrajectoryFormat::kTum;
    if (columns == 12) return TrajectoryFormat::kKitti;
    throw InputError(
        reader.Where(), "columns",
        fmt::format("found {} numbers; a trajectory line has 8 (TUM: timestamp tx ty tz qx qy qz qw) "
                    "or 12 (KITTI: row-major 3x4 [R|t])",
                    columns));
  }
  throw InputError(path, "no poses in the file: cannot tell TUM (8 columns) from KITTI (12 columns)");
}

Trajectory ReadTrajectory(const fs::path& path, const std::optional<fs::path>& times) {
  if (DetectTrajectoryFormat(path) == TrajectoryFormat::kTum) return ReadTumTrajectory(path);
  const std::vector<Rigid3d> poses = ReadKittiPoses(path);
  std::vector<double> stamps;
  if (times) {
    stamps = ReadTimes(*times);
    if (stamps.size() < poses.size()) {
      throw InputError(*times, fmt::format("lists {} timestamps, fewer than the {} poses in {}",
                                           stamps.size(), poses.size(), path.string()));
    }
  }
  Trajectory trajectory;
  trajectory.reserve(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    trajectory.push_back({times ? stamps[i] : static_cast<double>(i), poses[i]});
  }
  return trajectory;
}

}  // namespace semslam
