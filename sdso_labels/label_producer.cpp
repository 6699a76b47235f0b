#include "sdso_labels/label_producer.h"

#include <chrono>
#include <filesystem>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"

namespace dvso::labels {

namespace {

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void LabelProducerOptions::Check() const {
  projection.Check();
  stereo_check.Check();
  Require(max_queue >= 1, "labels: max_queue must be >= 1");
}

std::string LabelProducer::LabelPath(const std::string& out_dir, int frame_index, bool right) {
  return JoinPath(right ? JoinPath(out_dir, "right") : out_dir, FrameFileName(frame_index, ".png"));
}

LabelProducer::LabelProducer(const StereoCamera& camera, const LabelProducerOptions& options, std::string out_dir,
                             LabelSink sink, StereoPairLoader loader, LabelSink right_sink)
    : camera_(camera),
      options_(options),
      out_dir_(std::move(out_dir)),
      sink_(std::move(sink)),
      loader_(std::move(loader)),
      right_sink_(std::move(right_sink)) {
  options_.Check();
  camera_.Check();
  EnsureDirectory(out_dir_);
  if (options_.right_labels) EnsureDirectory(JoinPath(out_dir_, "right"));
  if (options_.worker_thread) worker_ = std::thread([this] { WorkerLoop(); });
}

LabelProducer::~LabelProducer() {
  if (!worker_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void LabelProducer::RethrowWorkerError() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

void LabelProducer::Submit(LabelJob job) {
  if (!worker_.joinable()) {
    Produce(job);
    return;
  }
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return error_ || static_cast<int>(queue_.size()) < options_.max_queue; });
  if (error_) std::rethrow_exception(error_);
  queue_.push_back(std::move(job));
  lock.unlock();
  changed_.notify_all();
}

void LabelProducer::Finish() {
  if (worker_.joinable()) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return error_ || (queue_.empty() && !busy_); });
  }
  RethrowWorkerError();
}

void LabelProducer::WorkerLoop() {
  for (;;) {
    LabelJob job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty() || error_) return;  // stopped (or failed: the rest is not written)
      job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    std::exception_ptr error;
    try {
      Produce(job);
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      if (error) {
        error_ = error;
        queue_.clear();
      }
    }
    changed_.notify_all();
    if (error) return;
  }
}

cv::Mat LabelProducer::Render(const LabelJob& job, bool right, const cv::Mat& left_image, const cv::Mat& right_image) {
  cv::Mat labels(camera_.left.height, camera_.left.width, CV_32F, cv::Scalar(0));
  if (!job.has_pose) return labels;
  // The rectified right camera sits `baseline` along the left camera's +x axis.
  Eigen::Isometry3d T_world_camera = job.T_world_frame;
  if (right) T_world_camera.translate(Eigen::Vector3d(camera_.baseline, 0, 0));
  const int projected = RenderLabelMap(job.points, T_world_camera, camera_, options_.projection, &labels);
  (right ? counters_.right_projected : counters_.projected) += projected;
  if (!left_image.empty() && options_.stereo_check.enabled) {
    const auto check_start = std::chrono::steady_clock::now();
    if (right) {
      VerifyRightLabelsWithStereo(left_image, right_image, options_.stereo_check, &labels);
    } else {
      VerifyLabelsWithStereo(left_image, right_image, options_.stereo_check, &labels);
    }
    counters_.check_ms += MsSince(check_start);
  }
  (right ? counters_.right_verified : counters_.verified) += cv::countNonZero(labels);
  return labels;
}

void LabelProducer::WriteMap(const std::string& path, const cv::Mat& labels) {
  const auto start = std::chrono::steady_clock::now();
  if (options_.overwrite || !std::filesystem::exists(path)) WriteKittiMapPng(path, labels);
  counters_.write_ms += MsSince(start);
}

void LabelProducer::Produce(const LabelJob& job) {
  cv::Mat left_image, right_image;
  if (job.has_pose && loader_ && options_.stereo_check.enabled) loader_(job.frame_index, &left_image, &right_image);
  // After the loader: decoding a pair the cache no longer holds is image-read time (the reader counts it),
  // not label time, and the run's summary subtracts both from the wall time.
  const auto start = std::chrono::steady_clock::now();
  const cv::Mat labels = Render(job, false, left_image, right_image);
  cv::Mat right_labels;
  if (options_.right_labels) right_labels = Render(job, true, left_image, right_image);
  counters_.extract_ms += MsSince(start);
  WriteMap(LabelPath(out_dir_, job.frame_index), labels);
  if (options_.right_labels) WriteMap(LabelPath(out_dir_, job.frame_index, true), right_labels);
  ++counters_.frames;
  if (sink_) sink_(job.frame_index, labels);
  if (right_sink_ && options_.right_labels) right_sink_(job.frame_index, right_labels);
  ++frames_written_;
}

}  // namespace dvso::labels
