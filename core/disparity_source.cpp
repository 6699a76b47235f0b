#include "core/disparity_source.h"

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "core/disparity_conversion.h"
#include "core/error.h"
#include "core/fs_util.h"

namespace dvso {

namespace {
bool IsNpy(const std::string& path) { return std::filesystem::path(path).extension() == ".npy"; }

// A valid pixel must be at least this close to fully supported by valid taps
// after bilinear resizing of the validity mask (else it touches an invalid one).
constexpr float kFullSupport = 0.999f;
}  // namespace

cv::Mat ResizeDisparity(const cv::Mat& disparity, int width, int height, DisparityResize method) {
  Require(disparity.type() == CV_32FC1, "ResizeDisparity: expected a CV_32FC1 map");
  const double scale = static_cast<double>(width) / disparity.cols;
  if (disparity.cols == width && disparity.rows == height) return disparity;
  cv::Mat out;
  if (method == DisparityResize::kNearest) {
    // Nearest keeps invalid (0) pixels from bleeding into valid ones (sparse labels).
    cv::resize(disparity, out, cv::Size(width, height), 0, 0, cv::INTER_NEAREST);
    out *= scale;
    return out;
  }
  // Bilinear: a dense D^R must stay smooth, its x-derivative enters the eq. 5.8
  // Jacobian (nearest would make 2-px stairs). Invalid taps are excluded by
  // resizing the validity mask alongside and dropping partially supported pixels.
  const cv::Mat clean = SanitizeDisparity(disparity);
  cv::Mat valid = cv::Mat(clean > 0) / 255;
  valid.convertTo(valid, CV_32F);
  cv::Mat resized_mask;
  cv::resize(clean, out, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  cv::resize(valid, resized_mask, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  out.setTo(0.0f, resized_mask < kFullSupport);
  out *= scale;
  return out;
}

FileDisparitySource::FileDisparitySource(std::string left_path, std::string right_path,
                                         std::vector<std::string> frame_names)
    : left_path_(std::move(left_path)), right_path_(std::move(right_path)), frame_names_(std::move(frame_names)) {
  Require(IsNpy(left_path_) == IsNpy(right_path_), "left and right disparities must both be .npy or both folders");
  const int frames = static_cast<int>(frame_names_.size());
  if (IsNpy(left_path_)) {
    left_npy_ = std::make_unique<NpyDisparityStack>(left_path_);
    right_npy_ = std::make_unique<NpyDisparityStack>(right_path_);
    RequireFile(left_npy_->size() >= frames, left_path_,
                "holds " + std::to_string(left_npy_->size()) + " maps, the sequence " + std::to_string(frames));
    RequireFile(right_npy_->size() >= frames, right_path_,
                "holds " + std::to_string(right_npy_->size()) + " maps, the sequence " + std::to_string(frames));
    return;
  }
  for (const std::string& dir : {left_path_, right_path_}) {
    RequireFile(std::filesystem::is_directory(dir), dir, "disparity folder does not exist");
    for (int i = 0; i < frames; ++i) {
      const std::string path = MapPath(dir, i);
      RequireFile(std::filesystem::is_regular_file(path), path,
                  "missing disparity map for frame " + std::to_string(i) + " (one PNG per image is needed)");
    }
  }
}

std::string FileDisparitySource::MapPath(const std::string& dir, int index) const {
  const std::string name =
      index >= 0 && index < static_cast<int>(frame_names_.size()) ? frame_names_[index] : FrameFileName(index, "");
  return JoinPath(dir, name + ".png");
}

DisparityPair FileDisparitySource::Predict(int index, const cv::Mat& left_image) {
  const int w = left_image.cols, h = left_image.rows;
  DisparityPair pair;
  if (left_npy_) {
    pair.left = SanitizeDisparity(left_npy_->Frame(index, w, h));
    pair.right = SanitizeDisparity(right_npy_->Frame(index, w, h));
  } else {
    pair.left = ResizeDisparity(ReadKittiMapPng(MapPath(left_path_, index)), w, h);
    pair.right = ResizeDisparity(ReadKittiMapPng(MapPath(right_path_, index)), w, h);
  }
  return pair;
}

AsyncDisparitySource::AsyncDisparitySource(std::unique_ptr<DisparitySource> inner) : inner_(std::move(inner)) {
  Require(inner_ != nullptr, "AsyncDisparitySource: no source");
  worker_ = std::thread([this] { WorkerLoop(); });
}

AsyncDisparitySource::~AsyncDisparitySource() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void AsyncDisparitySource::WorkerLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    changed_.wait(lock, [this] { return stop_ || requested_index_ >= 0; });
    if (stop_) return;
    const int index = requested_index_;
    const cv::Mat image = requested_image_;
    requested_index_ = -1;
    requested_image_.release();
    running_index_ = index;
    lock.unlock();
    DisparityPair result;
    std::exception_ptr error;
    try {
      result = inner_->Predict(index, image);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    running_index_ = -1;
    done_index_ = index;
    done_ = std::move(result);
    done_error_ = error;
    changed_.notify_all();
  }
}

void AsyncDisparitySource::Prefetch(int index, const cv::Mat& left_image) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (index == running_index_ || index == done_index_) return;
  requested_index_ = index;  // replaces a request the worker has not started
  requested_image_ = left_image.clone();
  changed_.notify_all();
}

bool AsyncDisparitySource::IsReady(int index) {
  std::lock_guard<std::mutex> lock(mutex_);
  return done_index_ == index;
}

DisparityPair AsyncDisparitySource::Predict(int index, const cv::Mat& left_image) {
  std::unique_lock<std::mutex> lock(mutex_);
  const bool prefetched = index == running_index_ || index == done_index_ || index == requested_index_;
  // A request for another frame waits until this result is taken: started as soon as frame `index`
  // finishes, it could finish too before this thread wakes and overwrite the result it waits for.
  int deferred_index = -1;
  cv::Mat deferred_image;
  if (requested_index_ >= 0 && requested_index_ != index) {
    deferred_index = std::exchange(requested_index_, -1);
    deferred_image = std::move(requested_image_);
  }
  if (!prefetched) {
    requested_index_ = index;
    requested_image_ = left_image.clone();
    changed_.notify_all();
  }
  changed_.wait(lock, [&] { return done_index_ == index; });
  (prefetched ? prefetched_used_ : computed_on_demand_)++;
  done_index_ = -1;
  DisparityPair result = std::move(done_);
  std::exception_ptr error = std::exchange(done_error_, nullptr);
  if (deferred_index >= 0 && requested_index_ < 0) {
    requested_index_ = deferred_index;
    requested_image_ = std::move(deferred_image);
    changed_.notify_all();
  }
  if (error) std::rethrow_exception(error);
  return result;
}

}  // namespace dvso
