// ESPNetv2 and SINet built in C++ against known outputs: the logits of an independent NumPy forward pass
// (tools/segnet_reference.py, float64) on the Cityscapes val image subsampled to 256x128, and the class mix
// of the full-size image against its ground truth through the segmenter.

#include "semslam/semantics/torch_networks.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"
#include "semslam/semantics/dnn_custom_layers.h"
#include "semslam/semantics/dnn_segmenter.h"
#include "semslam/semantics/label_image_segmenter.h"
#include "semslam/semantics/model_card.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/semantics/semantic_outputs.h"
#include "semslam/semantics/torch_state_dict.h"
#include "support/test_support.h"

namespace semslam {
namespace {

const std::filesystem::path kTestData = SEMSLAM_SEMANTICS_TEST_DATA;
const std::filesystem::path kModels = SEMSLAM_MODELS_DIR;
const char* const kImage = "cityscapes_samples/frankfurt_000000_000294_leftImg8bit.png";
const char* const kTruth =
    "cityscapes_samples/mmseg_downscaled_256x128/frankfurt_000000_000294_gtFine_labelTrainIds.png";

nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The reference's input: every `step`-th pixel, cropped to the divisor, RGB, ImageNet mean and std, NCHW.
cv::Mat ReferenceInput(const cv::Mat& bgr, int step, int height, int width) {
  cv::Mat blob({1, 3, height, width}, CV_32F);
  const double mean[3] = {0.485, 0.456, 0.406}, stddev[3] = {0.229, 0.224, 0.225};
  for (int c = 0; c < 3; ++c) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const double v = bgr.at<cv::Vec3b>(y * step, x * step)[2 - c] / 255.0;
        blob.ptr<float>(0, c)[y * width + x] = static_cast<float>((v - mean[c]) / stddev[c]);
      }
    }
  }
  return blob;
}

void ExpectMatchesReference(const std::string& architecture, const std::string& weights_file,
                            const std::string& expected_file) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  const nlohmann::json expected = ReadJson(kTestData / expected_file);
  const cv::Mat image = cv::imread((testing::SharedDataDir() / kImage).string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  const int h = expected["input_height"], w = expected["input_width"];
  cv::dnn::Net net = FindTorchArchitecture(architecture)->build(TorchStateDict::Read(dir / weights_file));
  net.setInput(ReferenceInput(image, expected["step"], h, w));
  const cv::Mat out = net.forward();
  ASSERT_EQ(out.dims, 4);
  ASSERT_EQ(out.size[1], expected["output_channels"].get<int>());
  ASSERT_EQ(out.size[2], expected["output_height"].get<int>());
  ASSERT_EQ(out.size[3], expected["output_width"].get<int>());
  const int plane = out.size[2] * out.size[3];
  double worst = 0.0;
  for (const auto& sample : expected["samples"]) {
    const int y = sample["y"], x = sample["x"];
    for (int c = 0; c < out.size[1]; ++c) {
      const double want = sample["logits"][static_cast<size_t>(c)];
      const double got = out.ptr<float>()[static_cast<size_t>(c) * plane + y * out.size[3] + x];
      worst = std::max(worst, std::abs(got - want) / (1.0 + std::abs(want)));
      EXPECT_NEAR(got, want, 2e-3 * (1.0 + std::abs(want)))
          << architecture << " channel " << c << " at " << x << "," << y;
    }
  }
  // The argmax over the 19 classes: the same histogram up to pixels on a near-tie.
  std::vector<int> histogram(19, 0);
  for (int i = 0; i < plane; ++i) {
    int best = 0;
    for (int c = 1; c < 19; ++c) {
      if (out.ptr<float>()[static_cast<size_t>(c) * plane + i] >
          out.ptr<float>()[static_cast<size_t>(best) * plane + i])
        best = c;
    }
    ++histogram[static_cast<size_t>(best)];
  }
  int differences = 0;
  for (int c = 0; c < 19; ++c)
    differences += std::abs(histogram[static_cast<size_t>(c)] -
                            expected["class_histogram"][static_cast<size_t>(c)].get<int>());
  EXPECT_LE(differences, plane / 500) << architecture;
  ::testing::Test::RecordProperty("worst_relative_logit_error", std::to_string(worst));
}

TEST(TorchNetworks, EspNetV2MatchesTheNumpyReference) {
  ExpectMatchesReference("espnetv2", "espnetv2_s_2.0_city_1024x512.pth", "espnetv2_expected.json");
}

TEST(TorchNetworks, SiNetMatchesTheNumpyReference) {
  ExpectMatchesReference("sinet", "sinet_cityscapes.pth", "sinet_expected.json");
}

TEST(TorchNetworks, TheWrongStateDictNamesTheMissingTensor) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  const TorchStateDict sinet = TorchStateDict::Read(dir / "sinet_cityscapes.pth");
  try {
    BuildEspNetV2(sinet);
    FAIL() << "built ESPNetv2 from SINet's weights";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sinet_cityscapes.pth"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("base_net.level1.conv.weight"), std::string::npos) << e.what();
  }
}

TEST(TorchNetworks, CardsInTheRepositoryMatchTheBuiltInOnes) {
  for (const std::string name : {"espnetv2", "sinet"}) {
    const ModelCard card = ReadModelCard(kModels / (name + "-cityscapes.yaml"));
    const ModelCard built_in =
        name == "sinet" ? SiNetCityscapesCard(card.file) : EspNetV2CityscapesCard(card.file);
    EXPECT_EQ(card.name, built_in.name);
    EXPECT_EQ(card.ResolvedFormat(), ModelCard::Format::kPth);
    EXPECT_EQ(card.architecture, built_in.architecture);
    EXPECT_EQ(card.input_width, built_in.input_width);
    EXPECT_EQ(card.input_height, 0);
    EXPECT_EQ(card.size_divisor, built_in.size_divisor);
    EXPECT_EQ(card.rgb, built_in.rgb);
    EXPECT_DOUBLE_EQ(card.scale, built_in.scale);
    EXPECT_EQ(card.mean, built_in.mean);
    EXPECT_EQ(card.stddev, built_in.stddev);
    EXPECT_EQ(card.channel_to_train_id, built_in.channel_to_train_id);
  }
  // ESPNetv2's background channel is dropped, not spread over the classes.
  EXPECT_EQ(EspNetV2CityscapesCard("x.pth").channel_to_train_id.back(), kDropChannel);
  EXPECT_THROW(ParseModelCard("file: x.pth\narchitecture: resnet\n", "/m", "/m/c.yaml"), InputError);
  EXPECT_THROW(ParseModelCard("file: x.pth\narchitecture: sinet\ninput: {width: 640, height: 200}\n", "/m",
                              "/m/c.yaml"),
               InputError);
}

TEST(TorchNetworks, InputSizeKeepsTheAspectRatio) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  const DnnSegmenter espnet(EspNetV2CityscapesCard(dir / "espnetv2_s_2.0_city_1024x512.pth"));
  EXPECT_EQ(espnet.NetworkInputSize({1241, 376}), cv::Size(1024, 304));   // KITTI
  EXPECT_EQ(espnet.NetworkInputSize({2048, 1024}), cv::Size(1024, 512));  // Cityscapes: the training size
  const DnnSegmenter sinet(SiNetCityscapesCard(dir / "sinet_cityscapes.pth"));
  EXPECT_EQ(sinet.NetworkInputSize({1241, 376}), cv::Size(1280, 384));
  const DnnSegmenter narrow(SiNetCityscapesCard(dir / "sinet_cityscapes.pth", 640));
  EXPECT_EQ(narrow.NetworkInputSize({1241, 376}), cv::Size(640, 256));
}

TEST(TorchNetworks, CustomLayersFollowPyTorchConventions) {
  RegisterCustomDnnLayers();
  // A 1x1x2x3 blob resized to 4x6 (half-pixel centres) and pooled adaptively to 1x2.
  cv::dnn::Net net;
  net.setInputsNames({"x"});
  cv::dnn::LayerParams up;
  up.set("scale", 2.0);
  up.set("align_corners", false);
  const int up_id = net.addLayer("up", kBilinearLayer, up);
  net.connect(0, 0, up_id, 0);
  cv::dnn::LayerParams pool;
  pool.set("scale", 0.5);
  const int pool_id = net.addLayer("pool", kAdaptiveAvgPoolLayer, pool);
  net.connect(up_id, 0, pool_id, 0);
  cv::Mat x({1, 1, 2, 3}, CV_32F);
  const float values[6] = {0, 1, 2, 3, 4, 5};
  std::copy(values, values + 6, x.ptr<float>());
  net.setInput(x);
  std::vector<cv::Mat> outs;
  net.forward(outs, std::vector<cv::String>{"up", "pool"});
  const cv::Mat& u = outs[0];
  ASSERT_EQ(u.size[2], 4);
  ASSERT_EQ(u.size[3], 6);
  // Row 0 is input row 0 (source -0.25 clamps to 0); column 1 sits a quarter of the way from 0 to 1.
  EXPECT_FLOAT_EQ(u.ptr<float>()[0], 0.0f);
  EXPECT_FLOAT_EQ(u.ptr<float>()[1], 0.25f);
  EXPECT_FLOAT_EQ(u.ptr<float>()[5], 2.0f);
  // Row 1: source row 0.25.
  EXPECT_FLOAT_EQ(u.ptr<float>()[6], 0.75f);
  const cv::Mat& p = outs[1];
  ASSERT_EQ(p.size[2], 2);
  ASSERT_EQ(p.size[3], 3);
  EXPECT_FLOAT_EQ(p.ptr<float>()[0], 0.5f);  // mean of 0, 0.25, 0.75, 1
  EXPECT_EQ(ScaledSize(8, 0.1, 5), 5);
  EXPECT_EQ(ScaledSize(8, 1.5, 5), 12);
}

// Pixel accuracy and mean IoU (classes present in the truth) of a segmenter on the full-size val image,
// its output shrunk to the 256x128 truth.
// Also checks the class mix: every class's share of the labelled truth pixels is matched by its share of the
// output within `mix_tolerance` (the sample: road 0.34, building 0.44, sidewalk 0.09, car 0.06, ...).
SegmentationScore ScoreOnCityscapes(Segmenter& segmenter, double mix_tolerance) {
  const cv::Mat image = cv::imread((testing::SharedDataDir() / kImage).string(), cv::IMREAD_COLOR);
  const cv::Mat truth = ReadLabelImage(testing::SharedDataDir() / kTruth);
  cv::Mat predicted;
  cv::resize(segmenter.Segment(image).LabelsAtInputSize(), predicted, truth.size(), 0, 0, cv::INTER_NEAREST);
  SegmentationScore score;
  score.Add(predicted, truth);
  std::array<double, kNumClasses> truth_share{}, predicted_share{};
  double labelled = 0.0;
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      const int t = truth.at<std::uint8_t>(y, x), p = predicted.at<std::uint8_t>(y, x);
      if (!IsValidTrainId(t)) continue;
      labelled += 1.0;
      truth_share[static_cast<size_t>(t)] += 1.0;
      if (IsValidTrainId(p)) predicted_share[static_cast<size_t>(p)] += 1.0;
    }
  }
  for (int c = 0; c < kNumClasses; ++c) {
    EXPECT_NEAR(predicted_share[static_cast<size_t>(c)] / labelled, truth_share[static_cast<size_t>(c)] / labelled,
                mix_tolerance)
        << ClassName(c);
  }
  return score;
}

TEST(TorchNetworks, EspNetV2LabelsTheCityscapesImage) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  SEMSLAM_REQUIRE_SHARED_DATA(samples, "cityscapes_samples");
  const auto segmenter = MakeSegmenter("espnetv2:" + (dir / "espnetv2_s_2.0_city_1024x512.pth").string());
  // Class shares within 0.025 (measured: building 0.423 against 0.441, road 0.328 against 0.337).
  const SegmentationScore score = ScoreOnCityscapes(*segmenter, 0.025);
  // The specification's bar; the NumPy reference at 1024x512 scores 0.947.
  EXPECT_GE(score.PixelAccuracy(), 0.93);
  EXPECT_GE(score.MeanIouOverTruthClasses(), 0.6);
  RecordProperty("pixel_accuracy", std::to_string(score.PixelAccuracy()));
}

TEST(TorchNetworks, SiNetLabelsTheCityscapesImage) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  SEMSLAM_REQUIRE_SHARED_DATA(samples, "cityscapes_samples");
  // SINet was trained on full-size Cityscapes images (2048x1024; the NumPy reference scores 0.914 there).
  const auto segmenter = MakeSegmenter("sinet:" + (dir / "sinet_cityscapes.pth").string() + ",width=2048");
  // Class shares within 0.035 (measured: building 0.410 against 0.441, car 0.040 against 0.062, bus 0.021).
  const SegmentationScore score = ScoreOnCityscapes(*segmenter, 0.035);
  EXPECT_GE(score.PixelAccuracy(), 0.9);
  RecordProperty("pixel_accuracy", std::to_string(score.PixelAccuracy()));
}

TEST(TorchNetworks, SegmentersTakeGreyBgrAndBgraImages) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  SEMSLAM_REQUIRE_SHARED_DATA(samples, "cityscapes_samples");
  const cv::Mat bgr = cv::imread((testing::SharedDataDir() / kImage).string(), cv::IMREAD_COLOR);
  cv::Mat small, grey, grey3, bgra;
  cv::resize(bgr, small, cv::Size(512, 256), 0, 0, cv::INTER_AREA);
  cv::cvtColor(small, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, grey3, cv::COLOR_GRAY2BGR);
  cv::cvtColor(small, bgra, cv::COLOR_BGR2BGRA);
  for (const std::string& net :
       {"espnetv2:" + (dir / "espnetv2_s_2.0_city_1024x512.pth").string() + ",width=512",
        "sinet:" + (dir / "sinet_cityscapes.pth").string() + ",width=512"}) {
    const auto segmenter = MakeSegmenter(net);
    // BGRA is BGR with the alpha dropped; grey is the same as three equal channels.
    const cv::Mat from_bgr = segmenter->Segment(small).Labels();
    EXPECT_EQ(cv::countNonZero(segmenter->Segment(bgra).Labels() != from_bgr), 0) << net;
    EXPECT_EQ(cv::countNonZero(segmenter->Segment(grey).Labels() != segmenter->Segment(grey3).Labels()), 0)
        << net;
    EXPECT_EQ(segmenter->Segment(grey).input_size(), grey.size());
  }
}

// auto: SINet for a colour camera, ESPNetv2 for a grey one (SINet reads grey trees as persons), settings kept.
TEST(TorchNetworks, AutoPicksTheNetworkForTheCamera) {
  SEMSLAM_REQUIRE_SHARED_DATA(dir, "segmentation_weights");
  SegmenterContext colour;
  colour.colour_images = true;
  const std::string on_colour = MakeSegmenter("auto:" + dir.string(), colour)->Describe();
  const std::string on_grey = MakeSegmenter("auto:" + dir.string() + ",width=512")->Describe();
  EXPECT_NE(on_colour.find("sinet"), std::string::npos) << on_colour;
  EXPECT_NE(on_grey.find("espnetv2"), std::string::npos) << on_grey;
  EXPECT_NE(on_grey.find("width 512"), std::string::npos) << on_grey;
  const std::string default_grey = MakeSegmenter("auto:" + dir.string())->Describe();
  EXPECT_NE(default_grey.find("width 768"), std::string::npos) << default_grey;
  EXPECT_THROW(MakeSegmenter("auto:" + (dir / "missing").string()), InputError);
  EXPECT_THROW(MakeSegmenter("auto,alpha=0.5"), InvalidArgument);
}

}  // namespace
}  // namespace semslam
