// Where the odometry gets predicted disparities from (DVSO: depth init from
// D^L, virtual stereo term with D^R). vo/ only sees this interface; files are
// read by the implementations below, a TorchScript predictor lives in stacknet/.
#pragma once

#include <condition_variable>
#include <utility>
#include <exception>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/disparity_io.h"

namespace dvso {

struct DisparityPair {
  cv::Mat left;   // D^L: CV_32F, pixels at the sequence's image resolution, <= 0 = unknown
  cv::Mat right;  // D^R: CV_32F, same size; right image x = left x - d
};

class DisparitySource {
 public:
  virtual ~DisparitySource() = default;
  // Predicted disparities for frame `index` given its left image (CV_8UC1 or
  // CV_8UC3); maps are returned at the image's resolution. Throws dvso::Error.
  virtual DisparityPair Predict(int index, const cv::Mat& left_image) = 0;
  // Hint that Predict(index, ...) may follow soon (a source with a worker
  // may start on it now). Default: nothing.
  virtual void Prefetch(int /*index*/, const cv::Mat& /*left_image*/) {}
  // True when Predict(index, ...) would not wait for a worker (a source
  // without one computes on the caller's thread and is always "ready").
  virtual bool IsReady(int /*index*/) { return true; }
};

// How a map is brought to another size. Values always scale with the width.
enum class DisparityResize {
  kBilinear,  // dense predictions: bilinear, a pixel next to an invalid (<= 0) one stays invalid
  kNearest,   // sparse labels: nearest, no value is ever interpolated
};

// Resizes a disparity map to width x height, scaling its values with the width.
cv::Mat ResizeDisparity(const cv::Mat& disparity, int width, int height,
                        DisparityResize method = DisparityResize::kBilinear);

// Reads precomputed maps frame by frame (memory does not grow with the
// sequence): either two folders of KITTI uint16 PNGs named like the images
// (frame_names[i] + ".png"), or two .npy stacks normalised by width
// (monodepth convention). Every file is checked to exist at construction, so
// a missing map fails before any output is written. Maps of another size are
// resized bilinearly; NaN / non-positive values become 0 (no depth).
class FileDisparitySource : public DisparitySource {
 public:
  // frame_names: the sequence's image names without extension, one per frame.
  FileDisparitySource(std::string left_path, std::string right_path, std::vector<std::string> frame_names);
  DisparityPair Predict(int index, const cv::Mat& left_image) override;

 private:
  std::string MapPath(const std::string& dir, int index) const;
  std::string left_path_, right_path_;
  std::vector<std::string> frame_names_;
  std::unique_ptr<NpyDisparityStack> left_npy_, right_npy_;
};

// Runs another source on a worker thread: Prefetch(i) starts frame i while the
// caller goes on (e.g. tracks frame i); Predict(i) returns that result, waiting
// for it, or computes i when it was not prefetched (a prefetch of another frame
// queued meanwhile starts once Predict has taken its result). Holds at most one
// frame in flight and one result, so memory is bounded. Errors of the wrapped source
// reach the caller of Predict for that frame. All methods are to be called
// from one thread (the odometry's).
class AsyncDisparitySource : public DisparitySource {
 public:
  explicit AsyncDisparitySource(std::unique_ptr<DisparitySource> inner);
  ~AsyncDisparitySource() override;
  DisparityPair Predict(int index, const cv::Mat& left_image) override;
  void Prefetch(int index, const cv::Mat& left_image) override;
  bool IsReady(int index) override;
  int prefetched_used() const { return prefetched_used_; }  // Predict calls served by a prefetch
  int computed_on_demand() const { return computed_on_demand_; }

 private:
  void WorkerLoop();

  std::unique_ptr<DisparitySource> inner_;
  std::mutex mutex_;
  std::condition_variable changed_;
  int requested_index_ = -1;   // frame the worker should compute next (-1 = none)
  cv::Mat requested_image_;
  int running_index_ = -1;     // frame the worker is computing
  int done_index_ = -1;        // frame whose result is in done_
  DisparityPair done_;
  std::exception_ptr done_error_;
  bool stop_ = false;
  int prefetched_used_ = 0, computed_on_demand_ = 0;
  std::thread worker_;
};

}  // namespace dvso
