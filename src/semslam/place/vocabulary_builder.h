#pragma once
// From image folders to a trained vocabulary: what `semslam vocab train` runs.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "semslam/features/orb_extractor.h"
#include "semslam/place/vocabulary.h"

namespace semslam {

// The images of the given folders, sorted by name within each folder (png, jpg, jpeg, pgm, ppm, bmp, tif,
// tiff). A folder without images directly in it is searched for a KITTI layout: DIR/image_0 or
// DIR/sequences/*/image_0. If max_images > 0 and there are more, that many are taken evenly spread.
// Throws InputError for a missing folder or one without images.
std::vector<std::filesystem::path> ListTrainingImages(const std::vector<std::filesystem::path>& folders,
                                                      size_t max_images = 0);

// ORB descriptors of each image (extracted in parallel over images). Throws InputError for an unreadable
// image. `progress(done, total)` is called from the calling thread now and then.
std::vector<std::vector<Descriptor>> ExtractTrainingDescriptors(
    const std::vector<std::filesystem::path>& images, const OrbOptions& orb,
    const std::function<void(size_t, size_t)>& progress = {});

// Descriptors of `count` procedurally drawn images (MakeSyntheticTrainingImage, seeds first_seed...) of the
// given size: a vocabulary that needs no data at all.
std::vector<std::vector<Descriptor>> ExtractProceduralDescriptors(
    size_t count, cv::Size size, const OrbOptions& orb, std::uint64_t first_seed = 1,
    const std::function<void(size_t, size_t)>& progress = {});

}  // namespace semslam
