#include "semslam/core/timing.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <fstream>
#include <numeric>
#include <string>

namespace semslam {

TimingSummary Summarize(std::vector<double> samples_ms) {
  TimingSummary s;
  if (samples_ms.empty()) return s;
  std::sort(samples_ms.begin(), samples_ms.end());
  const size_t n = samples_ms.size();
  s.count = n;
  s.total_ms = std::accumulate(samples_ms.begin(), samples_ms.end(), 0.0);
  s.mean_ms = s.total_ms / static_cast<double>(n);
  s.median_ms = (n % 2 == 1) ? samples_ms[n / 2] : 0.5 * (samples_ms[n / 2 - 1] + samples_ms[n / 2]);
  // Nearest-rank percentile.
  const size_t rank = static_cast<size_t>(std::ceil(0.95 * static_cast<double>(n)));
  s.p95_ms = samples_ms[std::clamp<size_t>(rank, 1, n) - 1];
  s.max_ms = samples_ms.back();
  return s;
}

void TimingRegistry::Add(const std::string& module, double milliseconds) {
  std::lock_guard lock(mutex_);
  samples_ms_[module].push_back(milliseconds);
}

std::vector<double> TimingRegistry::Samples(const std::string& module) const {
  std::lock_guard lock(mutex_);
  const auto it = samples_ms_.find(module);
  return it == samples_ms_.end() ? std::vector<double>{} : it->second;
}

std::map<std::string, TimingSummary> TimingRegistry::SummarizeAll() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, TimingSummary> out;
  for (const auto& [name, samples] : samples_ms_) out[name] = Summarize(samples);
  return out;
}

double PeakRssMiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // value in kB
  }
  return 0.0;
}

double CurrentRssMiB() {
  std::FILE* statm = std::fopen("/proc/self/statm", "r");
  if (statm == nullptr) return 0.0;
  unsigned long size_pages = 0, resident_pages = 0;
  const int read = std::fscanf(statm, "%lu %lu", &size_pages, &resident_pages);
  std::fclose(statm);
  if (read != 2) return 0.0;
  return static_cast<double>(resident_pages) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

void ReleaseFreeMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace semslam
