// Segmenter backends: ENet on a real KITTI frame, a tiny ONNX network, model cards, label and probability
// files, the ground-truth noise model, and the spec factory.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/dnn_segmenter.h"
#include "semslam/semantics/label_image_segmenter.h"
#include "semslam/semantics/model_card.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/semantics/semantic_outputs.h"
#include "support/test_support.h"

namespace semslam {
namespace {

const std::filesystem::path kTestData = SEMSLAM_SEMANTICS_TEST_DATA;
const std::filesystem::path kModels = SEMSLAM_MODELS_DIR;

// Share of each class among the pixels of a band of rows.
std::vector<double> ClassShares(const cv::Mat& labels, int row_begin, int row_end) {
  const ClassCounts counts = CountLabels(labels.rowRange(row_begin, row_end));
  double total = 0.0;
  for (auto c : counts) total += static_cast<double>(c);
  std::vector<double> shares;
  for (auto c : counts) shares.push_back(static_cast<double>(c) / total);
  return shares;
}

int Dominant(const std::vector<double>& shares) {
  return static_cast<int>(std::max_element(shares.begin(), shares.begin() + kNumClasses) - shares.begin());
}

TEST(ModelCard, EnetCardInTheRepositoryMatchesTheBuiltInOne) {
  const ModelCard card = ReadModelCard(kModels / "enet-cityscapes.yaml");
  const ModelCard built_in = EnetCityscapesCard(card.file);
  EXPECT_EQ(card.name, "enet-cityscapes");
  EXPECT_EQ(card.ResolvedFormat(), ModelCard::Format::kTorch);
  EXPECT_EQ(card.input_width, 1024);
  EXPECT_EQ(card.input_height, 512);
  EXPECT_TRUE(card.fixed_size);
  EXPECT_TRUE(card.rgb);
  EXPECT_DOUBLE_EQ(card.scale, built_in.scale);
  EXPECT_EQ(card.mean, built_in.mean);
  EXPECT_EQ(card.stddev, built_in.stddev);
  EXPECT_EQ(card.channel_to_train_id, built_in.channel_to_train_id);
  EXPECT_EQ(card.scores, ScoreKind::kLogits);
  // Unless SEMSLAM_SHARED_DATA says otherwise, the weights are read in place from ../shared/data.
  if (std::getenv("SEMSLAM_SHARED_DATA") == nullptr) {
    EXPECT_EQ(card.file.filename(), "enet-model.net");
    EXPECT_EQ(card.file.parent_path().filename(), "enet_cityscapes_torch");
    EXPECT_EQ(card.file.parent_path().parent_path().filename(), "data");
  }
}

TEST(ModelCard, ParsesFieldsAndReportsErrorsWithLines) {
  const std::string yaml =
      "name: x\nfile: ${SEMSLAM_TEST_UNSET_VARIABLE:-weights}/net.onnx\n"
      "input: {channel_order: bgr, mean: 127.5, std: [1, 2, 3], fixed: false, size_divisor: 8}\n"
      "output: {layout: nhwc, scores: probabilities, classes: [car, 0, none, Sky]}\n";
  const ModelCard card = ParseModelCard(yaml, "/models", "/models/x.yaml");
  EXPECT_EQ(card.file, std::filesystem::path("/models/weights/net.onnx"));
  EXPECT_EQ(card.ResolvedFormat(), ModelCard::Format::kOnnx);
  EXPECT_FALSE(card.rgb);
  EXPECT_EQ(card.mean, (std::array<double, 3>{127.5, 127.5, 127.5}));
  EXPECT_EQ(card.stddev, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(card.size_divisor, 8);
  EXPECT_EQ(card.layout, ModelCard::Layout::kNhwc);
  EXPECT_EQ(card.scores, ScoreKind::kProbabilities);
  EXPECT_EQ(card.channel_to_train_id, (std::vector<std::uint8_t>{13, 0, kNoLabel, 10}));

  try {
    ParseModelCard("file: a.onnx\noutput:\n  classes: [road, caravan]\n", "/m", "/m/bad.yaml");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 3);
    EXPECT_NE(std::string(e.what()).find("caravan"), std::string::npos);
  }
  EXPECT_THROW(ParseModelCard("name: no file\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ParseModelCard("file: a.onnx\ninput: {std: [1, 0, 1]}\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ParseModelCard("file: a.onnx\ninput: {fixed: true}\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ParseModelCard("file: [unclosed\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_EQ(ParseModelCard("file: a.onnx\ninput: {width: 4, height: 2, fixed: true, resize: tile}\n", "/m",
                           "/m/c.yaml")
                .resize,
            ModelCard::Resize::kTile);
  EXPECT_THROW(ParseModelCard("file: a.onnx\ninput: {resize: tile}\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ParseModelCard("file: a.onnx\ninput: {resize: crop}\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ReadModelCard("/nonexistent/card.yaml"), InputError);
  EXPECT_THROW(DnnSegmenter(EnetCityscapesCard("/nonexistent/enet.net")), InputError);
}

TEST(DnnSegmenter, TinyOnnxNetworkFollowsTheCard) {
  DnnSegmenter segmenter(ReadModelCard(kTestData / "tiny_segnet.yaml"));
  // 32x16 BGR image: red left quarter, green, blue, and black right quarter.
  cv::Mat image(16, 32, CV_8UC3, cv::Scalar(0, 0, 0));
  image.colRange(0, 8).setTo(cv::Scalar(0, 0, 255));
  image.colRange(8, 16).setTo(cv::Scalar(0, 255, 0));
  image.colRange(16, 24).setTo(cv::Scalar(255, 0, 0));
  EXPECT_EQ(segmenter.NetworkInputSize(image.size()), cv::Size(16, 8));
  const Segmentation s = segmenter.Segment(image);
  EXPECT_EQ(s.input_size(), cv::Size(32, 16));
  EXPECT_EQ(s.storage_size(), cv::Size(16, 8));
  EXPECT_EQ(s.LabelAt(3, 8), 0);    // red -> road (so the card's RGB order was applied)
  EXPECT_EQ(s.LabelAt(12, 8), 13);  // green -> car
  EXPECT_EQ(s.LabelAt(20, 2), 10);  // blue -> sky
  // Red: normalized (1, -1, -1), logits (0, 4, -4, -4): softmax road = e^4 / (1 + e^4 + 2 e^-4) = 0.98137,
  // plus the unlabeled share 0.017974 / 19.
  ClassLogProbs p;
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(0, 0), &p));
  EXPECT_NEAR(std::exp(p[0]), 0.98137 + 0.017974 / 19, 2e-4);
  // Black: logits (0, -4, -4, -4): 'unlabeled' (0.948) outweighs every class: no label, no observation.
  EXPECT_FALSE(s.Sample(Eigen::Vector2d(30, 8), &p));
  EXPECT_EQ(s.LabelAt(30, 8), kNoLabel);
  EXPECT_EQ(s.Labels().at<std::uint8_t>(4, 15), kNoLabel);
  EXPECT_EQ(s.Confidence().at<float>(4, 15), 0.0f);
  EXPECT_EQ(s.Compacted().LabelAt(30, 8), kNoLabel);

  // Grey input goes in as three equal channels.
  const Segmentation grey = segmenter.Segment(cv::Mat(16, 32, CV_8UC1, cv::Scalar(255)));
  EXPECT_EQ(grey.input_size(), cv::Size(32, 16));
  const cv::Mat blob = segmenter.Preprocess(cv::Mat(16, 32, CV_8UC1, cv::Scalar(255)));
  ASSERT_EQ(blob.dims, 4);
  EXPECT_EQ(blob.size[1], 3);
  EXPECT_NEAR(blob.ptr<float>()[0], 1.0f, 1e-6);  // (255/255 - 0.5) / 0.5
  EXPECT_THROW(segmenter.Segment(cv::Mat()), InvalidArgument);
}

TEST(DnnSegmenter, FreeInputSizeAndNhwcMismatchErrors) {
  ModelCard card = ReadModelCard(kTestData / "tiny_segnet.yaml");
  card.fixed_size = false;
  card.input_width = card.input_height = 0;
  card.size_divisor = 4;
  DnnSegmenter segmenter(card);
  cv::Mat image(10, 21, CV_8UC3, cv::Scalar(255, 0, 0));
  EXPECT_EQ(segmenter.NetworkInputSize(image.size()), cv::Size(20, 12));
  const Segmentation s = segmenter.Segment(image);
  EXPECT_EQ(s.storage_size(), cv::Size(20, 12));
  EXPECT_EQ(s.input_size(), cv::Size(21, 10));
  EXPECT_EQ(s.LabelAt(20, 9), 10);

  card.channel_to_train_id = {0, 1, 2};  // the network has 4 channels
  DnnSegmenter wrong(card);
  EXPECT_THROW(wrong.Segment(image), InputError);
}

// resize: tile keeps the aspect ratio: a 64x16 image is scaled to 32x8 and run as two 16x8 windows.
TEST(DnnSegmenter, TiledWindowsKeepTheAspectRatio) {
  ModelCard card = ReadModelCard(kTestData / "tiny_segnet.yaml");
  card.resize = ModelCard::Resize::kTile;
  DnnSegmenter segmenter(card);
  EXPECT_NE(segmenter.Describe().find("tiled"), std::string::npos);
  cv::Mat image(16, 64, CV_8UC3, cv::Scalar(0, 0, 255));  // red: road
  image.colRange(40, 64).setTo(cv::Scalar(255, 0, 0));    // blue: sky
  const Segmentation s = segmenter.Segment(image);
  EXPECT_EQ(s.input_size(), cv::Size(64, 16));
  EXPECT_EQ(s.storage_size(), cv::Size(32, 8));
  EXPECT_EQ(s.LabelAt(2, 8), 0);
  EXPECT_EQ(s.LabelAt(36, 8), 0);
  EXPECT_EQ(s.LabelAt(44, 8), 10);
  EXPECT_EQ(s.LabelAt(63, 15), 10);
  // Overlapping windows (40x16 -> 20x8, windows at 0 and 4) average to the same probabilities.
  const Segmentation o = segmenter.Segment(cv::Mat(16, 40, CV_8UC3, cv::Scalar(0, 0, 255)));
  ClassLogProbs p;
  ASSERT_TRUE(o.Sample(Eigen::Vector2d(10, 8), &p));
  EXPECT_NEAR(std::exp(p[0]), 0.98137 + 0.017974 / 19, 2e-4);
  // Narrower than the network: plain stretch.
  EXPECT_EQ(segmenter.Segment(cv::Mat(16, 24, CV_8UC3, cv::Scalar(0, 0, 255))).storage_size(),
            cv::Size(16, 8));
}

TEST(DnnSegmenter, EnetOnKittiFrame) {
  SEMSLAM_REQUIRE_SHARED_DATA(enet_dir, "enet_cityscapes_torch");
  SEMSLAM_REQUIRE_SHARED_DATA(kitti, "kitti_odom_07_3dv");
  const cv::Mat image =
      cv::imread((kitti / "sequences/07/image_0/000050.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  auto segmenter = MakeSegmenter("enet:" + (enet_dir / "enet-model.net").string() + ",threads=2");
  ASSERT_NE(segmenter, nullptr);
  const Segmentation s = segmenter->Segment(image);
  EXPECT_EQ(s.input_size(), image.size());
  EXPECT_EQ(s.storage_size(), cv::Size(1024, 512));
  const cv::Mat labels = s.LabelsAtInputSize();
  const int rows = labels.rows;
  const auto bottom = ClassShares(labels, rows * 4 / 5, rows);
  const auto top = ClassShares(labels, 0, rows / 5);
  std::cout << "ENet on KITTI 07 frame 50: bottom fifth road " << bottom[0] << ", top fifth building "
            << top[2] << ", sky " << top[10] << ", vegetation " << top[8] << "\n";
  EXPECT_EQ(Dominant(bottom), TrainId(SemanticClass::kRoad));
  EXPECT_GT(bottom[0], 0.4);
  const int top_class = Dominant(top);
  EXPECT_TRUE(top_class == TrainId(SemanticClass::kBuilding) || top_class == TrainId(SemanticClass::kSky))
      << ClassName(top_class);
}

// Writes a NumPy .npy file of float32 (H, W, C).
void WriteNpy(const std::filesystem::path& path, const std::vector<float>& values, int h, int w, int c) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(h) + ", " +
                       std::to_string(w) + ", " + std::to_string(c) + "), }";
  while ((10 + header.size() + 1) % 64 != 0) header.push_back(' ');
  header.push_back('\n');
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const std::uint16_t len = static_cast<std::uint16_t>(header.size());
  out.write(reinterpret_cast<const char*>(&len), 2);
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * 4));
}

TEST(LabelImageSegmenter, LabelIdsTrainIdsAndProbabilities) {
  testing::TempDir dir;
  // Cityscapes labelIds: road 7, car 26, parking 9 (not evaluated), sky 23.
  const cv::Mat label_ids = (cv::Mat_<std::uint8_t>(2, 4) << 7, 7, 26, 26, 9, 23, 23, 0);
  ASSERT_TRUE(cv::imwrite((dir / "000003.png").string(), label_ids));
  const cv::Mat image(4, 8, CV_8UC1, cv::Scalar(0));  // frames at twice the label resolution

  auto by_label_ids = MakeSegmenter("labels:" + dir.path().string() + ",ids=label,alpha=0.7");
  EXPECT_FALSE(by_label_ids->NeedsImage());
  EXPECT_TRUE(by_label_ids->NeedsFrameIndex());
  const Segmentation s = by_label_ids->Segment(image, 3);
  EXPECT_EQ(s.input_size(), cv::Size(8, 4));
  EXPECT_EQ(s.LabelAt(0, 0), 0);
  EXPECT_EQ(s.LabelAt(5, 0), 13);
  EXPECT_EQ(s.LabelAt(0, 3), kNoLabel);
  EXPECT_EQ(s.LabelAt(3, 3), 10);
  EXPECT_FLOAT_EQ(s.alpha(), 0.7f);
  EXPECT_THROW(by_label_ids->Segment(image, 4), InputError);  // no file for frame 4

  // The same file read as trainIds: 7 is traffic sign, 26 is not a class.
  auto by_train_ids = MakeSegmenter("labels:" + dir.path().string());
  const Segmentation t = by_train_ids->Segment(cv::Mat(), 3);
  EXPECT_EQ(t.input_size(), cv::Size(4, 2));
  EXPECT_EQ(t.LabelAt(0, 0), 7);
  EXPECT_EQ(t.LabelAt(2, 0), kNoLabel);
  EXPECT_FLOAT_EQ(t.alpha(), 0.8f);

  // A per-pixel confidence image next to the labels.
  const cv::Mat conf(2, 4, CV_8UC1, cv::Scalar(153));  // 0.6
  ASSERT_TRUE(cv::imwrite((dir / "000003_conf.png").string(), conf));
  ClassLogProbs p;
  ASSERT_TRUE(by_label_ids->Segment(image, 3).Sample(Eigen::Vector2d(0, 0), &p));
  EXPECT_NEAR(std::exp(p[0]), 0.6, 1e-6);

  // Probabilities from any network as .npy (H x W x 19) take precedence over the PNG.
  std::vector<float> probs(2 * 4 * 19, 0.0f);
  for (int i = 0; i < 8; ++i) {
    probs[static_cast<size_t>(i * 19 + 2)] = 0.7f;  // building
    probs[static_cast<size_t>(i * 19 + 8)] = 0.3f;  // vegetation
  }
  WriteNpy(dir / "000003.npy", probs, 2, 4, 19);
  const Segmentation n = by_label_ids->Segment(image, 3);
  EXPECT_EQ(n.storage(), Segmentation::Storage::kLogProbabilities);
  ASSERT_TRUE(n.Sample(Eigen::Vector2d(7, 3), &p));
  EXPECT_NEAR(std::exp(p[2]), 0.7, 1e-5);
  EXPECT_NEAR(std::exp(p[8]), 0.3, 1e-5);
  std::ofstream(dir / "000005.npy") << "not numpy";
  EXPECT_THROW(by_label_ids->Segment(image, 5), InputError);
  EXPECT_THROW(MakeSegmenter("labels:/nonexistent/folder"), InputError);
}

// A ground-truth image with several regions and an unlabeled band.
cv::Mat MakeTruth(int w, int h) {
  cv::Mat truth(h, w, CV_8UC1, cv::Scalar(10));
  truth.rowRange(h / 2, h).setTo(0);
  truth(cv::Rect(w / 4, h / 4, w / 3, h / 2)).setTo(2);
  truth(cv::Rect(w / 2, h / 2, w / 8, h / 4)).setTo(13);
  truth(cv::Rect(0, h - h / 10, w, h / 10)).setTo(kNoLabel);
  return truth;
}

double Accuracy(const cv::Mat& noisy, const cv::Mat& truth) {
  SegmentationScore score;
  score.Add(noisy, truth);
  return score.PixelAccuracy();
}

// P(a pixel's right neighbour is wrong | it is wrong): near the rate for salt noise, high for blobs.
double NeighbourWrongGivenWrong(const cv::Mat& noisy, const cv::Mat& truth) {
  double wrong = 0, both = 0;
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x + 1 < truth.cols; ++x) {
      if (truth.at<std::uint8_t>(y, x) >= kNumClasses || truth.at<std::uint8_t>(y, x + 1) >= kNumClasses)
        continue;
      if (noisy.at<std::uint8_t>(y, x) == truth.at<std::uint8_t>(y, x)) continue;
      ++wrong;
      if (noisy.at<std::uint8_t>(y, x + 1) != truth.at<std::uint8_t>(y, x + 1)) ++both;
    }
  }
  return both / wrong;
}

TEST(LabelNoise, ErrorRateBlobsSaltAndDeterminism) {
  const cv::Mat truth = MakeTruth(620, 188);
  for (double rate : {0.1, 0.25, 0.5}) {
    LabelNoiseOptions options;
    options.rate = rate;
    const cv::Mat noisy = AddLabelNoise(truth, options, 7);
    EXPECT_NEAR(Accuracy(noisy, truth), 1.0 - rate, 0.01) << rate;
    EXPECT_EQ(cv::countNonZero((truth == kNoLabel) != (noisy == kNoLabel)), 0);  // no-class pixels stay
    EXPECT_EQ(cv::countNonZero(noisy != AddLabelNoise(truth, options, 7)), 0);   // deterministic
    EXPECT_GT(cv::countNonZero(noisy != AddLabelNoise(truth, options, 8)), 0);
  }
  LabelNoiseOptions salt, blobs;
  salt.blob_fraction = 0.0;
  blobs.blob_fraction = 1.0;
  const double salt_neighbour = NeighbourWrongGivenWrong(AddLabelNoise(truth, salt, 1), truth);
  const double blob_neighbour = NeighbourWrongGivenWrong(AddLabelNoise(truth, blobs, 1), truth);
  EXPECT_NEAR(salt_neighbour, 0.25, 0.02);
  EXPECT_GT(blob_neighbour, 0.9);
  EXPECT_NEAR(Accuracy(AddLabelNoise(truth, blobs, 1), truth), 0.75, 0.01);
  LabelNoiseOptions none;
  none.rate = 0.0;
  EXPECT_EQ(cv::countNonZero(AddLabelNoise(truth, none, 1) != truth), 0);
  LabelNoiseOptions bad;
  bad.rate = 0.95;
  EXPECT_THROW(AddLabelNoise(truth, bad, 1), InvalidArgument);
}

TEST(TruthNoisySegmenter, SingleFrameAccuracyIsOneMinusRate) {
  testing::TempDir dir;
  const cv::Mat truth = MakeTruth(620, 188);
  for (int f = 0; f < 4; ++f) ASSERT_TRUE(cv::imwrite((dir / cv::format("%06d.png", f)).string(), truth));
  SegmenterContext context;
  context.truth_label_dir = dir.path();
  auto segmenter = MakeSegmenter("truth-noisy:0.25", context);
  ASSERT_NE(segmenter, nullptr);
  SegmentationScore score;
  cv::Mat first;
  for (int f = 0; f < 4; ++f) {
    const Segmentation s = segmenter->Segment(cv::Mat(), f);
    EXPECT_EQ(s.input_size(), truth.size());
    EXPECT_NEAR(s.alpha(), 0.75f, 1e-6);
    const cv::Mat labels = s.LabelsAtInputSize();
    if (f == 0) first = labels;
    score.Add(labels, truth);
  }
  std::cout << "truth-noisy:0.25 single-frame pixel accuracy " << score.PixelAccuracy() << "\n";
  EXPECT_NEAR(score.PixelAccuracy(), 0.75, 0.01);
  // Deterministic per frame, different between frames.
  EXPECT_EQ(cv::countNonZero(segmenter->Segment(cv::Mat(), 0).LabelsAtInputSize() != first), 0);
  EXPECT_GT(cv::countNonZero(segmenter->Segment(cv::Mat(), 1).LabelsAtInputSize() != first), 0);
  // Another seed, another noise.
  auto other = MakeSegmenter("truth-noisy:0.25,seed=5,alpha=0.6", context);
  EXPECT_GT(cv::countNonZero(other->Segment(cv::Mat(), 0).LabelsAtInputSize() != first), 0);
  EXPECT_FLOAT_EQ(other->Segment(cv::Mat(), 0).alpha(), 0.6f);
}

TEST(MakeSegmenter, SpecsAndErrors) {
  EXPECT_EQ(MakeSegmenter("none"), nullptr);
  EXPECT_THROW(MakeSegmenter("psp:model.onnx"), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("truth-noisy:0.25"), InvalidArgument);  // no label folder in the context
  SegmenterContext context;
  context.truth_label_dir = kTestData;
  EXPECT_THROW(MakeSegmenter("truth-noisy:abc", context), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("truth-noisy:0.95", context), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("truth-noisy:0.2,ids=label", context), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("labels:" + kTestData.string() + ",alpha=2"), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("enet:"), InvalidArgument);
  EXPECT_THROW(MakeSegmenter("enet:/nonexistent/enet-model.net"), InputError);
  EXPECT_THROW(MakeSegmenter("onnx:" + (kTestData / "tiny_segnet.yaml").string() + ",resize=crop"),
               InvalidArgument);
  EXPECT_NE(MakeSegmenter("onnx:" + (kTestData / "tiny_segnet.yaml").string() + ",resize=tile")
                ->Describe()
                .find("tiled"),
            std::string::npos);
  auto onnx = MakeSegmenter("onnx:" + (kTestData / "tiny_segnet.yaml").string());
  ASSERT_NE(onnx, nullptr);
  EXPECT_NE(onnx->Describe().find("tiny-segnet"), std::string::npos);
  EXPECT_TRUE(onnx->NeedsImage());
}

}  // namespace
}  // namespace semslam
