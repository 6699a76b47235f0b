// PairCachingReader: a SequenceReader that keeps the stereo pairs the
// odometry has read until the label writer has used them, so the stereo check
// never decodes an image twice. Frames are labelled in input order some
// keyframes after they were tracked; Take(i) drops everything up to i, so
// only that lag stays in memory (and at most `max_cached` pairs: when
// labelling lags further, e.g. at a standstill without new keyframes, the
// oldest pairs are dropped and read again when needed). Thread-safe: Take()
// may run on the label writer's worker thread.
#pragma once

#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/sequence.h"

namespace dvso::labels {

class PairCachingReader : public SequenceReader {
 public:
  explicit PairCachingReader(const SequenceReader& base, size_t max_cached = 128);

  int size() const override { return base_.size(); }
  bool is_stereo() const override { return base_.is_stereo(); }
  bool has_color() const override { return base_.has_color(); }
  const StereoCamera& camera() const override { return base_.camera(); }
  const std::vector<double>& timestamps() const override { return base_.timestamps(); }
  const std::string& root() const override { return base_.root(); }
  std::string FrameName(int index) const override { return base_.FrameName(index); }
  // Reads through the base reader and keeps the pair.
  StereoFrame Read(int index, const SequenceReadOptions& options) const override;

  // The pair of frame `index` (cached, else read again); forgets it and all earlier ones.
  void Take(int index, cv::Mat* left, cv::Mat* right) const;

  double read_ms() const;  // total time spent decoding images
  size_t cached() const;   // pairs held
  int rereads() const;     // pairs Take() had to read again (not cached)

 private:
  const SequenceReader& base_;
  const size_t max_cached_;
  mutable std::mutex mutex_;
  mutable std::map<int, std::pair<cv::Mat, cv::Mat>> cache_;  // guarded by mutex_
  mutable double read_ms_ = 0;                                // guarded by mutex_
  mutable int rereads_ = 0;                                   // guarded by mutex_
};

}  // namespace dvso::labels
