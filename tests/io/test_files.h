#pragma once
// Small helpers for the io tests: write a text file, check an InputError's message.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include "support/test_support.h"  // ReadText

namespace semslam::testing {

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// Runs `statement`, expects an InputError whose message contains every one of `parts`.
#define EXPECT_INPUT_ERROR(statement, ...)                                              \
  do {                                                                                  \
    try {                                                                               \
      statement;                                                                        \
      ADD_FAILURE() << "expected InputError from " #statement;                          \
    } catch (const ::semslam::InputError& e) {                                          \
      for (const std::string& part : std::initializer_list<std::string>{__VA_ARGS__}) { \
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos)                  \
            << "message '" << e.what() << "' lacks '" << part << "'";                   \
      }                                                                                 \
    }                                                                                   \
  } while (0)

}  // namespace semslam::testing
