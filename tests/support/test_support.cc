#include "support/test_support.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

extern char** environ;

namespace semslam::testing {

std::filesystem::path SharedDataDir() {
  if (const char* env = std::getenv("SEMSLAM_SHARED_DATA"); env != nullptr && *env != '\0') return env;
  return SEMSLAM_SHARED_DATA_DIR;
}

std::filesystem::path SharedDataPath(const std::string& relative) {
  const auto path = SharedDataDir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path{};
}

std::filesystem::path SemslamBinary() {
  if (const char* env = std::getenv("SEMSLAM_BIN"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(SEMSLAM_BINARY_DIR) / "bin" / "semslam";
}

std::filesystem::path SynthBinary() {
  if (const char* env = std::getenv("SEMSLAM_SYNTH_BIN"); env != nullptr && *env != '\0') return env;
  return SemslamBinary();
}

bool SharedDataRequired() {
  const char* env = std::getenv("SEMSLAM_REQUIRE_DATA");
  return env != nullptr && std::string_view(env) == "1";
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string test_name = info ? fmt::format("{}.{}", info->test_suite_name(), info->name()) : "test";
  path_ = std::filesystem::path(SEMSLAM_BINARY_DIR) / "test_tmp" /
          fmt::format("{}-{}-{}", test_name, rd() % 100000, counter++);
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("SEMSLAM_KEEP_TEST_TMP") != nullptr) return;
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::string CommandResult::Describe() const {
  std::ostringstream s;
  s << "`" << command << "` ";
  if (signal != 0) {
    s << "was killed by signal " << signal << " (" << strsignal(signal) << ")";
  } else {
    s << "exited with " << exit_code;
  }
  const std::string tail = err.size() > 2000 ? "..." + err.substr(err.size() - 2000) : err;
  s << "; stderr:\n" << tail;
  return s.str();
}

CommandResult RunSemslam(const std::vector<std::string>& args) { return RunBinary(SemslamBinary(), args); }

CommandResult RunBinary(const std::filesystem::path& binary_path, const std::vector<std::string>& args) {
  CommandResult result;
  const std::string binary = binary_path.string();
  std::vector<std::string> argv_strings = {binary};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  for (const std::string& a : argv_strings) {
    result.command += (result.command.empty() ? "" : " ");
    result.command += a.find_first_of(" '\"") == std::string::npos ? a : "'" + a + "'";
  }
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);

  TempDir dir;
  const std::string out_path = (dir / "stdout.txt").string();
  const std::string err_path = (dir / "stderr.txt").string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  pid_t pid = 0;
  const int spawn_error = posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawn_error != 0) {
    result.err = std::string("cannot start: ") + std::strerror(spawn_error);
    return result;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      result.err = std::string("waitpid: ") + std::strerror(errno);
      return result;
    }
  }
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  result.out = ReadText(out_path);
  result.err = ReadText(err_path);
  return result;
}

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace semslam::testing
