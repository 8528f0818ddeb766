#include "semslam/core/yaml_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "support/test_support.h"

namespace semslam {
namespace {

std::string ErrorOf(const std::string& yaml) {
  try {
    LoadYamlText(yaml, "config.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlFile, RefusesRepeatedKeysNamingTheLine) {
  const std::string top = ErrorOf("features:\n  num_features: 1000\nfeatures:\n  num_levels: 4\n");
  EXPECT_NE(top.find("config.yaml:3"), std::string::npos) << top;
  EXPECT_NE(top.find("features"), std::string::npos) << top;
  EXPECT_NE(top.find("line 1"), std::string::npos) << top;
  const std::string nested = ErrorOf("loop:\n  enabled: true\n  enabled: false\n");
  EXPECT_NE(nested.find("config.yaml:3"), std::string::npos) << nested;
  const std::string flow = ErrorOf("input: {width: 1, width: 2}\n");
  EXPECT_NE(flow.find("width"), std::string::npos) << flow;
  const std::string in_list = ErrorOf("classes:\n  - {a: 1, a: 2}\n");
  EXPECT_NE(in_list.find("config.yaml:2"), std::string::npos) << in_list;
}

// Found by the slam_config fuzz target: "? key: 0.7" (a key that is itself a map) threw yaml-cpp's
// TypedBadConversion out of the configuration reader, which names no file and ends the program.
TEST(YamlFile, RefusesKeysThatAreNotPlainNames) {
  for (const std::string yaml : {"tracking:\n  ? keyframe_tracked_ratio_stereo: 0.7\n  : 1\n",
                                 "? [a, b]\n: 1\n", "? {a: 1}\n: 2\n", "a: 1\n? \n: 2\n"}) {
    const std::string error = ErrorOf(yaml);
    EXPECT_NE(error.find("config.yaml:"), std::string::npos) << yaml << " -> " << error;
    EXPECT_NE(error.find("plain name"), std::string::npos) << yaml << " -> " << error;
  }
}

TEST(YamlFile, AcceptsDistinctKeys) {
  const YAML::Node node = LoadYamlText("a: 1\nb: {a: 2}\nc: [ {a: 3}, {a: 4} ]\n", "x.yaml");
  EXPECT_EQ(node["b"]["a"].as<int>(), 2);
}

TEST(YamlFile, MalformedAndNonUtf8TextAreLocated) {
  const std::string malformed = ErrorOf("a: [1, 2\nb: 3\n");
  EXPECT_NE(malformed.find("config.yaml:"), std::string::npos) << malformed;
  const std::string latin1 = ErrorOf("name: ok\nlabel: Caf\xE9\n");
  EXPECT_NE(latin1.find("config.yaml:2"), std::string::npos) << latin1;
  EXPECT_NE(latin1.find("UTF-8"), std::string::npos) << latin1;
}

TEST(YamlFile, FilesNotFoundNameThePath) {
  testing::TempDir dir;
  EXPECT_THROW(LoadYamlFile(dir / "missing.yaml"), InputError);
  std::ofstream(dir / "ok.yaml") << "x: 1\n";
  EXPECT_EQ(LoadYamlFile(dir / "ok.yaml")["x"].as<int>(), 1);
}

}  // namespace
}  // namespace semslam
