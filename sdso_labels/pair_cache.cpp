#include "sdso_labels/pair_cache.h"

#include <chrono>

#include "core/error.h"

namespace dvso::labels {

PairCachingReader::PairCachingReader(const SequenceReader& base, size_t max_cached)
    : base_(base), max_cached_(max_cached) {
  Require(max_cached >= 1, "PairCachingReader: max_cached must be >= 1");
}

StereoFrame PairCachingReader::Read(int index, const SequenceReadOptions& options) const {
  const auto start = std::chrono::steady_clock::now();
  StereoFrame frame = base_.Read(index, options);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard<std::mutex> lock(mutex_);
  read_ms_ += ms;
  if (!frame.right.empty()) cache_[index] = {frame.left, frame.right};
  while (cache_.size() > max_cached_) cache_.erase(cache_.begin());
  return frame;
}

void PairCachingReader::Take(int index, cv::Mat* left, cv::Mat* right) const {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = cache_.find(index);
    if (it != cache_.end()) {
      *left = it->second.first;
      *right = it->second.second;
      cache_.erase(cache_.begin(), cache_.upper_bound(index));
      return;
    }
    ++rereads_;
  }
  SequenceReadOptions pair;
  pair.load_right = true;
  const StereoFrame frame = Read(index, pair);
  *left = frame.left;
  *right = frame.right;
  std::lock_guard<std::mutex> lock(mutex_);
  cache_.erase(cache_.begin(), cache_.upper_bound(index));
}

double PairCachingReader::read_ms() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return read_ms_;
}

size_t PairCachingReader::cached() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return cache_.size();
}

int PairCachingReader::rereads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rereads_;
}

}  // namespace dvso::labels
