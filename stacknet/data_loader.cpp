#include "stacknet/data_loader.h"

#include <algorithm>
#include <future>
#include <numeric>
#include <random>

#include "stacknet/augmentation.h"

namespace dvso::stacknet {
namespace {
uint64_t Mix(uint64_t a, uint64_t b) {
  // splitmix64-style combination: well-spread seeds from small integers.
  uint64_t z = a * 0x9E3779B97F4A7C15ULL + b + 0x632BE59BD9B4E019ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
}  // namespace

std::vector<int> EpochOrder(int size, int seed, int stage, int epoch) {
  std::vector<int> order(size);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(Mix(Mix(seed, stage), epoch));
  std::shuffle(order.begin(), order.end(), rng);
  return order;
}

StereoBatch Collate(const std::vector<StereoSample>& samples) {
  auto stack = [&](torch::Tensor StereoSample::*field) {
    std::vector<torch::Tensor> parts;
    for (const auto& s : samples) parts.push_back(s.*field);
    return torch::stack(parts);
  };
  StereoBatch b;
  b.left = stack(&StereoSample::left);
  b.right = stack(&StereoSample::right);
  b.left_label = stack(&StereoSample::left_label);
  b.right_label = stack(&StereoSample::right_label);
  b.left_mask = stack(&StereoSample::left_mask);
  b.right_mask = stack(&StereoSample::right_mask);
  return b;
}

DataLoader::DataLoader(const StereoDataset& dataset, const AugmentOptions& augment, int batch_size, int num_workers,
                       int seed, int stage, int epoch, int first_batch, int max_batches, int prefetch)
    : dataset_(dataset),
      augment_(augment),
      batch_size_(batch_size),
      num_workers_(std::max(1, num_workers)),
      seed_(seed),
      stage_(stage),
      epoch_(epoch),
      first_batch_(first_batch),
      prefetch_(std::max(1, prefetch)) {
  order_ = EpochOrder(dataset.size(), seed, stage, epoch);
  num_batches_ = (dataset.size() + batch_size - 1) / batch_size;
  if (max_batches > 0) num_batches_ = std::min(num_batches_, max_batches);
  produced_ = first_batch_;
  producer_ = std::thread([this] { Produce(); });
}

DataLoader::~DataLoader() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  producer_.join();
}

StereoBatch DataLoader::LoadBatch(int batch) const {
  const int begin = batch * batch_size_;
  const int end = std::min<int>(begin + batch_size_, static_cast<int>(order_.size()));
  std::vector<StereoSample> samples(end - begin);
  auto load = [&](int position) {
    std::mt19937_64 rng(Mix(Mix(Mix(seed_, stage_), epoch_), position + 1));
    samples[position - begin] = Augment(dataset_.Load(order_[position]), augment_, rng);
  };
  // Positions are split over the workers; each worker's exceptions surface via get().
  std::vector<std::future<void>> workers;
  for (int w = 0; w < num_workers_; ++w) {
    workers.push_back(std::async(std::launch::async, [&, w] {
      for (int p = begin + w; p < end; p += num_workers_) load(p);
    }));
  }
  for (auto& f : workers) f.get();
  return Collate(samples);
}

void DataLoader::Produce() {
  try {
    for (int batch = first_batch_; batch < num_batches_; ++batch) {
      StereoBatch b = LoadBatch(batch);
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || static_cast<int>(ready_.size()) < prefetch_; });
      if (stop_) return;
      ready_.push_back(std::move(b));
      changed_.notify_all();
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = true;
  changed_.notify_all();
}

std::optional<StereoBatch> DataLoader::Next() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return !ready_.empty() || done_; });
  if (!ready_.empty()) {
    StereoBatch b = std::move(ready_.front());
    ready_.pop_front();
    changed_.notify_all();
    return b;
  }
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace dvso::stacknet
