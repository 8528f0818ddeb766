#pragma once
// A copy of every log message in a file (a run's run.log), for as long as the object lives.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace semslam {

// Copies every log message the default logger passes (debug and up when it is at debug level, else info and
// up) to `path`, with the date, after `header` lines (e.g. the version and the command line). Each message
// is flushed as it is written, so a process that is killed leaves its log whole.
class LogFile {
 public:
  explicit LogFile(const std::filesystem::path& path, const std::vector<std::string>& header = {});
  ~LogFile();
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

 private:
  std::shared_ptr<void> sink_;
  int previous_flush_level_ = 0;
};

}  // namespace semslam
