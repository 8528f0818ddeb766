#include "semslam/core/yaml_file.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "semslam/core/utf8.h"

namespace semslam {
namespace {

void CheckUniqueKeys(const YAML::Node& node, const std::filesystem::path& source, int depth) {
  // A YAML alias can make a node its own descendant; real configuration files are a few levels deep.
  if (depth > 64) throw InputError(YamlLocation(source, node.Mark()), "the YAML is nested too deeply");
  if (node.IsMap()) {
    std::map<std::string, int> first_line;
    for (const auto& entry : node) {
      // Our files name their keys; a list, a map or nothing as a key ("? [a, b]: 1") is a typo or garbage.
      if (!entry.first.IsScalar()) {
        throw InputError(YamlLocation(source, entry.first.Mark()),
                         "a key must be a plain name, not a list, a map or empty");
      }
      const std::string key = entry.first.Scalar();
      const int line = entry.first.Mark().line + 1;
      const auto [it, inserted] = first_line.emplace(key, line);
      if (!inserted) {
        throw InputError(YamlLocation(source, entry.first.Mark()), key,
                         fmt::format("the key is repeated (first on line {}); give it once", it->second));
      }
      CheckUniqueKeys(entry.second, source, depth + 1);
    }
  } else if (node.IsSequence()) {
    for (const auto& element : node) CheckUniqueKeys(element, source, depth + 1);
  }
}

}  // namespace

SourceLocation YamlLocation(const std::filesystem::path& file, const YAML::Mark& mark) {
  return {file, mark.line >= 0 ? mark.line + 1 : 0};
}

void RequireUniqueYamlKeys(const YAML::Node& node, const std::filesystem::path& source) {
  CheckUniqueKeys(node, source, 0);
}

YAML::Node LoadYamlText(const std::string& text, const std::filesystem::path& source) {
  const size_t bad = FindInvalidUtf8(text);
  if (bad != std::string::npos) {
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(bad), '\n'));
    RequireUtf8(std::string_view(text).substr(bad, 4), SourceLocation{source, line}, "text");
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(YamlLocation(source, e.mark), "malformed YAML: " + e.msg);
  }
  RequireUniqueYamlKeys(root, source);
  return root;
}

YAML::Node LoadYamlFile(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw InputError(file, "file not found");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open the file for reading");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(file, "read error");
  return LoadYamlText(buffer.str(), file);
}

}  // namespace semslam
