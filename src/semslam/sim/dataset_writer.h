#pragma once
// Writes the synthetic city as a KITTI-layout dataset with its ground truth:
//
//   DIR/sequences/<seq>/image_0/%06d.png, image_1/   left / right, 8-bit grey
//   DIR/sequences/<seq>/label_0/%06d.png             Cityscapes trainIds of the left image, 255 = none
//   DIR/sequences/<seq>/depth_0/%06d.png             uint16, left camera z * 256, 0 = sky, clamped at 65535
//   DIR/sequences/<seq>/calib.txt, times.txt         P0..P3; 0.0, 0.1, ...
//   DIR/poses/<seq>.txt                              KITTI poses (world_from_camera, world = first camera)
//   DIR/oxts/data/%010d.txt, DIR/oxts/timestamps.txt KITTI raw GPS/IMU (see gps_sim.h)
//   DIR/landmarks.csv                                name,lat,lon,alt,category
//   DIR/scene.json                                   options, origin, epoch, enu_from_world, route, street
//                                                    graph, landmarks, objects and surfaces with classes
//
// Every file is written atomically; the same options give the same bytes.

#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <string>

#include "semslam/sim/synthetic_city.h"

namespace semslam::sim {

struct DatasetOptions {
  std::string sequence = "00";
  bool progress = true;  // progress lines on stderr
  int png_compression = 1;
  // An earlier synthetic dataset in the folder (its scene.json) is replaced only when set; a folder holding
  // anything else is never written into.
  bool overwrite = false;
  void Check() const;
};

// Throws InputError naming DIR when it cannot be created or written, InvalidArgument when it holds files
// (see `overwrite`). times.txt is written last: a dataset whose writer was stopped has none. Stops at an
// interruption (core/interrupt.h) and throws Interrupted.
void WriteDataset(const SyntheticCity& sim, const std::filesystem::path& out,
                  const DatasetOptions& options = {});

// Renders frame `frame` and writes its four images under `sequence_dir` (image_0, image_1, label_0, depth_0).
void WriteFrame(const SyntheticCity& sim, size_t frame, const std::filesystem::path& sequence_dir,
                int png_compression = 1);
// Writes rendered images of one frame.
void WriteFrameImages(const RenderedFrame& images, size_t frame, const std::filesystem::path& sequence_dir,
                      int png_compression = 1);

// The contents of scene.json and landmarks.csv.
std::string SceneJson(const SyntheticCity& sim);
std::string LandmarksCsv(const SyntheticCity& sim);

}  // namespace semslam::sim
