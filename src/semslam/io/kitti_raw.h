#pragma once
// KITTI raw drives: image_0x/data/%010d.png with timestamps.txt, oxts/data/%010d.txt (30 fields) with
// timestamps.txt, and the date's calib_cam_to_cam.txt, calib_imu_to_velo.txt, calib_velo_to_cam.txt.

#include <array>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/geometry/eigen_types.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/io/sequence.h"

namespace semslam {

// One OXTS reading, in the field order of KITTI's dataformat.txt.
struct OxtsRecord {
  double lat = 0, lon = 0, alt = 0;                       // deg, deg, m
  double roll = 0, pitch = 0, yaw = 0;                    // rad
  double vn = 0, ve = 0, vf = 0, vl = 0, vu = 0;          // m/s (north, east, forward, left, up)
  double ax = 0, ay = 0, az = 0, af = 0, al = 0, au = 0;  // m/s^2
  double wx = 0, wy = 0, wz = 0, wf = 0, wl = 0, wu = 0;  // rad/s
  double pos_accuracy = 0, vel_accuracy = 0;              // m, m/s
  int navstat = 0, numsats = 0, posmode = 0, velmode = 0, orimode = 0;

  static constexpr int kNumFields = 30;
};

// Parses one oxts line of 30 whitespace-separated values.
OxtsRecord ParseOxtsLine(const std::string& line, const SourceLocation& where);
std::string FormatOxtsLine(const OxtsRecord& record);

// KITTI raw timestamps ("2011-09-26 13:02:25.964389445") as seconds since the Unix epoch (UTC).
std::vector<double> ReadKittiRawTimestamps(const std::filesystem::path& path);
void WriteKittiRawTimestamps(const std::filesystem::path& path, const std::vector<double>& unix_seconds);

struct StampedOxts {
  double timestamp = 0.0;  // seconds since the Unix epoch
  OxtsRecord record;
};
// Reads oxts_dir/timestamps.txt and oxts_dir/data/%010d.txt. A missing data file is an error.
std::vector<StampedOxts> ReadOxtsFolder(const std::filesystem::path& oxts_dir);
void WriteOxtsFolder(const std::filesystem::path& oxts_dir, const std::vector<StampedOxts>& readings);

// calib_cam_to_cam.txt (K_0x, D_0x, R_0x, T_0x, S_rect_0x, R_rect_0x, P_rect_0x, ...): every key as its
// numbers.
struct KittiRawCalibFile {
  std::map<std::string, std::vector<double>> values;
  // The numbers under `key`, requiring exactly `count` of them; throws InputError naming the file and key.
  std::vector<double> Get(const std::string& key, size_t count) const;
  // The 9 numbers under `key` as a row-major rotation; throws InputError naming the file, line and key for a
  // matrix that is not orthonormal or is a reflection.
  Eigen::Matrix3d GetRotation(const std::string& key) const;
  std::filesystem::path file;
  std::map<std::string, int> lines;  // the line of each key, for error messages
};
KittiRawCalibFile ReadKittiRawCalibFile(const std::filesystem::path& path);

// Rigid transforms from calib_imu_to_velo.txt / calib_velo_to_cam.txt (R: 9 numbers, T: 3).
Rigid3d ReadKittiRawRigid(const std::filesystem::path& path);  // velo_from_imu or cam_from_velo

// `file_name` (calib_cam_to_cam.txt, calib_imu_to_velo.txt, calib_velo_to_cam.txt) in the drive folder or its
// parent (KITTI's date folder). Throws InputError naming both places when it is in neither.
std::filesystem::path FindKittiRawCalibFile(const std::filesystem::path& drive_dir,
                                            const std::string& file_name);
// The rectified camera `camera_index` (0..3) from the OXTS (IMU) frame:
// [I | t] * R_rect_00 * cam0_from_velo * velo_from_imu, where t is the camera's offset in P_rect_0<index>
// = K [I | t] (the rectified cameras share R_rect_00's orientation).
Rigid3d ReadKittiRawRectifiedCameraFromImu(const std::filesystem::path& drive_dir, int camera_index);
inline Rigid3d ReadKittiRawRectifiedCam0FromImu(const std::filesystem::path& drive_dir) {
  return ReadKittiRawRectifiedCameraFromImu(drive_dir, 0);
}

// The rectified camera `camera_index` (0..3) from the Velodyne frame: [I | t] * R_rect_00 * cam0_from_velo
// (project with the camera's intrinsics from P_rect_0<index>).
Rigid3d ReadKittiRawRectifiedCameraFromVelo(const std::filesystem::path& drive_dir, int camera_index);

// A Velodyne scan (velodyne_points/data/%010d.bin): float32 x y z reflectance per point, x forward, y left,
// z up, metres. Throws InputError naming the file when it is missing, empty of points, not a whole number of
// points, or holds a non-finite value.
struct VelodynePoint {
  Eigen::Vector3d position;
  float reflectance = 0.0f;
};
std::vector<VelodynePoint> ReadVelodyneScan(const std::filesystem::path& path);

// The pose of an OXTS reading as KITTI's raw devkit computes it (convertOxtsToPose): position from a
// Mercator projection scaled by cos(latitude of the first reading) (x east, y north, metres on a sphere of
// radius 6378137 m) and the altitude as z; attitude R = Rz(yaw) Ry(pitch) Rx(roll). The pose maps the IMU
// frame (x forward, y left, z up) into that world.
double OxtsMercatorScale(double first_latitude_deg);
Rigid3d OxtsWorldFromImu(const OxtsRecord& record, double mercator_scale);
// Camera poses from OXTS readings: world_from_camera per reading, for the camera rigidly mounted as
// `camera_from_imu`, expressed in the first reading's camera frame (the first pose is the identity), as
// KITTI odometry poses are. Empty for no readings.
std::vector<Rigid3d> OxtsCameraPoses(const std::vector<OxtsRecord>& records, const Rigid3d& camera_from_imu);

// Opens a KITTI raw drive folder (<date>_drive_XXXX_sync/) with the camera `options` chooses (image_00 by
// default): image_0X/data/%010d.png with image_0X/timestamps.txt (Unix seconds), stereo with the pair's right
// camera (image_01 for image_00, image_03 for image_02) when its data/ folder is there; camera from P_rect_0X
// and S_rect_0X of calib_cam_to_cam.txt, baseline from the pair's P_rect offsets. A colour camera
// (image_02/03) reads as grey with LoadImage and as BGR with LoadColorImage. Ground truth, when oxts/ is
// there: OxtsCameraPoses of the chosen camera, frame i from oxts record i (the synced drives record them in
// step), timestamps from the camera.
std::unique_ptr<ImageSequence> OpenKittiRaw(const std::filesystem::path& drive_dir,
                                            const SequenceOptions& options = {});

}  // namespace semslam
