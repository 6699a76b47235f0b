// Multi-threaded batch loader: a producer thread assembles batches in order,
// loading the samples of each batch on `num_workers` threads, and keeps up to
// `prefetch` batches ready. The order and every sample's augmentation depend
// only on (seed, stage, epoch, position), so a resumed run sees exactly the
// batches the interrupted one would have seen.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "stacknet/dataset.h"
#include "stacknet/losses.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Sample order of one epoch: a permutation of [0, size) seeded by (seed, stage, epoch).
std::vector<int> EpochOrder(int size, int seed, int stage, int epoch);

// Stacks samples into a batch.
StereoBatch Collate(const std::vector<StereoSample>& samples);

class DataLoader {
 public:
  // Serves batches [first_batch, num_batches) of the epoch.
  DataLoader(const StereoDataset& dataset, const AugmentOptions& augment, int batch_size, int num_workers,
             int seed, int stage, int epoch, int first_batch = 0, int max_batches = 0, int prefetch = 2);
  ~DataLoader();
  DataLoader(const DataLoader&) = delete;
  DataLoader& operator=(const DataLoader&) = delete;

  int num_batches() const { return num_batches_; }
  // Next batch in order; std::nullopt at the end. Rethrows a loading error.
  std::optional<StereoBatch> Next();

 private:
  void Produce();
  StereoBatch LoadBatch(int batch) const;

  const StereoDataset& dataset_;
  AugmentOptions augment_;
  int batch_size_, num_workers_, seed_, stage_, epoch_;
  int first_batch_, num_batches_, prefetch_;
  std::vector<int> order_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<StereoBatch> ready_;
  int produced_ = 0;
  bool stop_ = false, done_ = false;
  std::exception_ptr error_;
  std::thread producer_;
};

}  // namespace dvso::stacknet
