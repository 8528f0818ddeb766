#include "semslam/core/log_file.h"

#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>

namespace semslam {

LogFile::LogFile(const std::filesystem::path& path, const std::vector<std::string>& header) {
  // The logger's level (info, or debug with -v) decides what reaches the file; -q only quiets stderr's sink.
  auto sink = std::make_shared<spdlog::sinks::basic_file_sink_mt>(path.string(), /*truncate=*/true);
  sink->set_pattern("%Y-%m-%d %H:%M:%S.%e [%l] %v");
  spdlog::default_logger()->sinks().push_back(sink);
  sink_ = sink;
  // Each message reaches the file as it is logged: the log of a process that is killed is the one needed.
  previous_flush_level_ = static_cast<int>(spdlog::default_logger()->flush_level());
  spdlog::default_logger()->flush_on(spdlog::level::trace);
  for (const std::string& line : header) spdlog::info("{}", line);
}

LogFile::~LogFile() {
  auto logger = spdlog::default_logger();
  logger->flush();
  logger->flush_on(static_cast<spdlog::level::level_enum>(previous_flush_level_));
  auto& sinks = logger->sinks();
  sinks.erase(std::remove_if(sinks.begin(), sinks.end(),
                             [&](const spdlog::sink_ptr& s) { return static_cast<void*>(s.get()) == sink_.get(); }),
              sinks.end());
}

}  // namespace semslam
